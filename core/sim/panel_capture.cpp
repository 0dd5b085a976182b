#include "sim/panel_capture.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "common/error.hpp"
#include "raycast/mesh_scene.hpp"
#include "sim/option_checks.hpp"
#include "sim/sensor_trajectory.hpp"
#include "sim/sim_rng.hpp"

namespace posefuse::sim {

namespace {

using std::numbers::pi;
constexpr double kDeg = pi / 180.0;
constexpr int kSupersampling = 3;                 // IR rays per pixel along each axis
constexpr double kRetroRadiance = 8.0 * 65535.0;  // markers: a 1/8 covered pixel saturates
constexpr double kBoardReflectivity = 0.6, kWallReflectivity = 0.5, kFloorReflectivity = 0.3;
constexpr double kShotCountsPerElectron = 4.0, kReadNoiseCounts = 20.0;
constexpr double kBoardThicknessM = 0.01;

// The panel as one triangle mesh in P: the board (a box behind the front face z = 0), then the
// four marker spheres (icospheres, two subdivisions). `marker_faces_begin` splits the faces.
struct PanelMesh {
  Eigen::Matrix3Xd vertices_P;
  Eigen::Matrix3Xi faces;
  int marker_faces_begin = 0;
};

void add_icosphere(const Vec3& centre, double radius, std::vector<Vec3>& vertices,
                   std::vector<Eigen::Vector3i>& faces) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Vec3> v = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                         {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  std::vector<Eigen::Vector3i> f = {{0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                                    {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                                    {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (Vec3& p : v) p.normalize();
  for (int level = 0; level < 2; ++level) {
    std::vector<Eigen::Vector3i> finer;
    for (const Eigen::Vector3i& tri : f) {
      int mid[3];
      for (int k = 0; k < 3; ++k) {
        v.push_back((v[static_cast<std::size_t>(tri[k])] + v[static_cast<std::size_t>(tri[(k + 1) % 3])]).normalized());
        mid[k] = static_cast<int>(v.size()) - 1;  // edges are split once per face: duplicates are harmless here
      }
      finer.push_back({tri[0], mid[0], mid[2]});
      finer.push_back({tri[1], mid[1], mid[0]});
      finer.push_back({tri[2], mid[2], mid[1]});
      finer.push_back({mid[0], mid[1], mid[2]});
    }
    f = finer;
  }
  const int offset = static_cast<int>(vertices.size());
  for (const Vec3& p : v) vertices.push_back(centre + radius * p);
  for (const Eigen::Vector3i& tri : f) faces.push_back(tri.array() + offset);
}

PanelMesh panel_mesh(const calib::PanelGeometry& panel) {
  std::vector<Vec3> v;
  std::vector<Eigen::Vector3i> f;
  const double x0 = panel.board_x_min_m, x1 = panel.board_x_max_m, y0 = panel.board_y_min_m, y1 = panel.board_y_max_m;
  for (const double z : {0.0, -kBoardThicknessM}) {
    v.push_back({x0, y0, z});
    v.push_back({x1, y0, z});
    v.push_back({x1, y1, z});
    v.push_back({x0, y1, z});
  }
  // Front, back, then the four sides (corners 0-3 front, 4-7 back).
  f = {{0, 1, 2}, {0, 2, 3}, {4, 6, 5}, {4, 7, 6}, {0, 4, 5}, {0, 5, 1},
       {1, 5, 6}, {1, 6, 2}, {2, 6, 7}, {2, 7, 3}, {3, 7, 4}, {3, 4, 0}};
  PanelMesh mesh;
  mesh.marker_faces_begin = static_cast<int>(f.size());
  for (const Vec3& m : panel.markers_P()) add_icosphere(m, panel.marker_radius_m, v, f);
  mesh.vertices_P.resize(3, static_cast<Eigen::Index>(v.size()));
  for (std::size_t i = 0; i < v.size(); ++i) mesh.vertices_P.col(static_cast<Eigen::Index>(i)) = v[i];
  mesh.faces.resize(3, static_cast<Eigen::Index>(f.size()));
  for (std::size_t i = 0; i < f.size(); ++i) mesh.faces.col(static_cast<Eigen::Index>(i)) = f[i];
  return mesh;
}

Quat random_turn(SimRng& rng, double sigma_rad) {
  return geometry::quat_from_rotation_vector(sigma_rad * Vec3(rng.normal(), rng.normal(), rng.normal()));
}

double uniform_in(SimRng& rng, double low, double high) { return low + (high - low) * rng.uniform(); }

std::vector<calib::PanelPose> random_poses(const PanelCaptureOptions& o, const calib::PanelGeometry& panel,
                                           std::uint64_t seed) {
  SimRng rng(seed, "panel_capture/poses");
  const Quat facing(Eigen::AngleAxisd(pi, Vec3::UnitY()));  // z_P towards the camera, y_P up
  const Vec3 board_centre_P(0.5 * (panel.board_x_min_m + panel.board_x_max_m),
                            0.5 * (panel.board_y_min_m + panel.board_y_max_m), 0.0);
  std::vector<calib::PanelPose> out;
  for (int i = 0; i < o.poses; ++i) {
    const Vec3 turn(uniform_in(rng, -1, 1) * o.max_tilt_deg * kDeg, uniform_in(rng, -1, 1) * o.max_tilt_deg * kDeg,
                    uniform_in(rng, -1, 1) * o.max_roll_deg * kDeg);
    calib::PanelPose pose;
    pose.X_from_P = (geometry::quat_from_rotation_vector(Vec3(turn.x(), turn.y(), 0.0)) * facing *
                     geometry::quat_from_rotation_vector(Vec3(0.0, 0.0, turn.z())))
                        .normalized();
    const Vec3 centre_K(uniform_in(rng, -0.15, 0.15), uniform_in(rng, -0.1, 0.1),
                        uniform_in(rng, o.distance_min_m, o.distance_max_m));
    pose.origin_X = centre_K - pose.X_from_P * board_centre_P;
    out.push_back(pose);
  }
  return out;
}

// IR radiance of the nearest room plane along a ray through the camera centre (0 if none).
double room_radiance(const std::vector<RoomPlane>& room, const Vec3& ray, double gain) {
  double best = INFINITY, out = 0.0;
  for (const RoomPlane& plane : room) {
    const double along = plane.normal_K.dot(ray);
    if (std::abs(along) <= 1e-9) continue;
    const double t = plane.offset_m / along;  // the hit is t * ray
    if (t > 0 && t < best) {
      best = t;
      const double reflectivity = plane.normal_K.z() > 0.5 ? kWallReflectivity : kFloorReflectivity;
      out = gain * reflectivity * (std::abs(along) / ray.norm()) / (t * t * ray.squaredNorm());
    }
  }
  return out;
}

// The camera whose pixel centres are the IR sub-rays: kSupersampling^2 per pixel of `intrinsics`,
// at col + (a - (s - 1) / 2) / s.
raycast::DepthIntrinsics supersampled(const raycast::DepthIntrinsics& intrinsics) {
  raycast::DepthIntrinsics fine = intrinsics;
  const int s = kSupersampling;
  fine.width *= s;
  fine.height *= s;
  fine.fx *= s;
  fine.fy *= s;
  fine.cx = s * intrinsics.cx + 0.5 * (s - 1);
  fine.cy = s * intrinsics.cy + 0.5 * (s - 1);
  return fine;
}

// IR counts before noise: the mean radiance over the sub-rays of each pixel (`camera` from
// supersampled(intrinsics)).
std::vector<double> render_ir_radiance(const raycast::DepthIntrinsics& intrinsics, const raycast::DepthCamera& camera,
                                       const raycast::MeshScene& scene, const PanelMesh& mesh,
                                       const Eigen::Matrix3Xd& vertices_K, const std::vector<RoomPlane>& room,
                                       double gain) {
  const int s = kSupersampling;
  const raycast::DepthIntrinsics& fine = camera.intrinsics();
  raycast::RenderImages hits;
  scene.render(camera, 0, hits);
  std::vector<double> radiance(static_cast<std::size_t>(intrinsics.width) * static_cast<std::size_t>(intrinsics.height),
                               0.0);
  for (int row = 0; row < fine.height; ++row) {
    for (int col = 0; col < fine.width; ++col) {
      const std::size_t i =
          static_cast<std::size_t>(row) * static_cast<std::size_t>(fine.width) + static_cast<std::size_t>(col);
      const Vec3 ray = camera.pixel_ray(col, row).cast<double>();  // z = 1
      const int face = hits.face[i];
      double value = 0.0;
      if (face >= mesh.marker_faces_begin) {
        value = kRetroRadiance;
      } else if (face >= 0) {
        const Vec3 a = vertices_K.col(mesh.faces(0, face)), b = vertices_K.col(mesh.faces(1, face)),
                   c = vertices_K.col(mesh.faces(2, face));
        const double cosine = std::abs((b - a).cross(c - a).normalized().dot(ray.normalized()));
        const double range_sq = std::pow(hits.depth_mm[i] * 1e-3, 2) * ray.squaredNorm();
        value = gain * kBoardReflectivity * cosine / range_sq;
      } else {
        value = room_radiance(room, ray, gain);
      }
      radiance[static_cast<std::size_t>(row / s) * static_cast<std::size_t>(intrinsics.width) +
               static_cast<std::size_t>(col / s)] += value / (s * s);
    }
  }
  return radiance;
}

std::vector<imu::ImuSample> still_imu(const Quat& W_from_A, const Vec3& p_W, double t0_s, double hold_s, double rate_hz,
                                      ImuSynthOptions options) {
  SensorTrajectory still;
  still.dt_s = 0.01;
  still.t0_s = t0_s - 0.05;
  const auto n = static_cast<std::size_t>(std::ceil((hold_s + 0.1) / still.dt_s)) + 1;
  still.p_W_m.assign(n, p_W);
  still.W_from_A.assign(n, W_from_A);
  options.nominal_rate_hz = rate_hz;
  return synthesize_imu(SensorKinematics(std::move(still)), uniform_times(t0_s, t0_s + hold_s, rate_hz), options)
      .samples;
}

}  // namespace

void validate(const PanelCaptureOptions& o) {
  if (o.poses_K.empty() && (o.poses < 1 || o.poses > 20)) {
    throw_invalid("panel_capture.poses", "is " + std::to_string(o.poses) + ", must be 1..20");
  }
  require_positive(o.distance_min_m, "panel_capture.distance_min_m");
  if (!(o.distance_max_m >= o.distance_min_m) || !std::isfinite(o.distance_max_m)) {
    throw_invalid("panel_capture.distance_max_m", "must be finite and >= distance_min_m");
  }
  require_non_negative(o.max_tilt_deg, "panel_capture.max_tilt_deg");
  if (o.max_tilt_deg > 60.0)
    throw_invalid("panel_capture.max_tilt_deg", "must be at most 60 (the panel must face the camera)");
  require_non_negative(o.max_roll_deg, "panel_capture.max_roll_deg");
  require_non_negative(o.marker_noise_m, "panel_capture.marker_noise_m");
  require_non_negative(o.imu_misalignment_deg, "panel_capture.imu_misalignment_deg");
  require_positive(o.hold_s, "panel_capture.hold_s");
  require_positive(o.ir_gain, "panel_capture.ir_gain");
  for (std::size_t i = 0; i < o.poses_K.size(); ++i) {
    if (!o.poses_K[i].origin_X.allFinite() || std::abs(o.poses_K[i].X_from_P.norm() - 1.0) > 1e-6) {
      throw_invalid("panel_capture.poses_K[" + std::to_string(i) + "]", "not a finite pose with a unit quaternion");
    }
  }
}

geometry::PinholeCamera pinhole_of(const raycast::DepthIntrinsics& c) {
  return {c.width, c.height, c.fx, c.fy, c.cx, c.cy, c.k1, c.k2, c.k3, 0.0, 0.0};
}

PanelCaptureResult simulate_panel_capture(const PanelCaptureOptions& o, const PanelCaptureRig& rig) {
  validate(o);
  raycast::validate(rig.depth_intrinsics);
  validate(rig.depth_noise);
  require_positive(rig.imu_rate_hz, "imu_rate_hz");
  PanelCaptureResult out;
  calib::CalibrationCapture& capture = out.capture;
  PanelCaptureTruth& truth = out.truth;
  capture.camera = pinhole_of(rig.depth_intrinsics);
  truth.K_from_B = rig.K_from_B;
  truth.K_from_W = rig.K_from_W;
  truth.marker_noise_m = o.marker_noise_m;
  truth.K_from_P = o.poses_K.empty() ? random_poses(o, capture.panel, rig.seed) : o.poses_K;

  // The mocap frame E: z up like W, turned about it, origin on the floor in front of the camera.
  SimRng mocap_rng(rig.seed, "panel_capture/mocap");
  const Quat W_from_E(Eigen::AngleAxisd(2 * pi * mocap_rng.uniform(), Vec3::UnitZ()));
  truth.K_from_E = (rig.K_from_W * W_from_E).normalized();
  truth.E_origin_K = Vec3(uniform_in(mocap_rng, -1, 1), -rig.camera_height_m, uniform_in(mocap_rng, 2.0, 3.0));

  // IMUs: calibrated magnetometers (II-C), the rest of the cheap-IMU error model.
  ImuSynthOptions imu = rig.imu;
  imu.error_model.hard_iron_sigma_uT = 0.0;
  imu.error_model.soft_iron_diagonal_sigma = 0.0;
  imu.error_model.soft_iron_off_diagonal_sigma = 0.0;
  imu.disturbances.clear();
  SimRng imu_rng(rig.seed, "panel_capture/imu");
  truth.P_from_panel_imu = random_turn(imu_rng, o.imu_misalignment_deg * kDeg);
  truth.panel_imu_errors = draw_imu_errors(imu.error_model, static_cast<std::uint64_t>(imu_rng.uniform() * 0x1.0p53));
  truth.base_imu_errors = draw_imu_errors(imu.error_model, static_cast<std::uint64_t>(imu_rng.uniform() * 0x1.0p53));
  const Quat W_from_K = rig.K_from_W.conjugate();
  const Quat W_from_B = (W_from_K * rig.K_from_B).normalized();

  const raycast::DepthCamera camera(rig.depth_intrinsics), ir_camera(supersampled(rig.depth_intrinsics));
  const PanelMesh mesh = panel_mesh(capture.panel);
  raycast::MeshScene scene(raycast::EmbreeDevice::shared(), mesh.faces, static_cast<int>(mesh.vertices_P.cols()));
  const std::vector<RoomPlane> room = simple_room(rig.camera_height_m, rig.wall_distance_m);
  const std::size_t pixels = static_cast<std::size_t>(camera.width()) * static_cast<std::size_t>(camera.height());
  raycast::RenderImages images;
  for (std::size_t i = 0; i < truth.K_from_P.size(); ++i) {
    const calib::PanelPose& pose = truth.K_from_P[i];
    calib::CapturePose& seen = capture.poses.emplace_back();
    Eigen::Matrix3Xd vertices_K = (pose.X_from_P.toRotationMatrix() * mesh.vertices_P).colwise() + pose.origin_X;
    scene.update_vertices(vertices_K);

    // (b) IR, then depth with the sensor's errors; saturated pixels return no depth.
    const std::vector<double> radiance =
        render_ir_radiance(rig.depth_intrinsics, ir_camera, scene, mesh, vertices_K, room, o.ir_gain);
    SimRng ir_rng(rig.seed, "panel_capture/ir/" + std::to_string(i));
    seen.ir.resize(pixels);
    for (std::size_t p = 0; p < pixels; ++p) {
      const double clean = std::min(radiance[p], 65535.0);
      const double sigma = std::sqrt(kShotCountsPerElectron * clean + kReadNoiseCounts * kReadNoiseCounts);
      seen.ir[p] = static_cast<std::uint16_t>(std::lround(std::clamp(clean + sigma * ir_rng.normal(), 0.0, 65535.0)));
      if (radiance[p] >= 65535.0) seen.ir[p] = 65535;  // saturation is not noisy
    }
    scene.render(camera, 0, images);
    composite_room(camera, room, images.depth_mm);
    const std::vector<std::uint8_t> no_body(pixels, raycast::kNoBody);
    seen.depth_mm = apply_depth_noise(camera, images.depth_mm, no_body, rig.depth_noise, rig.seed ^ 0x9a4e1c0fULL,
                                      static_cast<std::int64_t>(i))
                        .depth_mm;
    for (std::size_t p = 0; p < pixels; ++p) {
      if (radiance[p] >= 65535.0) seen.depth_mm[p] = 0;
    }

    // (a) mocap markers in E.
    SimRng marker_rng(rig.seed, "panel_capture/markers/" + std::to_string(i));
    const std::array<Vec3, 4> markers_P = capture.panel.markers_P();
    for (std::size_t m = 0; m < 4; ++m) {
      const Vec3 noise(marker_rng.normal(), marker_rng.normal(), marker_rng.normal());
      seen.markers_E[m] =
          truth.K_from_E.conjugate() * (pose.to_X(markers_P[m]) - truth.E_origin_K) + o.marker_noise_m * noise;
    }

    // (c) the still hold: the panel IMU and the base IMU (positions do not matter when still).
    const double t0 = static_cast<double>(i) * (o.hold_s + 2.0);
    const Quat W_from_panel_imu = (W_from_K * pose.X_from_P * truth.P_from_panel_imu).normalized();
    ImuSynthOptions panel_imu = imu, base_imu = imu;
    panel_imu.errors = truth.panel_imu_errors;
    base_imu.errors = truth.base_imu_errors;
    panel_imu.seed = rig.seed * 1000 + 2 * i;
    base_imu.seed = rig.seed * 1000 + 2 * i + 1;
    seen.panel_imu = still_imu(W_from_panel_imu, Vec3::Zero(), t0, o.hold_s, rig.imu_rate_hz, panel_imu);
    seen.base_imu = still_imu(W_from_B, Vec3::Zero(), t0, o.hold_s, rig.imu_rate_hz, base_imu);
  }
  return out;
}

}  // namespace posefuse::sim
