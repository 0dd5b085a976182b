#pragma once
// The result files of a fitted session, written by one code path for the client (results
// streamed back by the server) and for the simulator's ground truth (gt/), so that a result
// directory can be scored against a gt/ directory file by file, column by column.
//
//   imu_orientations/<device_id>.csv  t_us,w,x,y,z            W_from_A per IMU sample (device clock)
//   smpl_joints.csv                   t_us,joint,joint_name,x_m,y_m,z_m,source,confidence
//                                     (24 rows per frame, SMPL order, p_K)
//   camera_joints.csv                 the same columns, 25 rows per frame, Kinect v2 JointType order
//   forearms.csv                      t_us,arm,qw,qx,qy,qz,pronation_rad,source,confidence  (K_from_F)
//   imu_positions.csv                 t_us,device_id,x_m,y_m,z_m,source                   (p_K)
//   calibration.json                  CalibrationReport (protobuf JSON, .proto field names)
// t_us of frame files is the camera clock; enums are written by name (LEFT, FUSED, ...).
// A frame file is created when the first frame that has such entries arrives.
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "posefuse/v1/results.pb.h"
#include "session/text_fields.hpp"

namespace posefuse::session {

namespace result_layout {
inline const char* const kImuOrientationDir = "imu_orientations";
inline const char* const kSmplJointsCsv = "smpl_joints.csv";
inline const char* const kCameraJointsCsv = "camera_joints.csv";
inline const char* const kForearmsCsv = "forearms.csv";
inline const char* const kImuPositionsCsv = "imu_positions.csv";
inline const char* const kCalibrationJson = "calibration.json";
inline const std::vector<std::string> kOrientationColumns = {"t_us", "w", "x", "y", "z"};
inline const std::vector<std::string> kJointColumns = {"t_us", "joint", "joint_name", "x_m",
                                                       "y_m",  "z_m",   "source",     "confidence"};
inline const std::vector<std::string> kForearmColumns = {"t_us", "arm", "qw", "qx", "qy",
                                                         "qz", "pronation_rad", "source", "confidence"};
inline const std::vector<std::string> kImuPositionColumns = {"t_us", "device_id", "x_m", "y_m", "z_m",
                                                             "source"};
}  // namespace result_layout

class ResultFiles {
 public:
  // Creates `directory` (and parents); kFailedPrecondition when that fails.
  explicit ResultFiles(const std::filesystem::path& directory);
  ~ResultFiles();

  // kInvalidArgument naming the field for unsafe device ids or inconsistent array sizes.
  void write_orientations(const v1::ImuOrientationBatch& batch);
  // kInvalidArgument for more than 24 SMPL or 25 camera joints, or an unsafe device id.
  void write_frame(const v1::FrameResult& frame);
  void write_calibration(const v1::CalibrationReport& report);
  // Flushes and closes every file; kDataLoss when something could not be written.
  void close();

  std::uint64_t orientation_samples() const { return orientation_samples_; }
  std::uint64_t frames() const { return frames_; }
  const std::filesystem::path& directory() const { return directory_; }

 private:
  CsvWriter& frame_file(std::optional<CsvWriter>& file, const char* name,
                        const std::vector<std::string>& columns);

  std::filesystem::path directory_;
  std::map<std::string, std::unique_ptr<CsvWriter>> orientations_;
  std::optional<CsvWriter> smpl_joints_, camera_joints_, forearms_, imu_positions_;
  std::uint64_t orientation_samples_ = 0;
  std::uint64_t frames_ = 0;
};

}  // namespace posefuse::session
