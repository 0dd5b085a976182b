#include "fit/zone_sampling.hpp"

#include <gtest/gtest.h>

#include <array>
#include <limits>
#include <random>
#include <set>

#include "fit/silhouette_distance.hpp"
#include "synthetic_frames.hpp"

namespace posefuse::fit {
namespace {

struct StickFigure {
  raycast::DepthCamera camera{raycast::DepthIntrinsics{}};
  KinectSkeleton skeleton = testing::t_pose_skeleton(2.5);
  PointCloud cloud;
  explicit StickFigure(bool with_legs)
      : cloud(build_point_cloud(testing::render_stick_figure(camera, skeleton, with_legs), camera)) {}
};

std::array<int, kBodyZoneCount> count_per_zone(const std::vector<DepthSample>& samples, bool edge_only) {
  std::array<int, kBodyZoneCount> n{};
  for (const auto& s : samples)
    if (!edge_only || s.near_edge) ++n[static_cast<int>(s.zone)];
  return n;
}

TEST(FitZoneSampling, ZonesFollowTheNearestBone) {
  const StickFigure figure(true);
  const std::vector<int8_t> zone = assign_zones(figure.cloud, figure.skeleton, figure.camera);
  auto zone_at = [&](const Eigen::Vector3d& p_K) {
    const Eigen::Vector2d uv = *figure.camera.project(p_K);
    return BodyZone(zone[static_cast<size_t>(std::lround(uv.y())) * figure.camera.width() + std::lround(uv.x())]);
  };
  const auto& s = figure.skeleton;
  EXPECT_EQ(zone_at(s[3]), BodyZone::kHead);
  EXPECT_EQ(zone_at(s[1]), BodyZone::kTorso);
  EXPECT_EQ(zone_at((s[4] + s[5]) / 2), BodyZone::kLeftUpperArm);
  EXPECT_EQ(zone_at((s[5] + s[6]) / 2), BodyZone::kLeftForearm);
  EXPECT_EQ(zone_at(s[7]), BodyZone::kLeftForearm);
  EXPECT_EQ(zone_at((s[8] + s[9]) / 2), BodyZone::kRightUpperArm);
  EXPECT_EQ(zone_at((s[9] + s[10]) / 2), BodyZone::kRightForearm);
  EXPECT_EQ(zone_at(s[13]), BodyZone::kLeftLeg);
  EXPECT_EQ(zone_at(s[17]), BodyZone::kRightLeg);
}

TEST(FitZoneSampling, ZonesEqualTheNearestOfAllBonesPerPixel) {
  // assign_zones skips bones per 8 x 8 tile; every pixel must still get the nearest of all bones,
  // also for skeletons bent so that bones cross and come close (many ties and near-ties).
  StickFigure figure(true);
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> offset(-0.15, 0.15);
  for (int trial = 0; trial < 3; ++trial) {
    KinectSkeleton skeleton = figure.skeleton;
    if (trial > 0)
      for (auto& joint : skeleton) joint += Eigen::Vector3d(offset(rng), offset(rng), 0);
    const std::vector<int8_t> zone = assign_zones(figure.cloud, skeleton, figure.camera);
    int tested = 0;
    for (int row = 0; row < figure.cloud.height; ++row)
      for (int col = 0; col < figure.cloud.width; ++col) {
        const int8_t got = zone[static_cast<size_t>(row) * figure.cloud.width + col];
        if (!figure.cloud.has(col, row)) {
          ASSERT_EQ(got, -1);
          continue;
        }
        ASSERT_EQ(BodyZone(got), nearest_bone_zone(Eigen::Vector2d(col, row), skeleton, figure.camera))
            << "trial " << trial << " pixel " << col << ", " << row;
        ++tested;
      }
    EXPECT_GT(tested, 1000);
  }
}

TEST(FitZoneSampling, QuotasHonouredWithNearEdgeShare) {
  const StickFigure figure(true);
  const ZoneSamplingParams params;
  const auto samples = sample_depth_pixels(figure.cloud, figure.skeleton, figure.camera, params);
  ASSERT_EQ(samples.size(), 250u);
  // 250 x shares {0.14, 0.34, 0.10 x 4, 0.06 x 2}: every zone has more pixels than its quota.
  const std::array<int, kBodyZoneCount> expected = {35, 85, 25, 25, 25, 25, 15, 15};
  EXPECT_EQ(count_per_zone(samples, false), expected);
  const auto edges = count_per_zone(samples, true);
  for (int z = 0; z < kBodyZoneCount; ++z)
    EXPECT_EQ(edges[z], std::lround(0.3 * expected[z])) << body_zone_name(BodyZone(z));

  // Samples are distinct cloud pixels, their p_K is the cloud's, and near_edge is true.
  std::vector<uint8_t> outside(figure.cloud.valid.size());
  for (size_t i = 0; i < outside.size(); ++i) outside[i] = !figure.cloud.valid[i];
  const auto to_outside = silhouette_distance_map(outside, figure.cloud.width, figure.cloud.height);
  std::set<std::pair<int, int>> seen;
  for (const auto& s : samples) {
    EXPECT_TRUE(seen.insert({s.col, s.row}).second);
    ASSERT_TRUE(figure.cloud.has(s.col, s.row));
    EXPECT_EQ(s.p_K, figure.cloud.at(s.col, s.row));
    const float d = to_outside.distance_px[static_cast<size_t>(s.row) * figure.cloud.width + s.col];
    EXPECT_EQ(s.near_edge, d <= params.edge_band_px);
  }
}

TEST(FitZoneSampling, DeterministicForASeed) {
  const StickFigure figure(true);
  ZoneSamplingParams params;
  const auto a = sample_depth_pixels(figure.cloud, figure.skeleton, figure.camera, params);
  const auto b = sample_depth_pixels(figure.cloud, figure.skeleton, figure.camera, params);
  params.seed = 2;
  const auto c = sample_depth_pixels(figure.cloud, figure.skeleton, figure.camera, params);
  ASSERT_EQ(a.size(), b.size());
  int differing = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].col, b[i].col);
    EXPECT_EQ(a[i].row, b[i].row);
    differing += a[i].col != c[i].col || a[i].row != c[i].row;
  }
  EXPECT_GT(differing, 200);
}

