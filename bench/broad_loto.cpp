#include "broad_loto.hpp"

#include <cstdio>
#include <limits>

#include "common/error.hpp"

namespace posefuse::bench {

namespace {
constexpr double kDeg = 3.14159265358979323846 / 180.0;
}

std::vector<GridAxis> robust_tuned_axes() {
  // The values bracket the defaults by about a factor of two each way: the range over which
  // the defaults were moved by hand (docs/imu-robust.md).
  return {
      {"tau_acc_s", &RobustParams::tau_acc_s, {2.0, 4.0, 8.0}, 1.0, "s"},
      {"tau_mag_s", &RobustParams::tau_mag_s, {10.0, 20.0, 40.0}, 1.0, "s"},
      {"mag_norm_threshold", &RobustParams::mag_norm_threshold, {0.07, 0.1, 0.15}, 1.0, ""},
      {"mag_dip_threshold",
       &RobustParams::mag_dip_threshold_rad,
       {7.0 * kDeg, 10.0 * kDeg, 15.0 * kDeg},
       1.0 / kDeg,
       "deg"},
      {"mag_accept_after_s", &RobustParams::mag_accept_after_s, {0.25, 0.5, 1.0}, 1.0, "s"},
      {"mag_new_field_s", &RobustParams::mag_new_field_s, {5.0, 10.0, 20.0}, 1.0, "s"},
  };
}

std::size_t grid_size(const std::vector<GridAxis>& axes) {
  std::size_t n = 1;
  for (const GridAxis& axis : axes) n *= axis.values.size();
  return n;
}

RobustParams grid_point(const std::vector<GridAxis>& axes, std::size_t index, const RobustParams& base) {
  if (index >= grid_size(axes)) throw_invalid("grid index", std::to_string(index) + " is outside the grid");
  RobustParams p = base;
  for (const GridAxis& axis : axes) {
    p.*axis.member = axis.values[index % axis.values.size()];
    index /= axis.values.size();
  }
  return p;
}

std::string describe_grid_point(const std::vector<GridAxis>& axes, std::size_t index) {
  std::string out;
  for (const GridAxis& axis : axes) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%s%s=%g", out.empty() ? "" : " ", axis.name,
                  axis.values[index % axis.values.size()] * axis.display_scale);
    out += buf;
    index /= axis.values.size();
  }
  return out;
}

namespace {

// Mean of score[t][point] over all trials but `skip` (skip = trials.size(): none skipped).
double mean_without(const std::vector<std::vector<double>>& score, std::size_t point, std::size_t skip) {
  double sum = 0.0;
  std::size_t n = 0;
  for (std::size_t t = 0; t < score.size(); ++t) {
    if (t == skip) continue;
    sum += score[t][point];
    ++n;
  }
  return sum / static_cast<double>(n);
}

std::size_t best_without(const std::vector<std::vector<double>>& score, std::size_t skip, double* mean) {
  std::size_t best = 0;
  double best_mean = std::numeric_limits<double>::infinity();
  for (std::size_t point = 0; point < score.front().size(); ++point) {
    const double m = mean_without(score, point, skip);
    if (m < best_mean) {
      best_mean = m;
      best = point;
    }
  }
  if (mean != nullptr) *mean = best_mean;
  return best;
}

void check_scores(const std::vector<std::vector<double>>& score, std::size_t min_trials) {
  if (score.size() < min_trials) throw_invalid("score", "needs at least " + std::to_string(min_trials) + " trials");
  for (const auto& row : score) {
    if (row.empty() || row.size() != score.front().size()) throw_invalid("score", "rows must have one equal size > 0");
  }
}

}  // namespace

std::vector<Fold> leave_one_trial_out(const std::vector<std::vector<double>>& score) {
  check_scores(score, 2);
  std::vector<Fold> folds;
  for (std::size_t t = 0; t < score.size(); ++t) {
    Fold f;
    f.held_out = t;
    f.chosen = best_without(score, t, &f.training_mean);
    f.held_out_score = score[t][f.chosen];
    folds.push_back(f);
  }
  return folds;
}

std::size_t best_in_sample(const std::vector<std::vector<double>>& score, double* mean) {
  check_scores(score, 1);
  return best_without(score, score.size(), mean);
}

}  // namespace posefuse::bench
