#include "sim/depth_noise.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <numbers>

#include "common/error.hpp"
#include "raycast/mesh_scene.hpp"
#include "test_camera.hpp"

using posefuse::Error;
using namespace posefuse::sim;
namespace raycast = posefuse::raycast;

using posefuse::sim::testing::small_camera;

namespace {

using std::numbers::pi;

std::vector<uint16_t> render_planes(const raycast::DepthCamera& camera, const std::vector<RoomPlane>& planes) {
  std::vector<uint16_t> depth(static_cast<std::size_t>(camera.width()) * camera.height(), 0);
  composite_room(camera, planes, depth);
  return depth;
}

std::vector<uint8_t> no_body(const raycast::DepthCamera& camera) {
  return std::vector<uint8_t>(static_cast<std::size_t>(camera.width()) * camera.height(), raycast::kNoBody);
}

// Standard deviation (mm) of noisy - clean over `frames` frames of a wall at `z_m`.
double measured_wall_sigma_mm(double z_m, int frames) {
  const raycast::DepthCamera camera = small_camera();
  const std::vector<uint16_t> clean = render_planes(camera, {RoomPlane{Eigen::Vector3d::UnitZ(), z_m}});
  double sum = 0, sum_sq = 0;
  long count = 0;
  for (int f = 0; f < frames; ++f) {
    const NoisyDepth noisy = apply_depth_noise(camera, clean, no_body(camera), DepthNoiseOptions{}, 7, f);
    for (std::size_t i = 0; i < clean.size(); ++i) {
      EXPECT_NE(noisy.depth_mm[i], 0) << "pixel " << i;
      const double d = static_cast<double>(noisy.depth_mm[i]) - clean[i];
      sum += d;
      sum_sq += d * d;
      ++count;
    }
  }
  const double mean = sum / count;
  return std::sqrt(sum_sq / count - mean * mean);
}

}  // namespace

TEST(DepthNoise, WallNoiseMatchesModelAt1p5m) {
  const double model_mm = axial_sigma_m(DepthNoiseOptions{}, 1.5) * 1000.0;
  const double measured_mm = measured_wall_sigma_mm(1.5, 5);
  std::printf("wall 1.5 m: model sigma %.3f mm, measured %.3f mm\n", model_mm, measured_mm);
  EXPECT_NEAR(measured_mm, model_mm, 0.15 * model_mm);
}

TEST(DepthNoise, WallNoiseMatchesModelAt3m) {
  const double model_mm = axial_sigma_m(DepthNoiseOptions{}, 3.0) * 1000.0;
  const double measured_mm = measured_wall_sigma_mm(3.0, 5);
  std::printf("wall 3 m: model sigma %.3f mm, measured %.3f mm\n", model_mm, measured_mm);
  EXPECT_NEAR(measured_mm, model_mm, 0.15 * model_mm);
  EXPECT_GT(model_mm, 2.0 * axial_sigma_m(DepthNoiseOptions{}, 1.5) * 1000.0);
}

TEST(DepthNoise, GrazingFloorPixelsAreDropped) {
  const raycast::DepthCamera camera = small_camera();
  const double camera_height_m = 0.5;
  // Only the floor: a far wall would end it with a depth edge.
  const std::vector<uint16_t> clean = render_planes(camera, {simple_room(camera_height_m, 100.0)[0]});
  DepthNoiseOptions options;
  options.max_range_m = 60.0;
  const NoisyDepth noisy = apply_depth_noise(camera, clean, no_body(camera), options, 3, 0);
  int grazing = 0, grazing_kept = 0, steep = 0, steep_dropped = 0;
  for (int row = 0; row < camera.height(); ++row) {
    for (int col = 0; col < camera.width(); ++col) {
      const std::size_t i = static_cast<std::size_t>(row) * camera.width() + col;
      if (clean[i] == 0) continue;
      const Eigen::Vector3d ray = camera.pixel_ray(col, row).cast<double>().normalized();
      const double incidence_deg = std::acos(std::abs(ray.y())) * 180.0 / pi;
      if (incidence_deg > options.max_incidence_deg + 3.0) {
        ++grazing;
        grazing_kept += noisy.depth_mm[i] != 0;
      } else if (incidence_deg < options.max_incidence_deg - 3.0 && clean[i] > 600) {
        ++steep;
        steep_dropped += noisy.depth_mm[i] == 0;
      }
    }
  }
  std::printf("floor: %d grazing pixels (%d kept), %d steeper pixels (%d dropped)\n", grazing, grazing_kept, steep,
              steep_dropped);
  ASSERT_GT(grazing, 100);
  ASSERT_GT(steep, 100);
  EXPECT_EQ(grazing_kept, 0);
  EXPECT_EQ(steep_dropped, 0);
}

