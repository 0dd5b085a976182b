// Orientation accuracy and speed on BROAD trials (../shared/data/broad/README.md).
//
//   bench_broad_orientation [--mode NAME] [--csv-out DIR] FOLDER
//   bench_broad_orientation --loto [--mode robust|robust-offline] [--threads N] FOLDER
//
// Runs every *.hdf5 trial in FOLDER (sorted by name) through one filter mode with one parameter
// set, and prints per trial the RMSE of the total / heading / inclination error (degrees, over
// movement = 1 samples with ground truth) and the filter's speed (single thread, filter time
// only, measured as this thread's CPU time), then the mean over trials. The ground truth is read only to score.
//
// --loto: leave-one-trial-out validation of the robust filter's tuned parameters (broad_loto.hpp):
// every trial scored (mean total RMSE) at every point of the grid of tuned parameters, then per
// fold the point best on the other trials scored on the held-out one.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <functional>
#include <string>
#include <thread>
#include <vector>

#include "bench_clock.hpp"
#include "broad_loto.hpp"
#include "broad_trial.hpp"
#include "common/error.hpp"
#include "eval/orientation_error.hpp"
#include "geometry/frames.hpp"
#include "imu/kalman_orientation_filter.hpp"
#include "imu/robust_offline.hpp"
#include "imu/robust_orientation_filter.hpp"

