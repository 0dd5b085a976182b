#pragma once
// Writes a Fit call's results into an output directory as they arrive:
//   imu_orientations/, forearm_orientations/, forearm_orientations_offline/, smpl_joints.csv,
//   camera_joints.csv, forearms.csv,
//   imu_positions.csv, recovered_segments.csv, calibration.json
//                       through session::ResultFiles (session/result_files.hpp, which lists the
//                       columns), the same code path that writes the simulator's ground truth (gt/)
//   summary.json        the Summary
//   warnings.txt        one line per Warning or ItemError
// A file appears only when the session produced such results.
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>

#include "posefuse/v1/results.pb.h"
#include "session/pipeline_stage.hpp"
#include "session/result_files.hpp"

namespace posefuse::client {

class ResultWriter {
 public:
  // Creates `directory` (and parents) if needed; existing result files are replaced.
  explicit ResultWriter(const std::filesystem::path& directory);
  ~ResultWriter();

  void write(const v1::FitResult& result);
  // Flushes and closes every file; throws kDataLoss when something could not be written.
  void finish();

  const v1::Summary* summary() const { return have_summary_ ? &summary_ : nullptr; }
  std::uint64_t warnings() const { return warnings_; }
  std::uint64_t item_errors() const { return item_errors_; }
  std::uint64_t orientation_samples() const { return files_.orientation_samples(); }
  std::uint64_t forearm_samples() const { return files_.forearm_samples(); }
  std::uint64_t offline_forearm_samples() const { return files_.offline_forearm_samples(); }
  std::uint64_t imu_positions() const { return files_.imu_positions(); }
  std::uint64_t recovered_segments() const { return files_.recovered_segments(); }
  const std::filesystem::path& directory() const { return directory_; }

 private:
  void note(const std::string& kind, const std::string& code, const std::string& field, const std::string& message);

  std::filesystem::path directory_;
  session::ResultFiles files_;
  std::unique_ptr<std::ofstream> warnings_file_;
  v1::Summary summary_;
  bool have_summary_ = false;
  std::uint64_t warnings_ = 0;
  std::uint64_t item_errors_ = 0;
};

// Hands every result a SessionPipeline emits to a ResultWriter (what `posefuse fit` does with
// the server's stream), for running the pipeline in process (tests, benchmarks).
class ResultWriterSink : public session::ResultSink {
 public:
  explicit ResultWriterSink(ResultWriter& writer) : writer_(writer) {}
  void emit(v1::FitResult&& result) override { writer_.write(result); }

 private:
  ResultWriter& writer_;
};

}  // namespace posefuse::client