TEST(DepthNoise, IncidenceOfTiltedPlaneFromGradients) {
  const raycast::DepthCamera camera = small_camera();
  const Eigen::Vector3d normal = Eigen::Vector3d(std::sin(0.6), 0, std::cos(0.6));
  const std::vector<uint16_t> clean = render_planes(camera, {RoomPlane{normal, 2.0}});
  const std::vector<float> incidence = incidence_angles_deg(camera, clean, DepthNoiseOptions{});
  double worst_deg = 0;
  for (int row = 2; row < camera.height() - 2; ++row) {
    for (int col = 2; col < camera.width() - 2; ++col) {
      const Eigen::Vector3d ray = camera.pixel_ray(col, row).cast<double>().normalized();
      const double truth_deg = std::acos(std::abs(ray.dot(normal))) * 180.0 / pi;
      worst_deg =
          std::max(worst_deg, std::abs(truth_deg - incidence[static_cast<std::size_t>(row) * camera.width() + col]));
    }
  }
  std::printf("tilted plane: worst incidence error %.2f deg\n", worst_deg);
  EXPECT_LT(worst_deg, 3.0);
}

TEST(DepthNoise, QuantisesToWholeMillimetres) {
  const raycast::DepthCamera camera = small_camera();
  const std::vector<uint16_t> clean = render_planes(camera, {RoomPlane{Eigen::Vector3d::UnitZ(), 2.0}});
  DepthNoiseOptions options;
  options.axial_sigma_base_m = 0.0003;
  options.axial_sigma_quadratic_per_m = 0.0;
  const NoisyDepth noisy = apply_depth_noise(camera, clean, no_body(camera), options, 11, 0);
  int unchanged = 0;
  for (std::size_t i = 0; i < clean.size(); ++i) {
    ASSERT_LE(std::abs(static_cast<int>(noisy.depth_mm[i]) - clean[i]), 2);
    unchanged += noisy.depth_mm[i] == clean[i];
  }
  // 0.3 mm noise rounds back to the same millimetre when |noise| < 0.5 mm: P = 0.904.
  const double fraction = static_cast<double>(unchanged) / clean.size();
  std::printf("0.3 mm noise: %.3f of pixels unchanged after rounding\n", fraction);
  EXPECT_NEAR(fraction, 0.904, 0.02);

  options.axial_sigma_base_m = 0.0;
  EXPECT_EQ(apply_depth_noise(camera, clean, no_body(camera), options, 11, 0).depth_mm, clean);
}

TEST(DepthNoise, FlyingPixelsAlongDepthEdges) {
  const raycast::DepthCamera camera = small_camera();
  std::vector<uint16_t> clean(static_cast<std::size_t>(camera.width()) * camera.height());
  const int edge_col = 64;  // columns < 64 at 1.5 m, others at 3 m
  for (int row = 0; row < camera.height(); ++row) {
    for (int col = 0; col < camera.width(); ++col) {
      clean[static_cast<std::size_t>(row) * camera.width() + col] = col < edge_col ? 1500 : 3000;
    }
  }
  const DepthNoiseOptions options;
  const NoisyDepth noisy = apply_depth_noise(camera, clean, no_body(camera), options, 5, 0);
  int flying = 0;
  for (int row = 0; row < camera.height(); ++row) {
    for (int col = 0; col < camera.width(); ++col) {
      const std::size_t i = static_cast<std::size_t>(row) * camera.width() + col;
      const double z = noisy.depth_mm[i] * 1e-3;
      const bool off_surfaces =
          std::abs(z - 1.5) > 6 * axial_sigma_m(options, 1.5) && std::abs(z - 3.0) > 6 * axial_sigma_m(options, 3.0);
      if (!off_surfaces) continue;
      ++flying;
      EXPECT_TRUE(col == edge_col - 1 || col == edge_col) << "col " << col;
      EXPECT_GT(z, 1.45);
      EXPECT_LT(z, 3.05);
    }
  }
  // Two edge columns, half of the pixels fly, a few land within 6 sigma of a surface.
  const double fraction = flying / (2.0 * camera.height());
  std::printf("flying fraction of edge pixels: %.3f (probability %.2f)\n", fraction, options.flying_pixel_probability);
  EXPECT_GT(fraction, 0.35);
  EXPECT_LT(fraction, 0.55);
}

TEST(DepthNoise, BodyIndexEdgesShiftByAtMostTwoPixels) {
  const raycast::DepthCamera camera = small_camera();
  const std::vector<uint16_t> clean = render_planes(camera, {RoomPlane{Eigen::Vector3d::UnitZ(), 2.0}});
  std::vector<uint8_t> mask = no_body(camera);
  auto inside = [](int col, int row) { return (col - 64) * (col - 64) + (row - 53) * (row - 53) < 30 * 30; };
  for (int row = 0; row < camera.height(); ++row) {
    for (int col = 0; col < camera.width(); ++col) {
      if (inside(col, row)) mask[static_cast<std::size_t>(row) * camera.width() + col] = 2;
    }
  }
  const NoisyDepth noisy = apply_depth_noise(camera, clean, mask, DepthNoiseOptions{}, 9, 0);
  int eroded = 0, dilated = 0;
  for (int row = 0; row < camera.height(); ++row) {
    for (int col = 0; col < camera.width(); ++col) {
      const std::size_t i = static_cast<std::size_t>(row) * camera.width() + col;
      if (noisy.body_index[i] == mask[i]) continue;
      (mask[i] == 2 ? eroded : dilated) += 1;
      EXPECT_TRUE(noisy.body_index[i] == 2 || noisy.body_index[i] == raycast::kNoBody);
      // A changed pixel lies within 2 px (Chebyshev) of a pixel of the other class.
      bool near_other = false;
      for (int r = row - 2; r <= row + 2; ++r) {
        for (int c = col - 2; c <= col + 2; ++c) near_other |= inside(c, r) != inside(col, row);
      }
      EXPECT_TRUE(near_other) << col << ", " << row;
    }
  }
  std::printf("body index: %d pixels eroded, %d dilated\n", eroded, dilated);
  EXPECT_GT(eroded, 20);
  EXPECT_GT(dilated, 20);
}

