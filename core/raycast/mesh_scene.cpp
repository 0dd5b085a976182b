#include "raycast/mesh_scene.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "common/error.hpp"
#include "raycast/triangle_closest_point.hpp"

namespace posefuse::raycast {

void RenderImages::resize(int w, int h) {
  width = w;
  height = h;
  const size_t n = static_cast<size_t>(w) * h;
  depth_mm.assign(n, 0);
  body_index.assign(n, kNoBody);
  face.assign(n, -1);
  u.assign(n, 0.f);
  v.assign(n, 0.f);
  hit_col_begin = hit_col_end = hit_row_begin = hit_row_end = 0;
}

MeshScene::MeshScene(std::shared_ptr<EmbreeDevice> device, const Eigen::Matrix3Xi& faces, int num_vertices)
    : device_(std::move(device)), faces_(faces), num_vertices_(num_vertices) {
  if (!device_) throw_invalid("device", "is null");
  if (num_vertices < 3) throw_invalid("num_vertices", std::to_string(num_vertices) + " < 3");
  if (faces.cols() < 1) throw_invalid("faces", "no faces");
  if (faces.minCoeff() < 0 || faces.maxCoeff() >= num_vertices)
    throw_invalid("faces", "vertex index outside [0, " + std::to_string(num_vertices) + ")");
  scene_ = rtcNewScene(device_->handle());
  // ROBUST: watertight ray-triangle tests, so no ray slips through a shared edge.
  rtcSetSceneFlags(scene_, RTC_SCENE_FLAG_DYNAMIC | RTC_SCENE_FLAG_ROBUST);
  rtcSetSceneBuildQuality(scene_, RTC_BUILD_QUALITY_LOW);
  geometry_ = rtcNewGeometry(device_->handle(), RTC_GEOMETRY_TYPE_TRIANGLE);
  rtcSetGeometryBuildQuality(geometry_, RTC_BUILD_QUALITY_REFIT);
  vertex_buffer_ = static_cast<float*>(rtcSetNewGeometryBuffer(geometry_, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                               3 * sizeof(float), static_cast<size_t>(num_vertices)));
  auto* index = static_cast<unsigned*>(rtcSetNewGeometryBuffer(
      geometry_, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), static_cast<size_t>(faces.cols())));
  device_->check("geometry buffers");
  for (Eigen::Index f = 0; f < faces.cols(); ++f)
    for (int k = 0; k < 3; ++k) index[3 * f + k] = static_cast<unsigned>(faces(k, f));
  std::fill(vertex_buffer_, vertex_buffer_ + 3 * num_vertices, 0.f);
  rtcCommitGeometry(geometry_);
  rtcAttachGeometryByID(scene_, geometry_, 0);
  device_->check("scene");
}

MeshScene::~MeshScene() {
  rtcReleaseGeometry(geometry_);
  rtcReleaseScene(scene_);
}

void MeshScene::update_vertices(const Eigen::Matrix3Xd& vertices_K) {
  if (vertices_K.cols() != num_vertices_)
    throw_invalid("vertices_K",
                  std::to_string(vertices_K.cols()) + " vertices, scene has " + std::to_string(num_vertices_));
  if (!vertices_K.allFinite()) throw_invalid("vertices_K", "not finite");
  for (int i = 0; i < num_vertices_; ++i)
    for (int c = 0; c < 3; ++c) vertex_buffer_[3 * i + c] = static_cast<float>(vertices_K(c, i));
  box_min_ = vertices_K.rowwise().minCoeff();
  box_max_ = vertices_K.rowwise().maxCoeff();
  rtcUpdateGeometryBuffer(geometry_, RTC_BUFFER_TYPE_VERTEX, 0);
  rtcCommitGeometry(geometry_);
  rtcCommitScene(scene_);
  device_->check("commit");
  has_vertices_ = true;
}

