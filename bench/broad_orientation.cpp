// Orientation accuracy and speed on BROAD trials (../shared/data/broad/README.md).
//
//   bench_broad_orientation [--mode NAME] [--csv-out DIR] FOLDER
//
// Runs every *.hdf5 trial in FOLDER (sorted by name) through one filter mode with one parameter
// set, and prints per trial the RMSE of the total / heading / inclination error (degrees, over
// movement = 1 samples with ground truth) and the filter's speed (single thread, filter time
// only, measured as this thread's CPU time), then the mean over trials. The ground truth is read only to score.
#include <algorithm>
#include <cstdlib>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "bench_clock.hpp"
#include "broad_trial.hpp"
#include "common/error.hpp"
#include "eval/orientation_error.hpp"
#include "geometry/frames.hpp"
#include "imu/robust_offline.hpp"
#include "imu/kalman_orientation_filter.hpp"
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
  std::fprintf(to, "usage: bench_broad_orientation [--mode NAME] [--csv-out DIR] [--tau-acc S] FOLDER\n"
                  "  --tau-acc S: the robust mode's accelerometer time constant (default %.1f s)\nmodes:\n",
               posefuse::imu::RobustOrientationFilter::Params().tau_acc_s);
  for (const Mode& m : modes()) std::fprintf(to, "  %-16s %s\n", m.name, m.summary);
}

void write_csv(const fs::path& file, const std::vector<ImuSample>& imu, const std::vector<Quat>& ENU_from_A) {
  std::FILE* f = std::fopen(file.c_str(), "w");
  if (f == nullptr) throw posefuse::Error(posefuse::ErrorCode::kNotFound, file.string(), "cannot write");
  std::fprintf(f, "t_s,w,x,y,z\n");
  for (std::size_t i = 0; i < imu.size(); ++i) {
    const Quat& q = ENU_from_A[i];
    std::fprintf(f, "%.6f,%.9f,%.9f,%.9f,%.9f\n", 1e-6 * static_cast<double>(imu[i].t_us), q.w(), q.x(), q.y(),
                 q.z());
  }
  if (std::fclose(f) != 0) throw posefuse::Error(posefuse::ErrorCode::kDataLoss, file.string(), "write failed");
}

int run(int argc, char** argv) {
  std::string mode_name = "robust";
  std::string csv_dir;
  std::string folder;
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

    std::vector<Quat> ENU_from_A(W_from_A.size());
    const Quat ENU_from_W = posefuse::geometry::ENU_from_W();
    for (std::size_t i = 0; i < W_from_A.size(); ++i) ENU_from_A[i] = ENU_from_W * W_from_A[i];
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
  std::printf("%-46s %8.3f %8.3f %8.3f %9zu %10.2f\n", ("mean over " + std::to_string(files.size()) + " trials").c_str(),
              sum_total / n, sum_heading / n, sum_incl / n, sum_samples, sum_rate / n);
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
