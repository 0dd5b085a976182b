#include "sim/depth_noise.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>

#include <Eigen/Geometry>

#include "common/error.hpp"
#include "geometry/rounding.hpp"
#include "raycast/mesh_scene.hpp"
#include "sim/option_checks.hpp"
#include "sim/sim_rng.hpp"
#include "sim/ziggurat_normal.hpp"

namespace posefuse::sim {
namespace {

using std::numbers::pi;
constexpr double kDegToRad = pi / 180.0;
// 4-neighbours in the order the error model visits them.
constexpr int kNeighbourDc[4] = {1, -1, 0, 0}, kNeighbourDr[4] = {0, 0, 1, -1};

// Decides whether two neighbouring depths (metres, both > 0) lie on one surface.
class EdgeTest {
 public:
  EdgeTest(const raycast::DepthCamera& camera, const DepthNoiseOptions& options)
      : min_jump_m_(options.edge_min_jump_m),
        slope_per_m_(std::tan(options.edge_slope_deg * kDegToRad) /
                     std::min(camera.intrinsics().fx, camera.intrinsics().fy)) {}
  bool continuous(double z_a, double z_b) const {
    return std::abs(z_a - z_b) <= std::max(min_jump_m_, std::min(z_a, z_b) * slope_per_m_);
  }

