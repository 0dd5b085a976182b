#include "fit/silhouette_cleanup.hpp"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

namespace posefuse::fit {

namespace {

// Pixels of the outer ring: body pixels with a background pixel (or the image's border) within
// kRingPx rows and columns, as the body index lies 1-2 px off the depth (silhouette_cleanup.hpp).
constexpr int kRingPx = 2;

// A bone between two usable joints, in K.
struct BoneSegment {
  Eigen::Vector3f a, ab;
  float len2;
};

std::vector<BoneSegment> usable_bones(const TrackedSkeleton& skeleton) {
  std::vector<BoneSegment> bones;
  for (const ZoneBone& bone : kZoneBones) {
    if (!joint_unusable_reason(skeleton, bone.from, /*accept_inferred=*/true).empty() ||
        !joint_unusable_reason(skeleton, bone.to, /*accept_inferred=*/true).empty())
      continue;
    const Eigen::Vector3f a = skeleton.positions_K[static_cast<size_t>(bone.from)].cast<float>();
    const Eigen::Vector3f ab = skeleton.positions_K[static_cast<size_t>(bone.to)].cast<float>() - a;
    bones.push_back({a, ab, ab.squaredNorm()});
  }
  return bones;
}

float distance2_to_bone(const Eigen::Vector3f& p, const BoneSegment& s) {
  const float t = s.len2 > 0 ? std::clamp((p - s.a).dot(s.ab) / s.len2, 0.0f, 1.0f) : 0.0f;
  return (s.a + t * s.ab - p).squaredNorm();
}

// The smallest rectangle holding every body pixel (empty when none).
PixelRect body_box(const DepthFrame& frame) {
  PixelRect box{frame.width, frame.height, -1, -1};
  for (int row = 0; row < frame.height; ++row) {
    const uint8_t* body = frame.body_index.data() + static_cast<size_t>(row) * frame.width;
    for (int col = 0; col < frame.width; ++col) {
      if (col + 8 <= frame.width && background_word(body + col)) {
        col += 7;
        continue;
      }
      if (body[col] == kNoBody) continue;
      box = {std::min(box.col0, col), std::min(box.row0, row), std::max(box.col1, col), std::max(box.row1, row)};
    }
  }
  return box;
}

// Which body pixels of `box` are inside the silhouette: every pixel within kRingPx rows and
// columns is body too. Row-major over the box; a square's test is a row pass and a column pass
// of running counts.
std::vector<uint8_t> inner_pixels(const DepthFrame& frame, const PixelRect& box) {
  const int bw = box.col1 - box.col0 + 1, bh = box.row1 - box.row0 + 1, span = 2 * kRingPx + 1;
  const auto is_body = [&](int col, int row) {
    return col >= 0 && col < frame.width && frame.body_index[static_cast<size_t>(row) * frame.width + col] != kNoBody;
  };
  std::vector<uint8_t> full_row(static_cast<size_t>(bw) * bh, 0);
  for (int r = 0; r < bh; ++r) {
    const int row = box.row0 + r;
    int run = 0;  // body pixels in columns [col - kRingPx, col + kRingPx]
    for (int col = box.col0 - kRingPx; col < box.col0 + kRingPx; ++col) run += is_body(col, row);
    for (int c = 0; c < bw; ++c) {
      const int col = box.col0 + c;
      run += is_body(col + kRingPx, row);
      full_row[static_cast<size_t>(r) * bw + c] = run == span;
      run -= is_body(col - kRingPx, row);
    }
  }
  // Rows outside the box hold no body pixel.
  std::vector<uint8_t> inner(full_row.size(), 0);
  const auto full = [&](int r, int c) { return r >= 0 && r < bh && full_row[static_cast<size_t>(r) * bw + c]; };
  for (int c = 0; c < bw; ++c) {
    int run = 0;
    for (int r = -kRingPx; r < kRingPx; ++r) run += full(r, c);
    for (int r = 0; r < bh; ++r) {
      run += full(r + kRingPx, c);
      inner[static_cast<size_t>(r) * bw + c] = run == span;
      run -= full(r - kRingPx, c);
    }
  }
  return inner;
}

}  // namespace

std::size_t remove_off_body_depth(DepthFrame& frame, const TrackedSkeleton& skeleton,
                                  const SilhouetteCleanupOptions& options, const raycast::DepthCamera* camera) {
  double min_z = std::numeric_limits<double>::infinity(), max_z = -min_z;
  for (int j = 0; j < kKinectJointCount; ++j) {
    if (!joint_unusable_reason(skeleton, j, /*accept_inferred=*/true).empty()) continue;
    const double z = skeleton.positions_K[static_cast<size_t>(j)].z();
    min_z = std::min(min_z, z);
    max_z = std::max(max_z, z);
  }
  if (!(min_z <= max_z)) return 0;
  const std::size_t n = std::min(frame.depth_mm.size(), frame.body_index.size());
  // The ring's test needs whole images of the camera's size.
  const bool whole = camera != nullptr && camera->width() == frame.width && camera->height() == frame.height &&
                     frame.width > 0 && static_cast<size_t>(frame.width) * frame.height == n &&
                     frame.body_index.size() == frame.depth_mm.size();
  const std::vector<BoneSegment> bones = whole ? usable_bones(skeleton) : std::vector<BoneSegment>{};
  const PixelRect box = bones.empty() ? PixelRect{} : body_box(frame);
  const std::vector<uint8_t> inner = box.empty() ? std::vector<uint8_t>{} : inner_pixels(frame, box);
  const int box_width = box.col1 - box.col0 + 1;
  const float radius2 = static_cast<float>(options.depth_margin_m * options.depth_margin_m);

  const double near_mm = 1000.0 * (min_z - options.depth_margin_m), far_mm = 1000.0 * (max_z + options.depth_margin_m);
  std::size_t removed = 0;
  uint8_t* body = frame.body_index.data();
  const uint16_t* depth = frame.depth_mm.data();
  for (std::size_t i = 0; i < n;) {
    if (i + 8 <= n && background_word(body + i)) {
      i += 8;
      continue;
    }
    for (const std::size_t end = std::min(n, i + 8); i < end; ++i) {
      if (body[i] == kNoBody || depth[i] == kNoDepth) continue;
      const double z_mm = depth[i];
      bool off_body = z_mm < near_mm || z_mm > far_mm;
      if (!off_body && !inner.empty()) {
        const int col = static_cast<int>(i % static_cast<size_t>(frame.width)),
                  row = static_cast<int>(i / static_cast<size_t>(frame.width));
        if (!inner[static_cast<size_t>(row - box.row0) * box_width + (col - box.col0)]) {
          const Eigen::Vector3f p = camera->pixel_ray(col, row) * static_cast<float>(0.001 * z_mm);
          off_body = std::none_of(bones.begin(), bones.end(),
                                  [&](const BoneSegment& b) { return distance2_to_bone(p, b) <= radius2; });
        }
      }
      if (off_body) {
        body[i] = kNoBody;
        ++removed;
      }
    }
  }
  return removed;
}

}  // namespace posefuse::fit
