#pragma once
// Writes a Fit call's results into an output directory as they arrive:
//   imu_orientations/<device_id>.csv   t_us,w,x,y,z   (W_from_A per IMU sample, device clock)
//   calibration.json                   the CalibrationReport (protobuf JSON, .proto names)
//   summary.json                       the Summary
//   warnings.txt                       one line per Warning or ItemError
// Frame results and recovered segments are added here when the stages that make them land.
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <string>

#include "posefuse/v1/results.pb.h"
#include "session/text_fields.hpp"

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
  std::uint64_t orientation_samples() const { return orientation_samples_; }
  const std::filesystem::path& directory() const { return directory_; }

 private:
  void write_orientations(const v1::ImuOrientationBatch& batch);
  void note(const std::string& kind, const std::string& code, const std::string& field,
            const std::string& message);

  std::filesystem::path directory_;
  std::map<std::string, std::unique_ptr<session::CsvWriter>> orientations_;
  std::unique_ptr<std::ofstream> warnings_file_;
  v1::Summary summary_;
  bool have_summary_ = false;
  std::uint64_t warnings_ = 0;
  std::uint64_t item_errors_ = 0;
  std::uint64_t orientation_samples_ = 0;
};

}  // namespace posefuse::client