namespace {

using posefuse::geometry::Quat;
using posefuse::imu::ImuSample;
namespace fs = std::filesystem;

// One selectable filter: writes W_from_A for every sample of a whole recording into an output
// that already has one entry per sample (allocated outside the timed region).
struct Mode {
  const char* name;
  const char* summary;
  std::function<void(const std::vector<ImuSample>&, std::vector<Quat>&)> run;
};

// A causal filter with `Quat update(const ImuSample&)`, default-constructed, fed sample by sample.
template <typename Filter>
void run_causal(const std::vector<ImuSample>& samples, std::vector<Quat>& W_from_A) {
  Filter filter;
  for (std::size_t i = 0; i < samples.size(); ++i) W_from_A[i] = filter.update(samples[i]);
}

// The robust filter's parameters for the robust mode (--tau-acc changes them).
posefuse::imu::RobustOrientationFilter::Params& robust_params() {
  static posefuse::imu::RobustOrientationFilter::Params params;
  return params;
}

// Add new filters here.
const std::vector<Mode>& modes() {
  static const std::vector<Mode> table = {
      {"faithful", "paper 1's quaternion Kalman filter and gyro bias test (default parameters)",
       run_causal<posefuse::imu::KalmanOrientationFilter>},
      {"faithful-gated", "the same Kalman filter; bias test also needs |rate - bias| < 3 deg/s",
       [](const std::vector<ImuSample>& s, std::vector<Quat>& W_from_A) {
         posefuse::imu::KalmanOrientationFilter::Params params;
         params.gyro_bias.max_still_rate_rad_s = 3.0 * EIGEN_PI / 180.0;
         posefuse::imu::KalmanOrientationFilter filter(params);
         for (std::size_t i = 0; i < s.size(); ++i) W_from_A[i] = filter.update(s[i]);
       }},
      {"robust", "RobustOrientationFilter, causal (default parameters but --tau-acc)",
       [](const std::vector<ImuSample>& s, std::vector<Quat>& W_from_A) {
         posefuse::imu::RobustOrientationFilter filter(robust_params());
         for (std::size_t i = 0; i < s.size(); ++i) W_from_A[i] = filter.update(s[i]);
       }},
      {"robust-offline", "robust filter, forward+backward passes over the whole recording (non-causal)",
       [](const std::vector<ImuSample>& s, std::vector<Quat>& W_from_A) {
         W_from_A = posefuse::imu::robust_orientation_offline(s);
       }},
  };
  return table;
}

void print_usage(std::FILE* to) {
  std::fprintf(to,
               "usage: bench_broad_orientation [--mode NAME] [--csv-out DIR] [--tau-acc S] FOLDER\n"
               "       bench_broad_orientation --loto [--mode robust|robust-offline] [--threads N] FOLDER\n"
               "  --tau-acc S: the robust mode's accelerometer time constant (default %.1f s)\n"
               "  --loto: leave-one-trial-out validation of the robust filter's tuned parameters\nmodes:\n",
               posefuse::imu::RobustOrientationFilter::Params().tau_acc_s);
  for (const Mode& m : modes()) std::fprintf(to, "  %-16s %s\n", m.name, m.summary);
}

void write_csv(const fs::path& file, const std::vector<ImuSample>& imu, const std::vector<Quat>& ENU_from_A) {
  std::FILE* f = std::fopen(file.c_str(), "w");
  if (f == nullptr) throw posefuse::Error(posefuse::ErrorCode::kNotFound, file.string(), "cannot write");
  std::fprintf(f, "t_s,w,x,y,z\n");
  for (std::size_t i = 0; i < imu.size(); ++i) {
    const Quat& q = ENU_from_A[i];
    std::fprintf(f, "%.6f,%.9f,%.9f,%.9f,%.9f\n", 1e-6 * static_cast<double>(imu[i].t_us), q.w(), q.x(), q.y(), q.z());
  }
  if (std::fclose(f) != 0) throw posefuse::Error(posefuse::ErrorCode::kDataLoss, file.string(), "write failed");
}

// Total RMSE (degrees) of one trial's W_from_A against its ground truth.
// The estimates in BROAD's frame (sensor -> ENU), as the ground truth and the metric have them.
std::vector<Quat> ENU_from_A_of(const std::vector<Quat>& W_from_A) {
  std::vector<Quat> ENU_from_A(W_from_A.size());
  const Quat ENU_from_W = posefuse::geometry::ENU_from_W();
  for (std::size_t i = 0; i < W_from_A.size(); ++i) ENU_from_A[i] = ENU_from_W * W_from_A[i];
  return ENU_from_A;
}

double total_rmse_deg(const posefuse::bench::BroadTrial& trial, const std::vector<Quat>& W_from_A) {
  return posefuse::eval::orientation_rmse(ENU_from_A_of(W_from_A), trial.ENU_from_sensor_gt, trial.movement).total_rad *
         180.0 / EIGEN_PI;
}

// Leave-one-trial-out over the grid of tuned parameters (broad_loto.hpp), for the robust filter
// causal or offline. Scoring runs on `threads` threads, each taking whole grid points.
int run_loto(const std::vector<posefuse::bench::BroadTrial>& trials, bool offline, unsigned threads) {
  using posefuse::bench::RobustParams;
  const std::vector<posefuse::bench::GridAxis> axes = posefuse::bench::robust_tuned_axes();
  const std::size_t points = posefuse::bench::grid_size(axes);
  std::printf("leave-one-trial-out: robust filter %s, %zu trials, %zu grid points over %zu tuned parameters:\n",
              offline ? "offline" : "causal", trials.size(), points, axes.size());
  for (const auto& axis : axes) {
    std::printf("  %-22s", axis.name);
    for (double v : axis.values) std::printf(" %g", v * axis.display_scale);
    std::printf(" %s\n", axis.display_unit);
  }
  std::fflush(stdout);

  std::vector<std::vector<double>> score(trials.size(), std::vector<double>(points, 0.0));
  std::atomic<std::size_t> next{0}, done{0};
  const auto worker = [&] {
    for (std::size_t point = next++; point < points; point = next++) {
      const RobustParams params = posefuse::bench::grid_point(axes, point, RobustParams{});
      for (std::size_t t = 0; t < trials.size(); ++t) {
        std::vector<Quat> W_from_A;
        if (offline) {
          W_from_A = posefuse::imu::robust_orientation_offline(trials[t].imu, params);
        } else {
          posefuse::imu::RobustOrientationFilter filter(params);
          W_from_A.reserve(trials[t].imu.size());
          for (const ImuSample& s : trials[t].imu) W_from_A.push_back(filter.update(s));
        }
        score[t][point] = total_rmse_deg(trials[t], W_from_A);
      }
      const std::size_t n = ++done;
      if (n % 50 == 0 || n == points) std::fprintf(stderr, "  scored %zu / %zu grid points\n", n, points);
    }
  };
  std::vector<std::thread> pool;
  for (unsigned i = 1; i < threads; ++i) pool.emplace_back(worker);
  worker();
  for (std::thread& t : pool) t.join();

  // The defaults are a grid point (every axis holds its default value); find it for the table.
  std::size_t default_point = points;
  for (std::size_t point = 0; point < points; ++point) {
    const RobustParams p = posefuse::bench::grid_point(axes, point, RobustParams{});
    bool same = true;
    for (const auto& axis : axes) {
      const double d = RobustParams{}.*axis.member;
      same = same && std::abs(p.*axis.member - d) <= 1e-9 * std::abs(d);  // defaults spell pi shorter
    }
    if (same) default_point = point;
  }
  if (default_point == points) throw posefuse::Error(posefuse::ErrorCode::kInternal, "grid", "lacks the defaults");

  const auto folds = posefuse::bench::leave_one_trial_out(score);
  std::printf("%-46s %9s %9s %9s  %s\n", "held-out trial", "held-out", "defaults", "training",
              "chosen on the other trials");
  double sum_held = 0.0, sum_default = 0.0, max_held = 0.0;
  std::size_t worst = 0;
  for (const auto& f : folds) {
    const double d = score[f.held_out][default_point];
    std::printf("%-46s %9.3f %9.3f %9.3f  %s\n", trials[f.held_out].name.c_str(), f.held_out_score, d, f.training_mean,
                posefuse::bench::describe_grid_point(axes, f.chosen).c_str());
    sum_held += f.held_out_score;
    sum_default += d;
    if (f.held_out_score > max_held) {
      max_held = f.held_out_score;
      worst = f.held_out;
    }
  }
  const double n = static_cast<double>(trials.size());
  double best_mean = 0.0;
  const std::size_t best = posefuse::bench::best_in_sample(score, &best_mean);
  std::printf("leave-one-trial-out mean total RMSE: %.3f deg (held-out max %.3f, %s)\n", sum_held / n, max_held,
              trials[worst].name.c_str());
  std::printf("in-sample mean, defaults:            %.3f deg\n", sum_default / n);
  std::printf("in-sample mean, best grid point:     %.3f deg (%s)\n", best_mean,
              posefuse::bench::describe_grid_point(axes, best).c_str());
  return 0;
}

int run(int argc, char** argv) {
  std::string mode_name = "robust";
  std::string csv_dir;
  std::string folder;
  bool loto = false;
  unsigned threads = std::max(1u, std::thread::hardware_concurrency());
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--help" || arg == "-h") {
      print_usage(stdout);
      return 0;
    } else if (arg == "--tau-acc" && i + 1 < argc) {
      char* end = nullptr;
      const double tau = std::strtod(argv[++i], &end);
      if (end == argv[i] || *end != '\0' || !(tau > 0.0)) {
        std::fprintf(stderr, "bench_broad_orientation: --tau-acc must be a number of seconds > 0, not '%s'\n", argv[i]);
        return 2;
      }
      robust_params().tau_acc_s = tau;
    } else if (arg == "--loto") {
      loto = true;
    } else if (arg == "--threads" && i + 1 < argc) {
      char* end = nullptr;
      const long n = std::strtol(argv[++i], &end, 10);
      if (end == argv[i] || *end != '\0' || n < 1 || n > 64) {
        std::fprintf(stderr, "bench_broad_orientation: --threads must be 1..64, not '%s'\n", argv[i]);
        return 2;
      }
      threads = static_cast<unsigned>(n);
    } else if ((arg == "--mode" || arg == "--csv-out") && i + 1 < argc) {
      (arg == "--mode" ? mode_name : csv_dir) = argv[++i];
    } else if (!arg.empty() && arg[0] != '-' && folder.empty()) {
      folder = arg;
    } else {
      std::fprintf(stderr, "bench_broad_orientation: unexpected argument '%s'\n", arg.c_str());
      print_usage(stderr);
      return 2;
    }
  }
  if (folder.empty()) {
    print_usage(stderr);
    return 2;
  }
  const auto mode = std::find_if(modes().begin(), modes().end(), [&](const Mode& m) { return m.name == mode_name; });
  if (mode == modes().end()) {
    std::fprintf(stderr, "bench_broad_orientation: unknown mode '%s'\n", mode_name.c_str());
    print_usage(stderr);
    return 2;
  }
  if (!fs::is_directory(folder)) throw posefuse::Error(posefuse::ErrorCode::kNotFound, folder, "not a folder");
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(folder)) {
    if (entry.is_regular_file() && entry.path().extension() == ".hdf5") files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  if (files.empty()) throw posefuse::Error(posefuse::ErrorCode::kNotFound, folder, "no *.hdf5 trials");
  if (loto) {
    if (mode_name != "robust" && mode_name != "robust-offline") {
      std::fprintf(stderr, "bench_broad_orientation: --loto needs --mode robust or robust-offline\n");
      return 2;
    }
    std::vector<posefuse::bench::BroadTrial> trials;
    for (const fs::path& file : files) {
      trials.push_back(posefuse::bench::read_broad_trial(file.string()));
      posefuse::imu::validate_imu_stream(trials.back().imu, trials.back().name.c_str());
    }
    return run_loto(trials, mode_name == "robust-offline", threads);
  }
  if (!csv_dir.empty()) fs::create_directories(csv_dir);

  constexpr double kDeg = 180.0 / EIGEN_PI;
  std::printf("mode: %s (%s)\n", mode->name, mode->summary);
  std::printf("%-46s %8s %8s %8s %9s %10s\n", "trial", "total", "heading", "incl", "samples", "Msamples/s");
  double sum_total = 0, sum_heading = 0, sum_incl = 0, sum_rate = 0;
  std::size_t sum_samples = 0;
  for (const fs::path& file : files) {
    const posefuse::bench::BroadTrial trial = posefuse::bench::read_broad_trial(file.string());
    posefuse::imu::validate_imu_stream(trial.imu, trial.name.c_str());
    std::vector<Quat> W_from_A(trial.imu.size(), Quat::Identity());
    const double start_s = posefuse::bench::thread_cpu_seconds();
    mode->run(trial.imu, W_from_A);
    const double seconds = posefuse::bench::thread_cpu_seconds() - start_s;

    const std::vector<Quat> ENU_from_A = ENU_from_A_of(W_from_A);
    const auto rmse = posefuse::eval::orientation_rmse(ENU_from_A, trial.ENU_from_sensor_gt, trial.movement);
    const double rate = static_cast<double>(trial.imu.size()) / seconds * 1e-6;
    std::printf("%-46s %8.3f %8.3f %8.3f %9zu %10.2f\n", trial.name.c_str(), rmse.total_rad * kDeg,
                rmse.heading_rad * kDeg, rmse.inclination_rad * kDeg, trial.imu.size(), rate);
    sum_total += rmse.total_rad * kDeg;
    sum_heading += rmse.heading_rad * kDeg;
    sum_incl += rmse.inclination_rad * kDeg;
    sum_rate += rate;
    sum_samples += trial.imu.size();
    if (!csv_dir.empty()) write_csv(fs::path(csv_dir) / (trial.name + ".csv"), trial.imu, ENU_from_A);
  }
  const double n = static_cast<double>(files.size());
  std::printf("%-46s %8.3f %8.3f %8.3f %9zu %10.2f\n",
              ("mean over " + std::to_string(files.size()) + " trials").c_str(), sum_total / n, sum_heading / n,
              sum_incl / n, sum_samples, sum_rate / n);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const posefuse::Error& e) {
    std::fprintf(stderr, "bench_broad_orientation: %s (%s)\n", e.what(), posefuse::error_code_name(e.code()));
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_broad_orientation: %s\n", e.what());
    return 1;
  }
}
