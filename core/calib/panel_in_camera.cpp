#include "calib/panel_in_camera.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <Eigen/SVD>

#include "common/error.hpp"
#include "geometry/point_pca.hpp"
#include "geometry/rotation_matrix.hpp"

namespace posefuse::calib {

namespace {

std::string mm(double m) { return std::to_string(m * 1e3) + " mm"; }

// Intensity-weighted centroids of the bright blobs (4-connected).
std::vector<Vec2> bright_points(const IrImageView& ir, const PanelCameraOptions& o) {
  const std::size_t n = static_cast<std::size_t>(ir.width) * static_cast<std::size_t>(ir.height);
  const std::uint16_t peak = *std::max_element(ir.pixels, ir.pixels + n);
  const double threshold = std::max(1.0, o.bright_fraction * peak);
  std::vector<char> seen(n, 0);
  std::vector<Vec2> points;
  std::vector<std::size_t> stack;
  for (std::size_t start = 0; start < n; ++start) {
    if (seen[start] || ir.pixels[start] < threshold) continue;
    seen[start] = 1;
    stack.assign(1, start);
    double weight = 0.0, su = 0.0, sv = 0.0;
    int count = 0;
    while (!stack.empty()) {
      const std::size_t i = stack.back();
      stack.pop_back();
      const int col = static_cast<int>(i % static_cast<std::size_t>(ir.width));
      const int row = static_cast<int>(i / static_cast<std::size_t>(ir.width));
      const double w = ir.pixels[i];
      weight += w;
      su += w * col;
      sv += w * row;
      ++count;
      const int neighbours[4][2] = {{col - 1, row}, {col + 1, row}, {col, row - 1}, {col, row + 1}};
      for (const auto& nb : neighbours) {
        if (nb[0] < 0 || nb[1] < 0 || nb[0] >= ir.width || nb[1] >= ir.height) continue;
        const std::size_t j =
            static_cast<std::size_t>(nb[1]) * static_cast<std::size_t>(ir.width) + static_cast<std::size_t>(nb[0]);
        if (!seen[j] && ir.pixels[j] >= threshold) {
          seen[j] = 1;
          stack.push_back(j);
        }
      }
    }
    if (count >= o.min_blob_pixels && count <= o.max_blob_pixels) points.emplace_back(su / weight, sv / weight);
  }
  return points;
}

// M0..M3 from four unlabelled points (see the header, step 2).
std::array<Vec2, 4> label_markers(const std::vector<Vec2>& p) {
  double best_ratio = INFINITY;
  std::array<int, 3> best{0, 1, 2};
  int fourth = 3;
  for (int skip = 0; skip < 4; ++skip) {
    std::array<int, 3> t{};
    int k = 0;
    for (int i = 0; i < 4; ++i) {
      if (i != skip) t[static_cast<std::size_t>(k++)] = i;
    }
    const Vec2 a = p[static_cast<std::size_t>(t[0])], b = p[static_cast<std::size_t>(t[1])],
               c = p[static_cast<std::size_t>(t[2])];
    const double area2 = std::abs((b - a).x() * (c - a).y() - (b - a).y() * (c - a).x());
    const double longest = std::max({(b - a).norm(), (c - a).norm(), (c - b).norm()});
    const double ratio = area2 / (longest * longest);  // 0 for collinear points
    if (ratio < best_ratio) {
      best_ratio = ratio;
      best = t;
      fourth = skip;
    }
  }
  if (!(best_ratio < 0.05)) {
    throw_precondition("ir.markers", "no three bright points are collinear: not the panel's L");
  }
  const Vec2 m3 = p[static_cast<std::size_t>(fourth)];
  // The middle of the triple lies between the other two: the smallest sum of distances.
  std::array<Vec2, 3> t{p[static_cast<std::size_t>(best[0])], p[static_cast<std::size_t>(best[1])],
                        p[static_cast<std::size_t>(best[2])]};
  std::array<double, 3> spread{};
  for (std::size_t i = 0; i < 3; ++i) spread[i] = (t[i] - t[0]).norm() + (t[i] - t[1]).norm() + (t[i] - t[2]).norm();
  const std::size_t middle = static_cast<std::size_t>(std::min_element(spread.begin(), spread.end()) - spread.begin());
  std::swap(t[0], t[middle]);
  const Vec2 m1 = t[0];
  const bool first_is_corner = (t[1] - m3).norm() < (t[2] - m3).norm();
  return {first_is_corner ? t[1] : t[2], m1, first_is_corner ? t[2] : t[1], m3};
}

void check_inputs(const IrImageView& ir, const DepthView& depth, const PinholeCamera& camera) {
  geometry::validate(camera, "camera");
  if (!ir.pixels || ir.width != camera.width || ir.height != camera.height) {
    throw_invalid("ir.pixels",
                  "missing or not the camera's " + std::to_string(camera.width) + "x" + std::to_string(camera.height));
  }
  if (!depth.pixels || depth.width != camera.width || depth.height != camera.height) {
    throw_invalid("depth.pixels",
                  "missing or not the camera's " + std::to_string(camera.width) + "x" + std::to_string(camera.height));
  }
}

// A line's point nearest another line: closest points c1 + s d1 and c2 + t d2 (unit d).
void closest_points(const Vec3& c1, const Vec3& d1, const Vec3& c2, const Vec3& d2, Vec3* p1, Vec3* p2) {
  const Vec3 r = c1 - c2;
  const double b = d1.dot(d2), d = d1.dot(r), e = d2.dot(r), denom = 1.0 - b * b;
  const double s = denom > 1e-9 ? (b * e - d) / denom : 0.0;
  const double t = denom > 1e-9 ? (e - b * d) / denom : e;
  *p1 = c1 + s * d1;
  *p2 = c2 + t * d2;
}

// Steps 4-5 on one set of point groups: axes by PCA, orthonormalised, and the origin; fills
// out.pose and the residuals, throws on bad geometry.
void fit_groups(const std::vector<Vec3>& x_group, const std::vector<Vec3>& y_group, const std::vector<Vec3>& board,
                PanelInCamera& out, const PinholeCamera& camera, const PanelCameraOptions& o) {
  out.x_points = static_cast<int>(x_group.size());
  out.y_points = static_cast<int>(y_group.size());
  out.board_points = static_cast<int>(board.size());
  const auto require_points = [&](const std::vector<Vec3>& group, const char* field) {
    if (static_cast<int>(group.size()) < o.min_group_points) {
      throw_precondition(field, std::to_string(group.size()) + " depth points, need " +
                                    std::to_string(o.min_group_points) + " (panel too far, too oblique or not read)");
    }
  };
  require_points(x_group, "depth.x_strip");
  require_points(y_group, "depth.y_strip");
  require_points(board, "depth.board");
  const geometry::PointPca x_pca = geometry::point_pca(x_group), y_pca = geometry::point_pca(y_group),
                           board_pca = geometry::point_pca(board);
  out.x_elongation = std::sqrt(x_pca.variances(2) / std::max(x_pca.variances(1), 1e-18));
  out.y_elongation = std::sqrt(y_pca.variances(2) / std::max(y_pca.variances(1), 1e-18));
  out.board_rms_m = std::sqrt(board_pca.variances(0));
  if (out.x_elongation < o.min_strip_elongation) {
    throw_precondition("depth.x_strip", "not a strip: elongation " + std::to_string(out.x_elongation));
  }
  if (out.y_elongation < o.min_strip_elongation) {
    throw_precondition("depth.y_strip", "not a strip: elongation " + std::to_string(out.y_elongation));
  }
  if (out.board_rms_m > o.max_plane_rms_m) {
    throw_precondition("depth.board", "not flat: " + mm(out.board_rms_m) + " RMS from its plane (limit " +
                                          mm(o.max_plane_rms_m) + ")");
  }
  // Signs from the markers: M0, M2, M3 back-projected onto the board plane.
  const auto on_board = [&](const Vec2& px) {
    const Vec3 ray = geometry::back_project(camera, px.x(), px.y(), 1.0);
    return Vec3(ray * (board_pca.normal().dot(board_pca.centroid) / board_pca.normal().dot(ray)));
  };
  const Vec3 m0 = on_board(out.marker_px[0]), m2 = on_board(out.marker_px[2]), m3 = on_board(out.marker_px[3]);
  Vec3 x = x_pca.direction(), y = y_pca.direction(), z = board_pca.normal();
  if (x.dot(m2 - m0) < 0) x = -x;
  if (y.dot(m3 - m0) < 0) y = -y;
  if (z.dot(x.cross(y)) < 0) z = -z;
  if (z.dot(-board_pca.centroid) <= 0.0) {
    throw_precondition("panel.axes", "the panel's front face points away from the camera (mirrored labels?)");
  }
  out.axis_skew_rad = std::max({std::abs(std::asin(std::clamp(x.dot(y), -1.0, 1.0))),
                                std::abs(std::asin(std::clamp(x.dot(z), -1.0, 1.0))),
                                std::abs(std::asin(std::clamp(y.dot(z), -1.0, 1.0)))});
  if (out.axis_skew_rad > o.max_axis_skew_rad) {
    throw_precondition("panel.axes", "the measured axes are " + std::to_string(out.axis_skew_rad * 180 / EIGEN_PI) +
                                         " degrees from orthogonal (limit " +
                                         std::to_string(o.max_axis_skew_rad * 180 / EIGEN_PI) + ")");
  }
  Eigen::Matrix3d axes;
  axes << x, y, z;
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(axes, Eigen::ComputeFullU | Eigen::ComputeFullV);
  out.pose.X_from_P = geometry::quat_from_rotation_matrix(svd.matrixU() * svd.matrixV().transpose());
  // The virtual intersection of the two lines (on the panel surface).
  Vec3 on_x, on_y;
  closest_points(x_pca.centroid, x_pca.direction(), y_pca.centroid, y_pca.direction(), &on_x, &on_y);
  out.intersection_gap_m = (on_x - on_y).norm();
  if (out.intersection_gap_m > o.max_intersection_gap_m) {
    throw_precondition("panel.origin", "the X and Y lines pass " + mm(out.intersection_gap_m) + " apart (limit " +
                                           mm(o.max_intersection_gap_m) + ")");
  }
  out.pose.origin_X = 0.5 * (on_x + on_y);
}

// The panel placed by its four markers: each bright point's ray meets the plane of the first
// fit raised by the marker height; the model markers are fitted to those points (Kabsch). This
// places the regions exactly where the markers say, without the affine map's perspective error.
PanelPose markers_on_plane(const PanelInCamera& first, const PinholeCamera& camera, const PanelGeometry& panel) {
  const Vec3 normal = first.pose.X_from_P * Vec3::UnitZ();  // towards the camera
  const double offset = normal.dot(first.pose.origin_X) + panel.marker_height_m;
  std::array<Vec3, 4> markers_K{};
  for (std::size_t i = 0; i < 4; ++i) {
    const Vec3 ray = geometry::back_project(camera, first.marker_px[i].x(), first.marker_px[i].y(), 1.0);
    markers_K[i] = ray * (offset / normal.dot(ray));
  }
  try {
    return panel_pose_from_markers(markers_K, panel, nullptr, 0.01);
  } catch (const Error& error) {
    throw_precondition("ir.markers", std::string("the bright points do not form the panel's L: ") + error.what());
  }
}

}  // namespace

PanelInCamera panel_in_camera(const IrImageView& ir, const DepthView& depth, const PinholeCamera& camera,
                              const PanelGeometry& panel, const PanelCameraOptions& o) {
  check_inputs(ir, depth, camera);
  validate(panel);
  PanelInCamera out;

  // 1-2. Markers.
  const std::vector<Vec2> points = bright_points(ir, o);
  if (points.size() != 4) {
    throw_precondition("ir", "found " + std::to_string(points.size()) +
                                 " bright points, expected the panel's 4 markers (covered, out of view, or glare?)");
  }
  out.marker_px = label_markers(points);

  // 3. Affine map panel plane -> image from the four markers, and its inverse.
  const std::array<Vec3, 4> model = panel.markers_P();
  Eigen::Matrix<double, 8, 6> A = Eigen::Matrix<double, 8, 6>::Zero();
  Eigen::Matrix<double, 8, 1> b;
  for (int i = 0; i < 4; ++i) {
    const Vec3& m = model[static_cast<std::size_t>(i)];
    A.row(2 * i) << m.x(), m.y(), 1, 0, 0, 0;
    A.row(2 * i + 1) << 0, 0, 0, m.x(), m.y(), 1;
    b(2 * i) = out.marker_px[static_cast<std::size_t>(i)].x();
    b(2 * i + 1) = out.marker_px[static_cast<std::size_t>(i)].y();
  }
  const Eigen::Matrix<double, 6, 1> a = A.colPivHouseholderQr().solve(b);
  Eigen::Matrix2d linear;
  linear << a(0), a(1), a(3), a(4);
  if (std::abs(linear.determinant()) < 1e-6)
    throw_precondition("ir.markers", "the markers' L is degenerate in the image");
  const Eigen::Matrix2d inverse = linear.inverse();
  const Vec2 offset(a(2), a(5));

  // 3-5 twice: regions from the affine map (the plane from the strips alone), then again from
  // the first pose (exact perspective; points off the board plane drop out).
  const double margin = o.region_margin_m, w = panel.strip_half_width_m;
  const double clearance = o.marker_clearance * panel.marker_radius_m;
  PanelPose regions_pose;  // pass 1: the panel placed by its markers on the first plane
  for (int pass = 0; pass < 2; ++pass) {
    if (pass == 1) regions_pose = markers_on_plane(out, camera, panel);
    const Quat P_from_K = regions_pose.X_from_P.conjugate();
    std::vector<Vec3> x_group, y_group, board;
    for (int row = 0; row < depth.height; ++row) {
      for (int col = 0; col < depth.width; ++col) {
        const std::uint16_t z = depth.pixels[static_cast<std::size_t>(row) * static_cast<std::size_t>(depth.width) +
                                             static_cast<std::size_t>(col)];
        if (z == 0) continue;
        const Vec3 p = geometry::back_project(camera, col, row, z * 1e-3);
        Vec2 xy;  // in P
        if (pass == 0) {
          xy = inverse * (Vec2(col, row) - offset);
        } else {
          const Vec3 p_P = P_from_K * (p - regions_pose.origin_X);
          if (std::abs(p_P.z()) > 5.0 * o.max_plane_rms_m) continue;
          xy = p_P.head<2>();
        }
        const bool near_marker = std::any_of(model.begin(), model.end(),
                                             [&](const Vec3& m) { return (xy - m.head<2>()).norm() < clearance; });
        const bool on_board = xy.x() > panel.board_x_min_m + margin && xy.x() < panel.board_x_max_m - margin &&
                              xy.y() > panel.board_y_min_m + margin && xy.y() < panel.board_y_max_m - margin;
        if (near_marker || !on_board) continue;
        const bool in_x = std::abs(xy.y()) < w - margin / 2 && xy.x() > -w && xy.x() < panel.long_leg_m;
        const bool in_y = std::abs(xy.x()) < w - margin / 2 && xy.y() > -w && xy.y() < panel.short_leg_m;
        if (in_x) x_group.push_back(p);
        if (in_y) y_group.push_back(p);
        // The first pass takes its plane from the strips only: near the board's edges the
        // affine map can still reach the background.
        if (pass == 1 || in_x || in_y) board.push_back(p);
      }
    }
    fit_groups(x_group, y_group, board, out, camera, o);
  }

  // Residual: the model markers placed by this pose, projected, against the bright points.
  double sum_sq = 0.0;
  for (std::size_t i = 0; i < 4; ++i) {
    const auto px = geometry::project(camera, out.pose.to_X(model[i]));
    sum_sq += px ? (*px - out.marker_px[i]).squaredNorm() : 1e12;
  }
  out.marker_residual_px = std::sqrt(sum_sq / 4.0);
  if (out.marker_residual_px > o.max_marker_residual_px) {
    throw_precondition("panel.markers",
                       "the panel pose reprojects its markers " + std::to_string(out.marker_residual_px) +
                           " px RMS from the bright points (limit " + std::to_string(o.max_marker_residual_px) + ")");
  }
  return out;
}

}  // namespace posefuse::calib