void MeshScene::render(const DepthCamera& camera, uint8_t body_index, RenderImages& out) const {
  if (!has_vertices_) throw_precondition("vertices", "render before update_vertices");
  const int w = camera.width(), h = camera.height();
  out.resize(w, h);
  // Pixels whose z = 1 ray misses the projection of the bounding box cannot hit (exact: the
  // perspective image of a convex box in front of the camera is the hull of its corners).
  float ray_min_x = -std::numeric_limits<float>::infinity(), ray_max_x = -ray_min_x;
  float ray_min_y = ray_min_x, ray_max_y = ray_max_x;
  if (box_min_.z() > 1e-6) {
    ray_min_x = ray_min_y = std::numeric_limits<float>::infinity();
    ray_max_x = ray_max_y = -ray_min_x;
    for (int corner = 0; corner < 8; ++corner) {
      const Eigen::Vector3d p((corner & 1) ? box_max_.x() : box_min_.x(), (corner & 2) ? box_max_.y() : box_min_.y(),
                              (corner & 4) ? box_max_.z() : box_min_.z());
      const float x = static_cast<float>(p.x() / p.z()), y = static_cast<float>(p.y() / p.z());
      ray_min_x = std::min(ray_min_x, x);
      ray_max_x = std::max(ray_max_x, x);
      ray_min_y = std::min(ray_min_y, y);
      ray_max_y = std::max(ray_max_y, y);
    }
  }
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
  alignas(32) RTCRayHit8 packet;
  alignas(32) int valid[8];
  int pixel_of_lane[8];
  int lanes = 0;
  auto flush = [&]() {
    for (int l = lanes; l < 8; ++l) valid[l] = 0;
    rtcIntersect8(valid, scene_, &context, &packet);
    for (int l = 0; l < lanes; ++l) {
      if (packet.hit.geomID[l] == RTC_INVALID_GEOMETRY_ID) continue;
      const int pixel = pixel_of_lane[l];
      const double depth_mm = std::round(packet.ray.tfar[l] * 1000.0);  // rays have z = 1: t is z
      if (depth_mm > 65535.0) continue;
      out.depth_mm[pixel] = static_cast<uint16_t>(depth_mm);
      out.body_index[pixel] = body_index;
      out.face[pixel] = static_cast<int32_t>(packet.hit.primID[l]);
      out.u[pixel] = 1.f - packet.hit.u[l] - packet.hit.v[l];
      out.v[pixel] = packet.hit.u[l];
      const int row = pixel / w, col = pixel % w;
      if (out.hit_col_end == 0) {
        out.hit_col_begin = col;
        out.hit_row_begin = row;
      }
      out.hit_col_begin = std::min(out.hit_col_begin, col);
      out.hit_col_end = std::max(out.hit_col_end, col + 1);
      out.hit_row_begin = std::min(out.hit_row_begin, row);
      out.hit_row_end = std::max(out.hit_row_end, row + 1);
    }
    lanes = 0;
  };
  const auto [col_begin, col_end] = camera.columns_within(ray_min_x, ray_max_x);
  for (int row = 0; row < h; ++row) {
    if (!camera.row_within(row, ray_min_y, ray_max_y)) continue;
    for (int col = col_begin; col < col_end; ++col) {
      const Eigen::Vector3f& d = camera.pixel_ray(col, row);
      if (d.x() < ray_min_x || d.x() > ray_max_x || d.y() < ray_min_y || d.y() > ray_max_y) continue;
      packet.ray.org_x[lanes] = packet.ray.org_y[lanes] = packet.ray.org_z[lanes] = 0.f;
      packet.ray.dir_x[lanes] = d.x();
      packet.ray.dir_y[lanes] = d.y();
      packet.ray.dir_z[lanes] = d.z();
      packet.ray.tnear[lanes] = 0.f;
      packet.ray.tfar[lanes] = std::numeric_limits<float>::infinity();
      packet.ray.time[lanes] = 0.f;
      packet.ray.mask[lanes] = 0xFFFFFFFFu;
      packet.ray.id[lanes] = static_cast<unsigned>(lanes);
      packet.ray.flags[lanes] = 0;
      packet.hit.geomID[lanes] = RTC_INVALID_GEOMETRY_ID;
      packet.hit.instID[0][lanes] = RTC_INVALID_GEOMETRY_ID;
      valid[lanes] = -1;
      pixel_of_lane[lanes] = row * w + col;
      if (++lanes == 8) flush();
    }
  }
  if (lanes > 0) flush();
}

