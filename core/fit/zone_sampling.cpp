#include "fit/zone_sampling.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <optional>
#include <random>
#include <string>
#include <utility>

#include "common/error.hpp"
#include "fit/silhouette_distance.hpp"
#include "fit/tracked_skeleton.hpp"

namespace posefuse::fit {

namespace {

// A projected bone with what the point-segment distance needs precomputed.
struct Segment {
  Eigen::Vector2d a, ab;
  double len2;
  BodyZone zone;
};

double point_segment_distance2(const Eigen::Vector2d& p, const Segment& s) {
  const double t = s.len2 > 0 ? std::clamp((p - s.a).dot(s.ab) / s.len2, 0.0, 1.0) : 0.0;
  return (s.a + t * s.ab - p).squaredNorm();
}

void validate(const ZoneSamplingParams& params) {
  if (params.num_samples < 1 || params.num_samples > 1'000'000)
    throw_invalid("zone_params.num_samples", "must be in [1, 1e6], got " + std::to_string(params.num_samples));
  double total = 0;
  for (int z = 0; z < kBodyZoneCount; ++z) {
    const double share = params.zone_share[z];
    if (!std::isfinite(share) || share < 0)
      throw_invalid(std::string("zone_params.zone_share[") + body_zone_name(BodyZone(z)) + "]",
                    "must be finite and non-negative, got " + std::to_string(share));
    total += share;
  }
  if (std::abs(total - 1.0) > 1e-6)
    throw_invalid("zone_params.zone_share", "must sum to 1, sums to " + std::to_string(total));
  if (!std::isfinite(params.edge_share) || params.edge_share < 0 || params.edge_share > 1)
    throw_invalid("zone_params.edge_share", "must be in [0, 1], got " + std::to_string(params.edge_share));
  if (!std::isfinite(params.edge_band_px) || params.edge_band_px < 0)
    throw_invalid("zone_params.edge_band_px",
                  "must be finite and non-negative, got " + std::to_string(params.edge_band_px));
}

// Splits `total` into integer quotas proportional to `shares` (largest remainder), never giving
// a zone more than `available[z]`; the shortfall is handed to zones that still have pixels.
std::array<int, kBodyZoneCount> zone_quotas(int total, const std::array<double, kBodyZoneCount>& shares,
                                            const std::array<int, kBodyZoneCount>& available) {
  std::array<int, kBodyZoneCount> quota{};
  int left = total;
  for (int round = 0; left > 0 && round <= kBodyZoneCount; ++round) {
    double open_share = 0;
    for (int z = 0; z < kBodyZoneCount; ++z)
      if (quota[z] < available[z]) open_share += shares[z];
    // Zones with a zero share only take pixels when nothing else is left.
    const bool use_equal = open_share <= 0;
    std::array<double, kBodyZoneCount> weight{};
    double weight_sum = 0;
    for (int z = 0; z < kBodyZoneCount; ++z)
      if (quota[z] < available[z]) weight_sum += weight[z] = use_equal ? 1.0 : shares[z];
    if (weight_sum <= 0) break;
    std::array<std::pair<double, int>, kBodyZoneCount> remainders{};
    int given = 0;
    for (int z = 0; z < kBodyZoneCount; ++z) {
      const double exact = left * weight[z] / weight_sum;
      const int whole = std::min(static_cast<int>(std::floor(exact)), available[z] - quota[z]);
      quota[z] += whole;
      given += whole;
      remainders[z] = {quota[z] < available[z] ? exact - std::floor(exact) : -1.0, z};
    }
    std::stable_sort(remainders.begin(), remainders.end(), [](auto& a, auto& b) { return a.first > b.first; });
    for (const auto& [remainder, z] : remainders)
      if (given < left && remainder > 0 && quota[z] < available[z]) {
        ++quota[z];
        ++given;
      }
    left -= given;
    if (given == 0) {
      // Only fractional shares remained: hand single pixels out in zone order.
      for (int z = 0; z < kBodyZoneCount && left > 0; ++z)
        if (quota[z] < available[z] && weight[z] > 0) {
          ++quota[z];
          --left;
        }
    }
  }
  return quota;
}

// Draws `count` distinct entries of `pool` (partial Fisher-Yates), appending them to `out`.
void draw(std::vector<int>& pool, int count, std::mt19937_64& rng, std::vector<int>& out) {
  for (int i = 0; i < count; ++i) {
    std::uniform_int_distribution<size_t> pick(static_cast<size_t>(i), pool.size() - 1);
    std::swap(pool[static_cast<size_t>(i)], pool[pick(rng)]);
    out.push_back(pool[static_cast<size_t>(i)]);
  }
}

}  // namespace

const char* body_zone_name(BodyZone zone) {
  switch (zone) {
    case BodyZone::kHead: return "head";
    case BodyZone::kTorso: return "torso";
    case BodyZone::kLeftUpperArm: return "left_upper_arm";
    case BodyZone::kLeftForearm: return "left_forearm";
    case BodyZone::kRightUpperArm: return "right_upper_arm";
    case BodyZone::kRightForearm: return "right_forearm";
    case BodyZone::kLeftLeg: return "left_leg";
    case BodyZone::kRightLeg: return "right_leg";
  }
  return "unknown";
}

namespace {

void check_size(const PointCloud& cloud, const raycast::DepthCamera& camera) {
  if (cloud.width != camera.width() || cloud.height != camera.height() ||
      cloud.valid.size() != static_cast<size_t>(cloud.width) * cloud.height)
    throw_invalid("cloud.width", "cloud size does not match the camera");
}

// The bones that project into the image; throws for a non-finite joint or no bone.
std::vector<Segment> projected_bones(const KinectSkeleton& skeleton_K, const raycast::DepthCamera& camera) {
  std::array<std::optional<Eigen::Vector2d>, kKinectJointCount> joint_px;
  for (int j = 0; j < kKinectJointCount; ++j) {
    if (!skeleton_K[j].allFinite()) throw_invalid("skeleton[" + std::to_string(j) + "]", "not finite");
    joint_px[j] = camera.project(skeleton_K[j]);
  }
  std::vector<Segment> segments;
  for (const ZoneBone& bone : kZoneBones)
    if (joint_px[bone.from] && joint_px[bone.to]) {
      const Eigen::Vector2d ab = *joint_px[bone.to] - *joint_px[bone.from];
      segments.push_back({*joint_px[bone.from], ab, ab.squaredNorm(), bone.zone});
    }
  if (segments.empty()) throw_precondition("skeleton", "no bone projects into the depth image");
  return segments;
}

// assign_zones over the cloud's box only: the zones of its pixels, row-major with the box's width
// (-1 outside the cloud); the cloud's size is checked.
std::vector<int8_t> assign_zones_in_box(const PointCloud& cloud, const KinectSkeleton& skeleton_K,
                                        const raycast::DepthCamera& camera) {
  const std::vector<Segment> segments = projected_bones(skeleton_K, camera);
  const PixelRect& box = cloud.box;
  const int box_width = box.col1 - box.col0 + 1;
  std::vector<int8_t> zone(static_cast<size_t>(box_width) * std::max(0, box.row1 - box.row0 + 1), -1);
  // Tiles of kTile x kTile pixels: a segment whose distance from the tile's centre, less the
  // tile's radius, exceeds the smallest (distance + radius) over the segments is farther from
  // every pixel of the tile than that one and can never be the nearest (nor tie): only the others
  // are tested per pixel, in the same order, so the zones are those of testing all.
  constexpr int kTile = 8;
  const double radius = std::sqrt(2.0) * (kTile - 1) / 2;
  std::vector<const Segment*> near;
  for (int tile_row = box.row0; tile_row <= box.row1; tile_row += kTile)
    for (int tile_col = box.col0; tile_col <= box.col1; tile_col += kTile) {
      const Eigen::Vector2d centre(tile_col + (kTile - 1) / 2.0, tile_row + (kTile - 1) / 2.0);
      double bound = std::numeric_limits<double>::infinity();
      for (const Segment& segment : segments)
        bound = std::min(bound, std::sqrt(point_segment_distance2(centre, segment)) + radius);
      near.clear();
      for (const Segment& segment : segments)
        if (std::sqrt(point_segment_distance2(centre, segment)) - radius <= bound + 1e-6) near.push_back(&segment);
      // When the candidates share one zone, the nearest of them gives that zone to every cloud
      // pixel of the tile, as long as its squared distance (at most bound^2) cannot overflow.
      bool one_zone = bound < 1e150;
      for (const Segment* segment : near) one_zone = one_zone && segment->zone == near.front()->zone;
      for (int row = tile_row; row <= std::min(box.row1, tile_row + kTile - 1); ++row)
        for (int col = tile_col; col <= std::min(box.col1, tile_col + kTile - 1); ++col) {
          if (!cloud.has(col, row)) continue;
          if (one_zone) {
            zone[static_cast<size_t>(row - box.row0) * box_width + (col - box.col0)] =
                static_cast<int8_t>(near.front()->zone);
            continue;
          }
          const Eigen::Vector2d p(col, row);
          double best = std::numeric_limits<double>::infinity();
          for (const Segment* segment : near) {
            const double d2 = point_segment_distance2(p, *segment);
            if (d2 < best) {
              best = d2;
              zone[static_cast<size_t>(row - box.row0) * box_width + (col - box.col0)] =
                  static_cast<int8_t>(segment->zone);
            }
          }
        }
    }
  return zone;
}

// Which cloud pixels of the box lie within `band_px` (quasi-Euclidean, silhouette_distance.hpp) of
// a pixel outside the cloud, row-major with the box's width (other pixels of the box may be set
// too). The pixels within that distance of a pixel form a disc that holds, in the row dy off its
// centre, the columns up to half_width[|dy|] off; so a pixel is near the outside when some row dy
// off it has an outside pixel within half_width[|dy|] columns. Only outside pixels that are in the
// image count, as for the distance map over the box grown by the band.
std::vector<uint8_t> near_outside_in_box(const PointCloud& cloud, float band_px) {
  const PixelRect& box = cloud.box;
  const int box_width = box.col1 - box.col0 + 1, box_height = box.row1 - box.row0 + 1;
  std::vector<uint8_t> near(box.empty() ? 0 : static_cast<size_t>(box_width) * box_height, 0);
  if (box.empty() || !(band_px >= 0)) return near;
  // Offsets beyond the image never reach an image pixel.
  const int reach =
      static_cast<int>(std::min<float>(std::floor(band_px), static_cast<float>(cloud.width + cloud.height)));
  std::vector<int> half_width(static_cast<size_t>(reach) + 1);
  for (int dy = 0; dy <= reach; ++dy) {
    int w = -1;
    while (w + 1 <= reach && quasi_euclidean_distance(w + 1, dy) <= band_px) ++w;
    half_width[static_cast<size_t>(dy)] = w;
  }
  // row_gap: per row from reach above the box to reach below it (within the image), the column
  // distance from each box column to that row's nearest outside pixel, capped at reach + 1: a scan
  // each way along the row.
  const int row0 = std::max(0, box.row0 - reach), row1 = std::min(cloud.height - 1, box.row1 + reach);
  const int col0 = std::max(0, box.col0 - reach), col1 = std::min(cloud.width - 1, box.col1 + reach);
  const int span = col1 - col0 + 1, far = reach + 1;
  std::vector<int> row_gap(static_cast<size_t>(row1 - row0 + 1) * box_width), gap(static_cast<size_t>(span));
  bool any_outside = false;
  for (int row = row0; row <= row1; ++row) {
    const uint8_t* valid = cloud.valid.data() + static_cast<size_t>(row) * cloud.width + col0;
    int distance = far;
    for (int k = 0; k < span; ++k) gap[static_cast<size_t>(k)] = distance = valid[k] ? std::min(distance + 1, far) : 0;
    // A row without outside pixels (the cloud fills it) is far all along.
    if (distance == far && std::find(valid, valid + span, 0) == valid + span) {
      std::fill_n(row_gap.begin() + static_cast<ptrdiff_t>(row - row0) * box_width, box_width, far);
      continue;
    }
    any_outside = true;
    distance = far;
    for (int k = span - 1; k >= 0; --k) {
      distance = valid[k] ? std::min(distance + 1, far) : 0;
      gap[static_cast<size_t>(k)] = std::min(gap[static_cast<size_t>(k)], distance);
    }
    std::copy_n(gap.begin() + (box.col0 - col0), box_width,
                row_gap.begin() + static_cast<ptrdiff_t>(row - row0) * box_width);
  }
  if (!any_outside) return near;
  for (int row = box.row0; row <= box.row1; ++row) {
    uint8_t* out = near.data() + static_cast<size_t>(row - box.row0) * box_width;
    for (int other = std::max(row0, row - reach); other <= std::min(row1, row + reach); ++other) {
      const int* gap = row_gap.data() + static_cast<size_t>(other - row0) * box_width;
      const int limit = half_width[static_cast<size_t>(std::abs(other - row))];
      for (int k = 0; k < box_width; ++k) out[k] |= static_cast<uint8_t>(gap[k] <= limit);
    }
  }
  return near;
}

}  // namespace

BodyZone nearest_bone_zone(const Eigen::Vector2d& pixel, const KinectSkeleton& skeleton_K,
                           const raycast::DepthCamera& camera) {
  BodyZone zone = BodyZone::kTorso;
  double best = std::numeric_limits<double>::infinity();
  for (const Segment& segment : projected_bones(skeleton_K, camera)) {
    const double d2 = point_segment_distance2(pixel, segment);
    if (d2 < best) {
      best = d2;
      zone = segment.zone;
    }
  }
  return zone;
}

std::vector<int8_t> assign_zones(const PointCloud& cloud, const KinectSkeleton& skeleton_K,
                                 const raycast::DepthCamera& camera) {
  check_size(cloud, camera);
  const std::vector<int8_t> in_box = assign_zones_in_box(cloud, skeleton_K, camera);
  std::vector<int8_t> zone(cloud.valid.size(), -1);
  const PixelRect& box = cloud.box;
  const size_t box_width = static_cast<size_t>(box.col1 - box.col0 + 1);
  for (int row = box.row0; row <= box.row1; ++row)
    std::copy_n(in_box.begin() + static_cast<ptrdiff_t>((row - box.row0) * box_width), box_width,
                zone.begin() + static_cast<ptrdiff_t>(static_cast<size_t>(row) * cloud.width + box.col0));
  return zone;
}

std::vector<DepthSample> sample_depth_pixels(const PointCloud& cloud, const KinectSkeleton& skeleton_K,
                                             const raycast::DepthCamera& camera, const ZoneSamplingParams& params) {
  validate(params);
  check_size(cloud, camera);
  const PixelRect& box = cloud.box;
  const std::vector<int8_t> zone = assign_zones_in_box(cloud, skeleton_K, camera);
  const int box_width = box.col1 - box.col0 + 1;

  const std::vector<uint8_t> near_edge = near_outside_in_box(cloud, params.edge_band_px);
  std::array<std::vector<int>, kBodyZoneCount> edge_pixels, inner_pixels;
  // Row by row in the box: the ascending pixel order.
  for (int row = box.row0; row <= box.row1; ++row)
    for (int col = box.col0; col <= box.col1; ++col) {
      const size_t in_box = static_cast<size_t>(row - box.row0) * box_width + (col - box.col0);
      const int8_t z = zone[in_box];
      if (z < 0) continue;
      (near_edge[in_box] ? edge_pixels : inner_pixels)[z].push_back(row * cloud.width + col);
    }
  std::array<int, kBodyZoneCount> available{};
  for (int z = 0; z < kBodyZoneCount; ++z)
    available[z] = static_cast<int>(edge_pixels[z].size() + inner_pixels[z].size());
  const int total = std::min(params.num_samples, cloud.count);
  const auto quota = zone_quotas(total, params.zone_share, available);

  std::mt19937_64 rng(params.seed);
  std::vector<int> picked;
  std::vector<DepthSample> samples;
  samples.reserve(static_cast<size_t>(total));
  for (int z = 0; z < kBodyZoneCount; ++z) {
    const int edge_n_wanted = static_cast<int>(std::lround(params.edge_share * quota[z]));
    const int edge_n = std::min(static_cast<int>(edge_pixels[z].size()),
                                std::max(edge_n_wanted, quota[z] - static_cast<int>(inner_pixels[z].size())));
    picked.clear();
    draw(edge_pixels[z], edge_n, rng, picked);
    draw(inner_pixels[z], quota[z] - edge_n, rng, picked);
    for (size_t k = 0; k < picked.size(); ++k) {
      const int i = picked[k];
      DepthSample s;
      s.col = i % cloud.width;
      s.row = i / cloud.width;
      s.zone = BodyZone(z);
      s.near_edge = static_cast<int>(k) < edge_n;
      s.p_K = cloud.value_K[static_cast<size_t>(i)];
      samples.push_back(s);
    }
  }
  return samples;
}

}  // namespace posefuse::fit
