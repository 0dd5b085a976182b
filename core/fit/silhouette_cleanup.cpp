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

// A bone between two usable joints, in K, with the box its capsule of radius r fits in.
struct BoneSegment {
  Eigen::Vector3f a, ab;
  float len2;
  Eigen::Vector3f box_min, box_max;
};

std::vector<BoneSegment> usable_bones(const TrackedSkeleton& skeleton, float r) {
  std::vector<BoneSegment> bones;
  for (const ZoneBone& bone : kZoneBones) {
    if (!joint_unusable_reason(skeleton, bone.from, /*accept_inferred=*/true).empty() ||
        !joint_unusable_reason(skeleton, bone.to, /*accept_inferred=*/true).empty())
      continue;
    const Eigen::Vector3f a = skeleton.positions_K[static_cast<size_t>(bone.from)].cast<float>();
    const Eigen::Vector3f ab = skeleton.positions_K[static_cast<size_t>(bone.to)].cast<float>() - a;
    const Eigen::Vector3f b = a + ab;
    bones.push_back({a, ab, ab.squaredNorm(), a.cwiseMin(b).array() - r, a.cwiseMax(b).array() + r});
  }
  return bones;
}

// Whether p lies within r of the bone (r^2 = r2); the box test passes over most bones.
bool near_bone(const Eigen::Vector3f& p, const BoneSegment& s, float r2) {
  if ((p.array() < s.box_min.array()).any() || (p.array() > s.box_max.array()).any()) return false;
  const float t = s.len2 > 0 ? std::clamp((p - s.a).dot(s.ab) / s.len2, 0.0f, 1.0f) : 0.0f;
  return (s.a + t * s.ab - p).squaredNorm() <= r2;
}

// Which body pixels of `box` are inside the silhouette: every pixel within kRingPx rows and
// columns is body too. Row-major over the box; a square's test is a row pass and a column pass
// of running counts over the box padded with background.
std::vector<uint8_t> inner_pixels(const DepthFrame& frame, const PixelRect& box) {
  constexpr int k = kRingPx, span = 2 * kRingPx + 1;
  const int bw = box.col1 - box.col0 + 1, bh = box.row1 - box.row0 + 1, pw = bw + 2 * k;
  // Body mask of the box with k background pixels on each side; the image's border counts as
  // background.
  std::vector<uint8_t> mask(static_cast<size_t>(pw) * bh, 0);
  for (int r = 0; r < bh; ++r) {
    const uint8_t* body = frame.body_index.data() + static_cast<size_t>(box.row0 + r) * frame.width + box.col0;
    uint8_t* m = mask.data() + static_cast<size_t>(r) * pw + k;
    for (int c = 0; c < bw; ++c) m[c] = body[c] != kNoBody;
  }
  // Rows padded with k empty rows above and below.
  std::vector<uint8_t> full_row(static_cast<size_t>(bw) * (bh + 2 * k), 0);
  for (int r = 0; r < bh; ++r) {
    const uint8_t* m = mask.data() + static_cast<size_t>(r) * pw;
    uint8_t* f = full_row.data() + static_cast<size_t>(r + k) * bw;
    int run = 0;
    for (int c = 0; c < span - 1; ++c) run += m[c];
    for (int c = 0; c < bw; ++c) {
      run += m[c + span - 1];
      f[c] = run == span;
      run -= m[c];
    }
  }
  std::vector<uint8_t> inner(static_cast<size_t>(bw) * bh, 0);
  std::vector<uint8_t> run(static_cast<size_t>(bw), 0);
  for (int r = 0; r < span - 1; ++r)
    for (int c = 0; c < bw; ++c) run[c] += full_row[static_cast<size_t>(r) * bw + c];
  for (int r = 0; r < bh; ++r) {
    const uint8_t* enter = full_row.data() + static_cast<size_t>(r + span - 1) * bw;
    const uint8_t* leave = full_row.data() + static_cast<size_t>(r) * bw;
    uint8_t* out = inner.data() + static_cast<size_t>(r) * bw;
    for (int c = 0; c < bw; ++c) {
      run[c] += enter[c];
      out[c] = run[c] == span;
      run[c] -= leave[c];
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
                     static_cast<size_t>(frame.width) * frame.height == n &&
                     frame.body_index.size() == frame.depth_mm.size();
  const float radius = static_cast<float>(options.depth_margin_m), radius2 = radius * radius;
  const std::vector<BoneSegment> bones = whole ? usable_bones(skeleton, radius) : std::vector<BoneSegment>{};
  const PixelRect box =
      bones.empty() ? PixelRect{} : occupied_box(frame.body_index, frame.width, frame.height, kNoBody);
  const std::vector<uint8_t> inner = box.empty() ? std::vector<uint8_t>{} : inner_pixels(frame, box);

  const double near_mm = 1000.0 * (min_z - options.depth_margin_m), far_mm = 1000.0 * (max_z + options.depth_margin_m);
  std::size_t removed = 0;
  uint8_t* body = frame.body_index.data();
  const uint16_t* depth = frame.depth_mm.data();
  // Removes pixel i when its depth is out of range or, for a ring pixel (col, row), far from every
  // bone.
  const auto test = [&](std::size_t i, bool ring, int col, int row) {
    if (body[i] == kNoBody || depth[i] == kNoDepth) return;
    const double z_mm = depth[i];
    bool off_body = z_mm < near_mm || z_mm > far_mm;
    if (!off_body && ring) {
      const Eigen::Vector3f p = camera->pixel_ray(col, row) * static_cast<float>(0.001 * z_mm);
      off_body =
          std::none_of(bones.begin(), bones.end(), [&](const BoneSegment& b) { return near_bone(p, b, radius2); });
    }
    if (off_body) {
      body[i] = kNoBody;
      ++removed;
    }
  };
  if (inner.empty()) {
    for (std::size_t i = 0; i < n;) {
      if (i + 8 <= n && background_word(body + i)) {
        i += 8;
        continue;
      }
      for (const std::size_t end = std::min(n, i + 8); i < end; ++i) test(i, false, 0, 0);
    }
    return removed;
  }
  // Every body pixel lies in the box.
  const int box_width = box.col1 - box.col0 + 1;
  for (int row = box.row0; row <= box.row1; ++row) {
    const uint8_t* inner_row = inner.data() + static_cast<size_t>(row - box.row0) * box_width;
    for (int col = box.col0; col <= box.col1; ++col)
      test(static_cast<size_t>(row) * frame.width + col, !inner_row[col - box.col0], col, row);
  }
  return removed;
}

}  // namespace posefuse::fit