std::vector<bool> MeshScene::visible(const Eigen::Matrix3Xd& points_K, double tolerance_m) const {
  if (!has_vertices_) throw_precondition("vertices", "visibility query before update_vertices");
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  std::vector<bool> result(static_cast<size_t>(points_K.cols()), false);
  for (Eigen::Index i = 0; i < points_K.cols(); ++i) {
    const Eigen::Vector3d p = points_K.col(i);
    const double distance = p.norm();
    if (!p.allFinite() || distance <= tolerance_m) continue;
    RTCRay ray;
    ray.org_x = ray.org_y = ray.org_z = 0.f;
    ray.dir_x = static_cast<float>(p.x());
    ray.dir_y = static_cast<float>(p.y());
    ray.dir_z = static_cast<float>(p.z());
    ray.tnear = 0.f;
    ray.tfar = static_cast<float>(1.0 - tolerance_m / distance);  // t = 1 is the point itself
    ray.time = 0.f;
    ray.mask = 0xFFFFFFFFu;
    ray.id = 0;
    ray.flags = 0;
    rtcOccluded1(scene_, &context, &ray);
    result[static_cast<size_t>(i)] = ray.tfar >= 0.f;  // Embree sets tfar = -inf when occluded
  }
  return result;
}

void MeshScene::first_hits(const std::vector<Eigen::Vector3d>& through_K, std::vector<ClosestPoint>& hits) const {
  if (!has_vertices_) throw_precondition("vertices", "ray query before update_vertices");
  hits.assign(through_K.size(), ClosestPoint{});
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  for (size_t i = 0; i < through_K.size(); ++i) {
    const Eigen::Vector3d& p = through_K[i];
    const double length = p.norm();
    if (!p.allFinite() || length <= 0) continue;
    const Eigen::Vector3d direction = p / length;
    RTCRayHit rh;
    rh.ray.org_x = rh.ray.org_y = rh.ray.org_z = 0.f;
    rh.ray.dir_x = static_cast<float>(direction.x());
    rh.ray.dir_y = static_cast<float>(direction.y());
    rh.ray.dir_z = static_cast<float>(direction.z());
    rh.ray.tnear = 0.f;
    rh.ray.tfar = std::numeric_limits<float>::infinity();
    rh.ray.time = 0.f;
    rh.ray.mask = 0xFFFFFFFFu;
    rh.ray.id = 0;
    rh.ray.flags = 0;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(scene_, &context, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) continue;
    // Embree's (u, v) weight corners 1 and 2; ours weight corners 0 and 1 (see the header).
    hits[i] = {static_cast<int>(rh.hit.primID), 1.0 - rh.hit.u - rh.hit.v, rh.hit.u,
               static_cast<double>(rh.ray.tfar) * direction, static_cast<double>(rh.ray.tfar)};
  }
}

namespace {

struct ClosestPointSearch {
  const float* vertices;
  const Eigen::Matrix3Xi* faces;
  Eigen::Vector3d query;
  ClosestPoint best;
};

Eigen::Vector3d vertex_at(const float* buffer, int i) { return {buffer[3 * i], buffer[3 * i + 1], buffer[3 * i + 2]}; }

bool closest_point_callback(RTCPointQueryFunctionArguments* args) {
  auto* search = static_cast<ClosestPointSearch*>(args->userPtr);
  const int f = static_cast<int>(args->primID);
  const Eigen::Vector3i corners = search->faces->col(f);
  const Eigen::Vector3d a = vertex_at(search->vertices, corners[0]), b = vertex_at(search->vertices, corners[1]),
                        c = vertex_at(search->vertices, corners[2]);
  const Eigen::Vector3d w = closest_point_barycentric(search->query, a, b, c);
  const Eigen::Vector3d point = w[0] * a + w[1] * b + w[2] * c;
  const double distance = (point - search->query).norm();
  if (search->best.face >= 0 && distance >= search->best.distance) return false;
  search->best = {f, w[0], w[1], point, distance};
  args->query->radius = static_cast<float>(distance);
  return true;
}

}  // namespace

ClosestPoint MeshScene::closest_point(const Eigen::Vector3d& p_K) const {
  if (!has_vertices_) throw_precondition("vertices", "closest-point query before update_vertices");
  if (!p_K.allFinite()) throw_invalid("p_K", "not finite");
  ClosestPointSearch search{vertex_buffer_, &faces_, p_K, {}};
  RTCPointQuery query;
  query.x = static_cast<float>(p_K.x());
  query.y = static_cast<float>(p_K.y());
  query.z = static_cast<float>(p_K.z());
  query.time = 0.f;
  query.radius = std::numeric_limits<float>::infinity();
  RTCPointQueryContext context;
  rtcInitPointQueryContext(&context);
  rtcPointQuery(scene_, &query, &context, closest_point_callback, &search);
  if (search.best.face < 0) throw Error(ErrorCode::kInternal, "closest_point", "no face found");
  return search.best;
}

}  // namespace posefuse::raycast