 private:
  double min_jump_m_;
  double slope_per_m_;
};

// The 4-neighbour across a depth edge whose depth differs most from (col, row)'s, in mm, or 0
// where there is none (the first of equal ones in the order +col, -col, +row, -row).
uint16_t flying_neighbour_of(const std::vector<uint16_t>& depth_mm, int width, int height, const EdgeTest& edges,
                             int col, int row) {
  const double z = depth_mm[static_cast<std::size_t>(row) * width + col] * 1e-3;
  uint16_t edge_mm = 0;
  double edge_jump = 0;
  for (int k = 0; k < 4; ++k) {
    const int c = col + kNeighbourDc[k], r = row + kNeighbourDr[k];
    if (c < 0 || r < 0 || c >= width || r >= height) continue;
    const uint16_t neighbour_mm = depth_mm[static_cast<std::size_t>(r) * width + c];
    const double zn = neighbour_mm * 1e-3;
    if (zn <= 0 || edges.continuous(z, zn)) continue;
    if (std::abs(zn - z) > edge_jump) {
      edge_jump = std::abs(zn - z);
      edge_mm = neighbour_mm;
    }
  }
  return edge_mm;
}

// 1 where a pixel's depth or a 4-neighbour's differs from the background's: the pixels whose
// incidence and flying-pixel neighbour must be computed afresh.
std::vector<uint8_t> stencil_changed(const std::vector<uint16_t>& depth_mm, const std::vector<uint16_t>& room_mm,
                                     int width, int height) {
  std::vector<uint8_t> changed(depth_mm.size(), 0);
  for (int row = 0; row < height; ++row) {
    for (int col = 0; col < width; ++col) {
      const std::size_t i = static_cast<std::size_t>(row) * width + col;
      if (depth_mm[i] == room_mm[i]) continue;
      changed[i] = 1;
      if (col > 0) changed[i - 1] = 1;
      if (col + 1 < width) changed[i + 1] = 1;
      if (row > 0) changed[i - static_cast<std::size_t>(width)] = 1;
      if (row + 1 < height) changed[i + static_cast<std::size_t>(width)] = 1;
    }
  }
  return changed;
}

void check_image_size(const raycast::DepthCamera& camera, std::size_t size, const std::string& field) {
  const std::size_t expected = static_cast<std::size_t>(camera.width()) * camera.height();
  if (size != expected) {
    throw_invalid(field, "has " + std::to_string(size) + " pixels, the camera " + std::to_string(expected));
  }
}

}  // namespace

void validate(const DepthNoiseOptions& options) {
  require_non_negative(options.axial_sigma_base_m, "axial_sigma_base_m");
  require_non_negative(options.axial_sigma_quadratic_per_m, "axial_sigma_quadratic_per_m");
  require_positive(options.max_incidence_deg, "max_incidence_deg");
  require_positive(options.edge_min_jump_m, "edge_min_jump_m");
  require_finite(options.edge_slope_deg, "edge_slope_deg");
  if (options.edge_slope_deg <= options.max_incidence_deg || options.edge_slope_deg >= 90.0) {
    throw_invalid("edge_slope_deg",
                  "must lie in (max_incidence_deg, 90), got " + std::to_string(options.edge_slope_deg));
  }
  require_probability(options.flying_pixel_probability, "flying_pixel_probability");
  require_positive(options.min_range_m, "min_range_m");
  require_interval(options.min_range_m, options.max_range_m, "max_range_m");
  if (options.max_range_m > 65.0) {
    throw_invalid("max_range_m", "must fit uint16 millimetres, got " + std::to_string(options.max_range_m));
  }
  if (options.max_edge_shift_px < 0 || options.max_edge_shift_px > 8) {
    throw_invalid("max_edge_shift_px", "must lie in [0, 8], got " + std::to_string(options.max_edge_shift_px));
  }
}

double axial_sigma_m(const DepthNoiseOptions& options, double z_m) {
  const double d = z_m - 0.4;
  return options.axial_sigma_base_m + options.axial_sigma_quadratic_per_m * d * d;
}

std::vector<RoomPlane> simple_room(double camera_height_m, double wall_distance_m) {
  require_positive(camera_height_m, "camera_height_m");
  require_positive(wall_distance_m, "wall_distance_m");
  return {RoomPlane{Eigen::Vector3d::UnitY(), -camera_height_m}, RoomPlane{Eigen::Vector3d::UnitZ(), wall_distance_m}};
}

void composite_room(const raycast::DepthCamera& camera, const std::vector<RoomPlane>& planes,
                    std::vector<uint16_t>& depth_mm) {
  check_image_size(camera, depth_mm.size(), "depth_mm");
  for (std::size_t i = 0; i < planes.size(); ++i) {
    const double norm = planes[i].normal_K.norm();
    if (!std::isfinite(norm) || std::abs(norm - 1.0) > 1e-6 || !std::isfinite(planes[i].offset_m)) {
      throw_invalid("planes[" + std::to_string(i) + "]", "needs a finite unit normal and offset");
    }
  }
  for (int row = 0; row < camera.height(); ++row) {
    for (int col = 0; col < camera.width(); ++col) {
      // The ray p = z * r (r with unit z) meets n . p = d at z = d / (n . r).
      const Eigen::Vector3d ray = camera.pixel_ray(col, row).cast<double>();
      double nearest_z = std::numeric_limits<double>::infinity();
      for (const RoomPlane& plane : planes) {
        const double n_dot_r = plane.normal_K.dot(ray);
        if (std::abs(n_dot_r) < 1e-12) continue;
        const double z = plane.offset_m / n_dot_r;
        if (z > 0) nearest_z = std::min(nearest_z, z);
      }
      const double z_mm = std::round(nearest_z * 1000.0);
      if (!(z_mm >= 1.0 && z_mm <= 65535.0)) continue;
      uint16_t& pixel = depth_mm[static_cast<std::size_t>(row) * camera.width() + col];
      if (pixel == 0 || pixel > z_mm) pixel = static_cast<uint16_t>(z_mm);
    }
  }
}

namespace {

// Cosine of the incidence angle per pixel (NaN where undefined); the noise model compares it
// with cos(max_incidence) rather than taking acos of every pixel (a third of its time).
class IncidenceCosines {
 public:
  IncidenceCosines(const raycast::DepthCamera& camera, const std::vector<uint16_t>& depth_mm,
                   const DepthNoiseOptions& options)
      : camera_(camera),
        depth_mm_(depth_mm),
        edges_(camera, options),
        width_(camera.width()),
        height_(camera.height()) {}

  // NaN where the pixel has no depth or no neighbour on its surface along a row or column.
  float at(int col, int row) const {
    if (z_at(col, row) <= 0) return std::numeric_limits<float>::quiet_NaN();
    const Eigen::Vector3d normal = difference(col, row, 1, 0).cross(difference(col, row, 0, 1));
    const double normal_norm = normal.norm();
    if (normal_norm <= 0) return std::numeric_limits<float>::quiet_NaN();
    const Eigen::Vector3d ray = camera_.pixel_ray(col, row).cast<double>();
    const double cos_incidence = std::abs(normal.dot(ray)) / (normal_norm * ray.norm());
    return static_cast<float>(std::min(1.0, cos_incidence));
  }

  std::vector<float> all() const {
    std::vector<float> out(depth_mm_.size());
    for (int row = 0; row < height_; ++row) {
      for (int col = 0; col < width_; ++col) out[static_cast<std::size_t>(row) * width_ + col] = at(col, row);
    }
    return out;
  }