TEST(DepthNoise, DeterministicForSeedAndFrame) {
  const raycast::DepthCamera camera = small_camera();
  const std::vector<uint16_t> clean = render_planes(camera, simple_room(0.8, 3.5));
  const NoisyDepth a = apply_depth_noise(camera, clean, no_body(camera), DepthNoiseOptions{}, 42, 3);
  const NoisyDepth b = apply_depth_noise(camera, clean, no_body(camera), DepthNoiseOptions{}, 42, 3);
  const NoisyDepth c = apply_depth_noise(camera, clean, no_body(camera), DepthNoiseOptions{}, 42, 4);
  const NoisyDepth d = apply_depth_noise(camera, clean, no_body(camera), DepthNoiseOptions{}, 43, 3);
  EXPECT_EQ(a.depth_mm, b.depth_mm);
  EXPECT_EQ(a.body_index, b.body_index);
  EXPECT_NE(a.depth_mm, c.depth_mm);
  EXPECT_NE(a.depth_mm, d.depth_mm);
}

TEST(DepthNoise, RejectsBadInput) {
  const raycast::DepthCamera camera = small_camera();
  const std::vector<uint16_t> clean = render_planes(camera, simple_room(0.8, 3.5));
  DepthNoiseOptions bad;
  bad.axial_sigma_base_m = std::nan("");
  EXPECT_THROW(validate(bad), Error);
  bad = DepthNoiseOptions{};
  bad.edge_slope_deg = 70.0;  // below max_incidence_deg
  EXPECT_THROW(validate(bad), Error);
  bad = DepthNoiseOptions{};
  bad.flying_pixel_probability = 1.5;
  EXPECT_THROW(apply_depth_noise(camera, clean, no_body(camera), bad, 1, 0), Error);
  std::vector<uint16_t> short_depth(clean.begin(), clean.end() - 1);
  EXPECT_THROW(apply_depth_noise(camera, short_depth, no_body(camera), DepthNoiseOptions{}, 1, 0), Error);
  EXPECT_THROW(composite_room(camera, {RoomPlane{Eigen::Vector3d(0, 2, 0), 1.0}}, short_depth), Error);
  EXPECT_THROW(simple_room(-1.0, 3.0), Error);
}

TEST(DepthNoise, StaticBackgroundGivesTheSameFrames) {
  // A "person" (a slanted box with a rounded top, nearer than the room) in front of the room:
  // reusing the room's cached incidence must not change a single pixel.
  const raycast::DepthCamera camera = small_camera();
  const std::vector<RoomPlane> room = simple_room(0.8, 3.5);
  const StaticBackground background(camera, room, DepthNoiseOptions{});
  EXPECT_EQ(background.depth_mm(), render_planes(camera, room));
  for (int frame = 0; frame < 3; ++frame) {
    std::vector<uint16_t> body(static_cast<std::size_t>(camera.width()) * camera.height(), 0);
    std::vector<uint8_t> mask = no_body(camera);
    for (int row = 10; row < 90; ++row) {
      for (int col = 30 + 5 * frame; col < 80 + 5 * frame; ++col) {
        const std::size_t i = static_cast<std::size_t>(row) * camera.width() + col;
        body[i] = static_cast<uint16_t>(2000 + 4 * col + (row < 20 ? (20 - row) * (20 - row) : 0));
        mask[i] = 1;
      }
    }
    std::vector<uint16_t> full = body, cached = body;
    composite_room(camera, room, full);
    background.composite(cached);
    ASSERT_EQ(full, cached);
    const NoisyDepth a = apply_depth_noise(camera, full, mask, DepthNoiseOptions{}, 5, frame);
    const NoisyDepth b = apply_depth_noise(camera, cached, mask, DepthNoiseOptions{}, 5, frame, &background);
    EXPECT_EQ(a.depth_mm, b.depth_mm) << frame;
    EXPECT_EQ(a.body_index, b.body_index) << frame;
  }
  DepthNoiseOptions other;
  other.edge_min_jump_m = 0.1;
  std::vector<uint16_t> depth = background.depth_mm();
  EXPECT_THROW(apply_depth_noise(camera, depth, no_body(camera), other, 1, 0, &background), Error);
  std::vector<uint16_t> short_depth(10, 0);
  EXPECT_THROW(background.composite(short_depth), Error);
}