TEST(FitZoneSampling, MissingZonesHandTheirQuotaToTheOthers) {
  // No legs in the silhouette, and leg joints that cannot be projected (behind the camera), so
  // no pixel falls in a leg zone.
  StickFigure figure(false);
  for (int j = 12; j <= 19; ++j) figure.skeleton[j].z() = -1;
  const auto samples = sample_depth_pixels(figure.cloud, figure.skeleton, figure.camera);
  ASSERT_EQ(samples.size(), 250u);
  const auto n = count_per_zone(samples, false);
  EXPECT_EQ(n[static_cast<int>(BodyZone::kLeftLeg)], 0);
  EXPECT_EQ(n[static_cast<int>(BodyZone::kRightLeg)], 0);
  // The 30 leg samples are spread over the other zones by share (0.88 of the total):
  // 250 x 0.34 / 0.88 = 96.6, 250 x 0.14 / 0.88 = 39.8, 250 x 0.10 / 0.88 = 28.4.
  EXPECT_GE(n[static_cast<int>(BodyZone::kTorso)], 96);
  EXPECT_LE(n[static_cast<int>(BodyZone::kTorso)], 97);
  EXPECT_GE(n[static_cast<int>(BodyZone::kHead)], 39);
  EXPECT_LE(n[static_cast<int>(BodyZone::kHead)], 40);
  for (int z = 2; z < 6; ++z) {
    EXPECT_GE(n[z], 28);
    EXPECT_LE(n[z], 29);
  }
}

TEST(FitZoneSampling, SmallCloudGivesEveryPixel) {
  const StickFigure figure(true);
  ZoneSamplingParams params;
  params.num_samples = figure.cloud.count + 100;
  const auto samples = sample_depth_pixels(figure.cloud, figure.skeleton, figure.camera, params);
  EXPECT_EQ(static_cast<int>(samples.size()), figure.cloud.count);
}

// Drawing more samples than pixels takes every pixel with a zone (the pixel lists are built over
// the cloud's box only): the same pixels as a scan of the whole image, each with the zone of
// assign_zones and the edge flag of the full-image distance to the outside, for any band.
void expect_every_pixel_with_zone_and_edge_flag(const PointCloud& cloud, const KinectSkeleton& skeleton,
                                                const raycast::DepthCamera& camera, float band_px) {
  SCOPED_TRACE("edge_band_px " + std::to_string(band_px));
  ZoneSamplingParams params;
  params.num_samples = cloud.count + 100;
  params.edge_band_px = band_px;
  const auto samples = sample_depth_pixels(cloud, skeleton, camera, params);
  const std::vector<int8_t> zone = assign_zones(cloud, skeleton, camera);
  std::vector<uint8_t> outside(cloud.valid.size());
  for (size_t i = 0; i < outside.size(); ++i) outside[i] = !cloud.valid[i];
  const auto to_outside = silhouette_distance_map(outside, cloud.width, cloud.height);
  std::set<size_t> expected, seen;
  for (size_t i = 0; i < zone.size(); ++i)
    if (zone[i] >= 0) expected.insert(i);
  int near_edge = 0;
  for (const auto& s : samples) {
    const size_t i = static_cast<size_t>(s.row) * cloud.width + s.col;
    EXPECT_TRUE(seen.insert(i).second);
    EXPECT_EQ(static_cast<int>(s.zone), zone[i]);
    EXPECT_EQ(s.near_edge, to_outside.distance_px[i] <= band_px) << s.col << ", " << s.row;
    near_edge += s.near_edge;
  }
  EXPECT_EQ(seen, expected);
  if (band_px >= 1) {
    EXPECT_GT(near_edge, 0);
  }
}