  // The background's cached cosines, recomputed where `changed` (a stencil_changed mask) is set.
  std::vector<float> reusing(const StaticBackground& background, const std::vector<uint8_t>& changed) const {
    std::vector<float> out = background.incidence_cosines();
    for (int row = 0; row < height_; ++row) {
      for (int col = 0; col < width_; ++col) {
        const std::size_t i = static_cast<std::size_t>(row) * width_ + col;
        if (changed[i]) out[i] = at(col, row);
      }
    }
    return out;
  }

 private:
  double z_at(int col, int row) const { return depth_mm_[static_cast<std::size_t>(row) * width_ + col] * 1e-3; }
  Eigen::Vector3d point(int col, int row) const { return camera_.pixel_ray(col, row).cast<double>() * z_at(col, row); }
  bool usable(double z, int c, int r) const {
    if (c < 0 || r < 0 || c >= width_ || r >= height_) return false;
    const double zn = z_at(c, r);
    return zn > 0 && edges_.continuous(z, zn);
  }
  // Difference of points across (col, row) along (dc, dr): central where both neighbours are
  // on the surface, else one-sided; zero when neither is.
  Eigen::Vector3d difference(int col, int row, int dc, int dr) const {
    const double z = z_at(col, row);
    const bool ahead = usable(z, col + dc, row + dr), behind = usable(z, col - dc, row - dr);
    const Eigen::Vector3d a = ahead ? point(col + dc, row + dr) : point(col, row);
    const Eigen::Vector3d b = behind ? point(col - dc, row - dr) : point(col, row);
    return a - b;
  }

