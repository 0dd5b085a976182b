#pragma once
// Leave-one-trial-out validation of the robust filter's parameter choices on BROAD.
//
// Every parameter that was chosen by looking at BROAD scores is an axis of a grid. Each trial is
// scored with every grid point; then, for each fold, the grid point with the best mean over the
// other trials is chosen and scored on the held-out trial. The mean of the held-out scores is
// what a stranger with other trials should expect; the in-sample mean (one choice for all
// trials, scored on the same trials) is printed beside it. docs/benchmarks.md reports both.
#include <cstddef>
#include <string>
#include <vector>

#include "imu/robust_orientation_filter.hpp"

namespace posefuse::bench {

using RobustParams = imu::RobustOrientationFilter::Params;

// One tuned parameter and the values it may take (in the Params' own units).
struct GridAxis {
  const char* name;
  double RobustParams::*member;
  std::vector<double> values;
  double display_scale;  // printed value = stored value * display_scale (rad -> deg)
  const char* display_unit;
};

// The parameters that were tuned on BROAD, each over the values that were tried by hand.
std::vector<GridAxis> robust_tuned_axes();

// Number of grid points: the product of the axes' sizes.
std::size_t grid_size(const std::vector<GridAxis>& axes);

// Grid point `index` (mixed radix over the axes, the first axis fastest) applied to `base`.
RobustParams grid_point(const std::vector<GridAxis>& axes, std::size_t index, const RobustParams& base);

// "tau_acc_s=4 tau_mag_s=20 ..." for grid point `index`.
std::string describe_grid_point(const std::vector<GridAxis>& axes, std::size_t index);

struct Fold {
  std::size_t held_out = 0;     // trial index
  std::size_t chosen = 0;       // grid point chosen on the other trials
  double held_out_score = 0.0;  // the chosen point's score on the held-out trial
  double training_mean = 0.0;   // the chosen point's mean over the other trials
};

// score[trial][point]: lower is better. One fold per trial (needs at least two trials); ties go
// to the lower grid index.
std::vector<Fold> leave_one_trial_out(const std::vector<std::vector<double>>& score);

// The grid point with the best mean over all trials, and that mean.
std::size_t best_in_sample(const std::vector<std::vector<double>>& score, double* mean = nullptr);

}  // namespace posefuse::bench
