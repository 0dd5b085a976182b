#include "sim/color_render.hpp"

#include <cmath>
#include <limits>
#include <opencv2/imgcodecs.hpp>

#include "common/error.hpp"
#include "geometry/rounding.hpp"
#include "sim/option_checks.hpp"
#include "sim/sim_rng.hpp"

namespace posefuse::sim {
namespace {

// Albedo per material, BGR in [0, 1].
const std::array<Eigen::Vector3d, 5> kAlbedo = {
    Eigen::Vector3d(0.45, 0.58, 0.80),  // skin
    Eigen::Vector3d(0.62, 0.32, 0.16),  // shirt (blue)
    Eigen::Vector3d(0.25, 0.22, 0.20),  // trousers
    Eigen::Vector3d(0.12, 0.12, 0.12),  // shoes
    Eigen::Vector3d(0.10, 0.14, 0.22),  // hair
};
const Eigen::Vector3d kStrapAlbedo(0.06, 0.06, 0.06);
const Eigen::Vector3d kFloorAlbedo(0.40, 0.47, 0.55);
const Eigen::Vector3d kWallAlbedo(0.80, 0.82, 0.84);
constexpr int kNoiseMargin = 64;  // px of the noise pool beyond the image on each side

}  // namespace

void validate(const ColorCameraOptions& options) {
  raycast::validate(options.intrinsics);
  if (!options.color_from_depth.matrix().allFinite()) throw_invalid("color.color_from_depth", "is not finite");
  require_non_negative(options.noise_sigma, "color.noise_sigma");
  if (options.jpeg_quality < 1 || options.jpeg_quality > 100) {
    throw_invalid("color.jpeg_quality", "is " + std::to_string(options.jpeg_quality) + ", must be 1..100");
  }
  require_positive(options.strap_width_m, "color.strap_width_m");
}

bool is_strap(const RenderModel& model, const StrapPlacement& straps, double width_m, int face, double u, double v) {
  const Eigen::Vector3i corners = model.model->faces.col(face);
  const int arm = model.forearm_arm[static_cast<std::size_t>(corners[0])];
  if (arm < 0 || std::isnan(straps[static_cast<std::size_t>(arm)])) return false;
  for (int k = 1; k < 3; ++k) {
    if (model.forearm_arm[static_cast<std::size_t>(corners[k])] != arm) return false;
  }
  const double w[3] = {u, v, 1.0 - u - v};  // core/body's barycentric convention
  double s = 0;
  for (int k = 0; k < 3; ++k) s += w[k] * model.forearm_coordinate_m[static_cast<std::size_t>(corners[k])];
  return std::abs(s - straps[static_cast<std::size_t>(arm)]) <= 0.5 * width_m;
}

ColorRenderer::ColorRenderer(const ColorCameraOptions& options, const RenderModel& model, const StrapPlacement& straps,
                             const std::vector<RoomPlane>& room_K, std::uint64_t seed)
    : options_(options),
      camera_(options.intrinsics),
      scene_(raycast::EmbreeDevice::shared(), model.model->faces, model.model->num_vertices()),
      model_(model),
      straps_(straps),
      seed_(seed) {
  validate(options);
  // Room planes n . p_K = d become n_C . p_C = d + n_C . t in C.
  const Eigen::Isometry3d& C_from_K = options_.color_from_depth;
  std::vector<RoomPlane> room_C;
  for (const RoomPlane& plane : room_K) {
    const Eigen::Vector3d n_C = C_from_K.linear() * plane.normal_K;
    room_C.push_back(RoomPlane{n_C, plane.offset_m + n_C.dot(C_from_K.translation())});
  }
  background_.create(camera_.height(), camera_.width(), CV_16SC3);
  for (int row = 0; row < camera_.height(); ++row) {
    auto* out = background_.ptr<cv::Vec3s>(row);
    for (int col = 0; col < camera_.width(); ++col) {
      const Eigen::Vector3d ray = camera_.pixel_ray(col, row).cast<double>();
      double nearest_z = std::numeric_limits<double>::infinity();
      std::size_t hit = room_C.size();
      for (std::size_t p = 0; p < room_C.size(); ++p) {
        const double n_dot_r = room_C[p].normal_K.dot(ray);
        if (std::abs(n_dot_r) < 1e-12) continue;
        const double z = room_C[p].offset_m / n_dot_r;
        if (z > 0 && z < nearest_z) {
          nearest_z = z;
          hit = p;
        }
      }
      // Plane 0 is the floor, the others walls; nothing hit stays dark.
      const Eigen::Vector3d colour =
          hit == room_C.size() ? Eigen::Vector3d(0.05, 0.05, 0.05) : (hit == 0 ? kFloorAlbedo : kWallAlbedo);
      out[col] =
          cv::Vec3s(static_cast<short>(std::lround(255 * colour[0])), static_cast<short>(std::lround(255 * colour[1])),
                    static_cast<short>(std::lround(255 * colour[2])));
    }
  }
  noise_ = cv::Mat::zeros(camera_.height() + 2 * kNoiseMargin, camera_.width() + 2 * kNoiseMargin, CV_16SC3);
  if (options_.noise_sigma > 0) {
    // cv::RNG is OpenCV's documented multiply-with-carry generator: the same numbers everywhere.
    SimRng rng(seed, "color_noise");
    cv::RNG noise_rng(static_cast<std::uint64_t>(rng.uniform() * 0x1.0p53));
    cv::Mat noise(noise_.size(), CV_32FC3);
    noise_rng.fill(noise, cv::RNG::NORMAL, 0.0, options_.noise_sigma);
    noise.convertTo(noise_, CV_16SC3);
  }
}

cv::Mat ColorRenderer::render(const Eigen::Matrix3Xd& vertices_K, std::int64_t frame) {
  const Eigen::Matrix3Xd vertices_C = options_.color_from_depth * vertices_K;
  scene_.update_vertices(vertices_C);
  scene_.render(camera_, 0, images_);
  // The noise window of this frame (zero noise: none).
  int dx = 0, dy = 0;
  const bool noisy = options_.noise_sigma > 0;
  if (noisy) {
    SimRng rng(seed_, "color_noise/" + std::to_string(frame));
    dx = std::min(2 * kNoiseMargin, static_cast<int>(rng.uniform() * (2 * kNoiseMargin + 1)));
    dy = std::min(2 * kNoiseMargin, static_cast<int>(rng.uniform() * (2 * kNoiseMargin + 1)));
  }
  // One pass writes room + noise saturated to 8 bits (as adding 16-bit images and converting
  // would); a second overwrites the person's pixels, only inside the render's hit rectangle.
  const int channels = 3 * camera_.width();
  cv::Mat bgr(camera_.height(), camera_.width(), CV_8UC3);
  const auto noise_row = [&](int row) { return noise_.ptr<short>(row + dy) + 3 * dx; };
  for (int row = 0; row < camera_.height(); ++row) {
    const short* room = background_.ptr<short>(row);
    const short* noise = noise_row(row);
    std::uint8_t* out = bgr.ptr<std::uint8_t>(row);
    if (noisy) {
      for (int k = 0; k < channels; ++k) out[k] = cv::saturate_cast<std::uint8_t>(room[k] + noise[k]);
    } else {
      for (int k = 0; k < channels; ++k) out[k] = cv::saturate_cast<std::uint8_t>(room[k]);
    }
  }
  const Eigen::Matrix3Xi& faces = model_.model->faces;
  // Face normals once per frame rather than once per pixel (the same expression, the same values).
  face_normals_.resize(3, faces.cols());
  for (Eigen::Index f = 0; f < faces.cols(); ++f) {
    const Eigen::Vector3i c = faces.col(f);
    face_normals_.col(f) =
        (vertices_C.col(c[1]) - vertices_C.col(c[0])).cross(vertices_C.col(c[2]) - vertices_C.col(c[0])).normalized();
  }
  for (int row = images_.hit_row_begin; row < images_.hit_row_end; ++row) {
    const short* noise = noise_row(row);
    std::uint8_t* out = bgr.ptr<std::uint8_t>(row);
    for (int col = images_.hit_col_begin; col < images_.hit_col_end; ++col) {
      const std::size_t i = static_cast<std::size_t>(row) * camera_.width() + col;
      const int face = images_.face[i];
      if (face < 0) continue;
      const Eigen::Vector3i c = faces.col(face);
      const double w[3] = {images_.u[i], images_.v[i], 1.0 - images_.u[i] - images_.v[i]};
      const int nearest = w[0] >= w[1] && w[0] >= w[2] ? 0 : (w[1] >= w[2] ? 1 : 2);
      const Material material = model_.material[static_cast<std::size_t>(c[nearest])];
      const Eigen::Vector3d albedo = is_strap(model_, straps_, options_.strap_width_m, face, w[0], w[1])
                                         ? kStrapAlbedo
                                         : kAlbedo[static_cast<std::size_t>(material)];
      const Eigen::Vector3d ray = camera_.pixel_ray(col, row).cast<double>().normalized();
      const Eigen::Vector3d colour = 255.0 * albedo * (0.35 + 0.65 * std::max(0.0, -face_normals_.col(face).dot(ray)));
      for (int k = 0; k < 3; ++k) {
        const auto shaded = static_cast<short>(geometry::round_half_up(colour[k]));  // colour >= 0
        out[3 * col + k] = cv::saturate_cast<std::uint8_t>(noisy ? shaded + noise[3 * col + k] : shaded);
      }
    }
  }
  return bgr;
}

v1::ColorFrame encode_color_frame(const cv::Mat& bgr, int jpeg_quality, std::int64_t t_us) {
  std::vector<std::uint8_t> bytes;
  if (!cv::imencode(".jpg", bgr, bytes, {cv::IMWRITE_JPEG_QUALITY, jpeg_quality})) {
    throw Error(ErrorCode::kInternal, "color", "JPEG encoding failed");
  }
  v1::ColorFrame frame;
  frame.set_t_us(t_us);
  frame.set_width(static_cast<std::uint32_t>(bgr.cols));
  frame.set_height(static_cast<std::uint32_t>(bgr.rows));
  frame.set_encoding(v1::ColorFrame::JPEG);
  frame.set_data(bytes.data(), bytes.size());
  return frame;
}

}  // namespace posefuse::sim