// Holes of single pixels inside the cloud, away from its box's edges (the box stays the same).
void punch_holes(PointCloud& cloud, int count, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> col(cloud.box.col0 + 1, cloud.box.col1 - 1),
      row(cloud.box.row0 + 1, cloud.box.row1 - 1);
  for (int k = 0; k < count; ++k) {
    const size_t i = static_cast<size_t>(row(rng)) * cloud.width + col(rng);
    if (!cloud.valid[i]) continue;
    cloud.valid[i] = 0;
    cloud.value_K[i].setZero();
    --cloud.count;
  }
}

TEST(FitZoneSampling, EveryPixelSampledCarriesItsZoneAndEdgeFlag) {
  StickFigure figure(true);
  for (const float band : {0.0f, 1.0f, 1.5f, 2.5f, 3.0f, 4.2f, 6.0f})
    expect_every_pixel_with_zone_and_edge_flag(figure.cloud, figure.skeleton, figure.camera, band);
  punch_holes(figure.cloud, 400, 7);
  for (const float band : {1.0f, 3.0f, 4.2f})
    expect_every_pixel_with_zone_and_edge_flag(figure.cloud, figure.skeleton, figure.camera, band);
}

TEST(FitZoneSampling, EdgeFlagsOfACloudThatTouchesTheImageBorder) {
  // The image's border is not outside the cloud: only pixels without a depth reading are.
  const StickFigure figure(true);
  PointCloud cloud = VectorImage::empty(figure.cloud.width, figure.cloud.height);
  for (int row = 0; row < cloud.height; ++row)
    for (int col = 0; col < 120; ++col) cloud.set(col, row, Eigen::Vector3f(0, 0, 2));
  for (const float band : {1.0f, 3.0f})
    expect_every_pixel_with_zone_and_edge_flag(cloud, figure.skeleton, figure.camera, band);
  punch_holes(cloud, 300, 11);
  for (const float band : {1.0f, 3.0f, 4.2f})
    expect_every_pixel_with_zone_and_edge_flag(cloud, figure.skeleton, figure.camera, band);

  // A cloud that fills the image has no pixel near an edge; with holes, those around them.
  PointCloud full = VectorImage::empty(figure.cloud.width, figure.cloud.height);
  for (int row = 0; row < full.height; ++row)
    for (int col = 0; col < full.width; ++col) full.set(col, row, Eigen::Vector3f(0, 0, 2));
  ZoneSamplingParams params;
  params.num_samples = full.count;
  for (const auto& s : sample_depth_pixels(full, figure.skeleton, figure.camera, params)) ASSERT_FALSE(s.near_edge);
  punch_holes(full, 50, 13);
  expect_every_pixel_with_zone_and_edge_flag(full, figure.skeleton, figure.camera, 3.0f);
}

TEST(FitZoneSampling, BadInputNamesTheField) {
  const StickFigure figure(true);
  ZoneSamplingParams params;
  params.zone_share[0] += 0.1;
  EXPECT_EQ(testing::error_field([&] { sample_depth_pixels(figure.cloud, figure.skeleton, figure.camera, params); }),
            "zone_params.zone_share");
  params = {};
  params.zone_share[2] = -0.1;
  params.zone_share[3] = 0.3;
  EXPECT_EQ(testing::error_field([&] { sample_depth_pixels(figure.cloud, figure.skeleton, figure.camera, params); }),
            "zone_params.zone_share[left_upper_arm]");
  params = {};
  params.num_samples = 0;
  EXPECT_EQ(testing::error_field([&] { sample_depth_pixels(figure.cloud, figure.skeleton, figure.camera, params); }),
            "zone_params.num_samples");
  params = {};
  params.edge_share = 1.5;
  EXPECT_EQ(testing::error_field([&] { sample_depth_pixels(figure.cloud, figure.skeleton, figure.camera, params); }),
            "zone_params.edge_share");
  PointCloud wrong_size = figure.cloud;
  wrong_size.width -= 1;
  EXPECT_EQ(testing::error_field([&] { sample_depth_pixels(wrong_size, figure.skeleton, figure.camera); }),
            "cloud.width");
  KinectSkeleton skeleton = figure.skeleton;
  skeleton[5].x() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(testing::error_field([&] { sample_depth_pixels(figure.cloud, skeleton, figure.camera); }), "skeleton[5]");
  for (auto& joint : skeleton) joint = Eigen::Vector3d(0, 0, -1);  // all behind the camera
  EXPECT_EQ(testing::error_field([&] { sample_depth_pixels(figure.cloud, skeleton, figure.camera); }), "skeleton");
}

}  // namespace
}  // namespace posefuse::fit