  const raycast::DepthCamera& camera_;
  const std::vector<uint16_t>& depth_mm_;
  EdgeTest edges_;
  int width_, height_;
};

}  // namespace

std::vector<float> incidence_angles_deg(const raycast::DepthCamera& camera, const std::vector<uint16_t>& depth_mm,
                                        const DepthNoiseOptions& options) {
  validate(options);
  check_image_size(camera, depth_mm.size(), "depth_mm");
  std::vector<float> angles = IncidenceCosines(camera, depth_mm, options).all();
  for (float& a : angles) {
    if (!std::isnan(a)) a = static_cast<float>(std::acos(static_cast<double>(a)) / kDegToRad);
  }
  return angles;
}

StaticBackground::StaticBackground(const raycast::DepthCamera& camera, const std::vector<RoomPlane>& planes,
                                   const DepthNoiseOptions& options)
    : depth_mm_(static_cast<std::size_t>(camera.width()) * camera.height(), 0), options_(options) {
  validate(options);
  composite_room(camera, planes, depth_mm_);
  incidence_cos_ = IncidenceCosines(camera, depth_mm_, options).all();
  const EdgeTest edges(camera, options);
  flying_neighbour_mm_.assign(depth_mm_.size(), 0);
  for (int row = 0; row < camera.height(); ++row) {
    for (int col = 0; col < camera.width(); ++col) {
      flying_neighbour_mm_[static_cast<std::size_t>(row) * camera.width() + col] =
          flying_neighbour_of(depth_mm_, camera.width(), camera.height(), edges, col, row);
    }
  }
}

void StaticBackground::composite(std::vector<uint16_t>& depth_mm) const {
  if (depth_mm.size() != depth_mm_.size()) {
    throw_invalid("depth_mm", "has " + std::to_string(depth_mm.size()) + " pixels, the background " +
                                  std::to_string(depth_mm_.size()));
  }
  for (std::size_t i = 0; i < depth_mm.size(); ++i) {
    if (depth_mm_[i] != 0 && (depth_mm[i] == 0 || depth_mm[i] > depth_mm_[i])) depth_mm[i] = depth_mm_[i];
  }
}

NoisyDepth apply_depth_noise(const raycast::DepthCamera& camera, const std::vector<uint16_t>& clean_depth_mm,
                             const std::vector<uint8_t>& clean_body_index, const DepthNoiseOptions& options,
                             std::uint64_t seed, std::int64_t frame_index, const StaticBackground* background) {
  validate(options);
  check_image_size(camera, clean_depth_mm.size(), "clean_depth_mm");
  check_image_size(camera, clean_body_index.size(), "clean_body_index");
  if (background) {
    check_image_size(camera, background->depth_mm().size(), "background");
    const DepthNoiseOptions& b = background->options();
    if (b.edge_min_jump_m != options.edge_min_jump_m || b.edge_slope_deg != options.edge_slope_deg) {
      throw_invalid("background", "was made with other edge options");
    }
  }
  const int width = camera.width(), height = camera.height();
  const std::size_t num_pixels = clean_depth_mm.size();
  SimRng rng(seed, "depth_noise/" + std::to_string(frame_index));
  const EdgeTest edges(camera, options);
  const IncidenceCosines incidence(camera, clean_depth_mm, options);
  // With a background, pixels whose stencil shows only the room take its cached incidence and
  // flying-pixel neighbour; everything else is computed here.
  const std::vector<uint8_t> changed = background
                                           ? stencil_changed(clean_depth_mm, background->depth_mm(), width, height)
                                           : std::vector<uint8_t>(num_pixels, 1);
  const std::vector<float> incidence_cos = background ? incidence.reusing(*background, changed) : incidence.all();
  const auto min_cos = static_cast<float>(std::cos(options.max_incidence_deg * kDegToRad));

  NoisyDepth out;
  out.depth_mm.assign(num_pixels, 0);
  for (int row = 0; row < height; ++row) {
    for (int col = 0; col < width; ++col) {
      const std::size_t i = static_cast<std::size_t>(row) * width + col;
      const uint16_t clean_mm = clean_depth_mm[i];
      if (clean_mm == 0) continue;
      // NaN: no neighbour on the same surface along a row or column (a sliver one pixel wide,
      // or a surface steeper than edge_slope_deg), which the sensor does not resolve either.
      if (!(incidence_cos[i] >= min_cos)) continue;
      double z = clean_mm * 1e-3;
      // Flying pixel: mix with the farthest-off neighbour across a depth edge.
      const uint16_t edge_mm = changed[i] ? flying_neighbour_of(clean_depth_mm, width, height, edges, col, row)
                                          : background->flying_neighbour_mm()[i];
      if (edge_mm != 0 && rng.uniform() < options.flying_pixel_probability) {
        const double t = rng.uniform();
        z = t * z + (1.0 - t) * (edge_mm * 1e-3);
      }
      z += axial_sigma_m(options, z) * ziggurat_normal(rng);
      if (z < options.min_range_m || z > options.max_range_m) continue;
      out.depth_mm[i] = static_cast<uint16_t>(geometry::round_half_up(z * 1000.0));
    }
  }

  // Body index: random erosion/dilation at each boundary pixel of the clean mask.
  out.body_index = clean_body_index;
  auto is_body = [&](int col, int row) {
    return clean_body_index[static_cast<std::size_t>(row) * width + col] != raycast::kNoBody;
  };
  for (int row = 0; row < height; ++row) {
    for (int col = 0; col < width; ++col) {
      if (!is_body(col, row)) continue;
      bool boundary = false;
      for (int k = 0; k < 4; ++k) {
        const int c = col + kNeighbourDc[k], r = row + kNeighbourDr[k];
        if (c >= 0 && r >= 0 && c < width && r < height && !is_body(c, r)) boundary = true;
      }
      if (!boundary) continue;
      const int span = 2 * options.max_edge_shift_px + 1;
      const int shift = std::min(span - 1, static_cast<int>(rng.uniform() * span)) - options.max_edge_shift_px;
      if (shift == 0) continue;
      // Dilation paints this body's index onto non-body pixels within `shift`; erosion clears
      // body pixels within |shift| - 1 (so a shift of -1 removes just the boundary pixel).
      const int radius = shift > 0 ? shift : -shift - 1;
      const uint8_t index = clean_body_index[static_cast<std::size_t>(row) * width + col];
      for (int r = std::max(0, row - radius); r <= std::min(height - 1, row + radius); ++r) {
        for (int c = std::max(0, col - radius); c <= std::min(width - 1, col + radius); ++c) {
          const std::size_t j = static_cast<std::size_t>(r) * width + c;
          if (shift > 0 && !is_body(c, r)) out.body_index[j] = index;
          if (shift < 0 && is_body(c, r)) out.body_index[j] = raycast::kNoBody;
        }
      }
    }
  }
  for (std::size_t i = 0; i < num_pixels; ++i) {
    if (out.depth_mm[i] == 0) out.body_index[i] = raycast::kNoBody;
  }
  return out;
}

}  // namespace posefuse::sim
