#pragma once
// Writes a Fit call's results into an output directory as they arrive:
//   imu_orientations/<device_id>.csv   t_us,w,x,y,z   (W_from_A per IMU sample, device clock)
//   forearm_orientations/<device_id>.csv  t_us,w,x,y,z,pronation_rad  (K_from_F per arm IMU
//                                      sample, camera clock; pronation + / supination -)
//   imu_positions.csv                  t_us,device_id,x_m,y_m,z_m,source  (p_K per camera frame;
//                                      source VISUAL (strap seen) or PREDICTED (live, in a gap))
//   recovered_segments.csv             device_id,method,t_start_us,t_end_us,t_us,imu_x_m,imu_y_m,
//                                      imu_z_m,elbow_x_m,elbow_y_m,elbow_z_m,wrist_x_m,wrist_y_m,
//                                      wrist_z_m,w,x,y,z  (one row per recovered sample; method
//                                      PAPER or SMOOTHER; K_from_F as w x y z)
//   calibration.json                   the CalibrationReport (protobuf JSON, .proto names)
//   summary.json                       the Summary
//   warnings.txt                       one line per Warning or ItemError
// The forearm CSV files appear only when the session produced such results. Body-model joints
// are added here when the fitting stage lands.
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
  std::uint64_t forearm_samples() const { return forearm_samples_; }
  std::uint64_t imu_positions() const { return imu_positions_; }
  std::uint64_t recovered_segments() const { return recovered_segments_; }
  const std::filesystem::path& directory() const { return directory_; }

 private:
  void write_orientations(const v1::ImuOrientationBatch& batch);
  void write_forearm_orientations(const v1::ForearmOrientationBatch& batch);
  void write_frame(const v1::FrameResult& frame);
  void write_segment(const v1::RecoveredSegment& segment);
  void note(const std::string& kind, const std::string& code, const std::string& field,
            const std::string& message);

  std::filesystem::path directory_;
  std::map<std::string, std::unique_ptr<session::CsvWriter>> orientations_;
  std::map<std::string, std::unique_ptr<session::CsvWriter>> forearm_orientations_;
  std::unique_ptr<session::CsvWriter> imu_positions_file_;
  std::unique_ptr<session::CsvWriter> segments_file_;
  std::unique_ptr<std::ofstream> warnings_file_;
  v1::Summary summary_;
  bool have_summary_ = false;
  std::uint64_t warnings_ = 0;
  std::uint64_t item_errors_ = 0;
  std::uint64_t orientation_samples_ = 0;
  std::uint64_t forearm_samples_ = 0;
  std::uint64_t imu_positions_ = 0;
  std::uint64_t recovered_segments_ = 0;
};

}  // namespace posefuse::client
