#include "eval/skeleton_errors.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>

#include "common/error.hpp"

namespace posefuse::eval {

namespace {

void check(const std::vector<Vec3>& errors, double off_track_m, int half_window) {
  if (!(std::isfinite(off_track_m) && off_track_m > 0.0)) {
    throw_invalid("off_track_m", "is " + std::to_string(off_track_m) + ", must be > 0");
  }
  if (half_window < 1) throw_invalid("half_window", "is " + std::to_string(half_window) + ", must be >= 1");
  for (std::size_t i = 0; i < errors.size(); ++i) {
    if (!errors[i].allFinite()) throw_invalid("errors[" + std::to_string(i) + "]", "is not finite");
  }
}

}  // namespace

std::vector<bool> off_track_frames(const std::vector<Vec3>& errors, double off_track_m, int half_window) {
  check(errors, off_track_m, half_window);
  const long n = static_cast<long>(errors.size());
  std::vector<bool> off(errors.size(), false);
  std::vector<double> window;
  for (long i = 0; i < n; ++i) {
    const long lo = std::max(0L, i - half_window), hi = std::min(n - 1, i + half_window);
    Vec3 median;
    for (int axis = 0; axis < 3; ++axis) {
      window.clear();
      for (long k = lo; k <= hi; ++k) window.push_back(errors[static_cast<std::size_t>(k)][axis]);
      const std::size_t mid = window.size() / 2;
      std::nth_element(window.begin(), window.begin() + static_cast<long>(mid), window.end());
      double m = window[mid];
      if (window.size() % 2 == 0) {  // even (at the ends): the mean of the two middle values
        m = 0.5 * (m + *std::max_element(window.begin(), window.begin() + static_cast<long>(mid)));
      }
      median[axis] = m;
    }
    off[static_cast<std::size_t>(i)] = (errors[static_cast<std::size_t>(i)] - median).norm() > off_track_m;
  }
  return off;
}

JointErrorStats joint_error_stats(const std::vector<Vec3>& errors, double off_track_m, int half_window) {
  const std::vector<bool> off = off_track_frames(errors, off_track_m, half_window);
  JointErrorStats s;
  s.frames = errors.size();
  if (errors.empty()) {
    s.bias_m = s.spread_m = s.mean_abs_m = std::numeric_limits<double>::quiet_NaN();
    return s;
  }
  Vec3 mean = Vec3::Zero();
  for (const Vec3& e : errors) {
    mean += e;
    s.mean_abs_m += e.norm();
  }
  const double n = static_cast<double>(errors.size());
  mean /= n;
  s.mean_abs_m /= n;
  s.bias_m = mean.norm();
  double sum_sq = 0.0;
  for (const Vec3& e : errors) sum_sq += (e - mean).squaredNorm();
  s.spread_m = std::sqrt(sum_sq / n);
  s.off_track_frames = static_cast<std::size_t>(std::count(off.begin(), off.end(), true));
  return s;
}

}  // namespace posefuse::eval
