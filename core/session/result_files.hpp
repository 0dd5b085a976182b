#pragma once
// The result files of a fitted session, written by one code path for the client (results
// streamed back by the server) and for the simulator's ground truth (gt/), so that a result
// directory can be scored against a gt/ directory file by file, column by column.
//
//   imu_orientations/<device_id>.csv  t_us,w,x,y,z,uncertainty_rad,confidence  W_from_A per IMU
//                                     sample (device clock) with its predicted RMS error
//   forearm_orientations/<device_id>.csv  t_us,w,x,y,z,pronation_rad,uncertainty_rad,confidence
//                                     K_from_F per arm IMU sample (camera clock; pronation + /
//                                     supination -)
//   forearm_orientations_offline/<device_id>.csv  the same columns: the offline solution, every
//                                     sample re-solved at the session's end with the final mounting
//                                     (ForearmOrientationBatch.offline)
//   smpl_joints.csv                   t_us,joint,joint_name,x_m,y_m,z_m,source,confidence
//                                     (24 rows per frame, SMPL order, p_K)
//   camera_joints.csv                 the same columns, 25 rows per frame, Kinect v2 JointType order
//   smpl_joint_rotations.csv          t_us,joint,joint_name,w,x,y,z  the fitted model's global joint
//                                     rotations K_from_joint (24 rows per fitted frame, SMPL order)
//   forearms.csv                      t_us,arm,qw,qx,qy,qz,pronation_rad,source,confidence  (K_from_F)
//   imu_positions.csv                 t_us,device_id,x_m,y_m,z_m,source                   (p_K)
//   recovered_segments.csv            device_id,method,t_start_us,t_end_us,t_us,imu_x_m,imu_y_m,
//                                     imu_z_m,elbow_x_m,elbow_y_m,elbow_z_m,wrist_x_m,wrist_y_m,
//                                     wrist_z_m,w,x,y,z  (one row per recovered sample; method
//                                     PAPER or SMOOTHER; p_K and K_from_F as w x y z)
//   joint_angles.csv                  t_s,<angle>...,<angle>_confidence...  one row per frame with a
//                                     fitted body; one column per ISB angle (measures/joint_angles.hpp
//                                     names, degrees), empty where undefined; then each angle's
//                                     confidence (0 where held or undefined). t_s: camera clock, s
//   repetitions.csv                   angle,repetition,t_start_s,t_peak_s,t_end_s,min_deg,max_deg,
//                                     range_deg,peak_speed_deg_s,duration_s,counted  (one row per
//                                     repetition, partial ones with counted 0)
//   repetition_summary.json           RepetitionSummary without its repetitions (count, means, spreads)
//   calibration.json                  CalibrationReport (protobuf JSON, .proto field names)
// t_us of frame files is the camera clock; enums are written by name (LEFT, FUSED, ...).
// A frame, forearm or segment file is created when the first result that has such entries
// arrives.
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
inline const char* const kForearmOrientationDir = "forearm_orientations";
inline const char* const kForearmOrientationOfflineDir = "forearm_orientations_offline";
inline const char* const kRecoveredSegmentsCsv = "recovered_segments.csv";
inline const char* const kSmplJointsCsv = "smpl_joints.csv";
inline const char* const kCameraJointsCsv = "camera_joints.csv";
inline const char* const kSmplJointRotationsCsv = "smpl_joint_rotations.csv";
inline const char* const kFitEnergyCsv = "fit_energy.csv";
inline const char* const kForearmsCsv = "forearms.csv";
inline const char* const kImuPositionsCsv = "imu_positions.csv";
inline const char* const kCalibrationJson = "calibration.json";
inline const char* const kJointAnglesCsv = "joint_angles.csv";
inline const char* const kRepetitionsCsv = "repetitions.csv";
inline const char* const kRepetitionSummaryJson = "repetition_summary.json";
inline const std::vector<std::string> kRepetitionColumns = {
    "angle",     "repetition",       "t_start_s",  "t_peak_s", "t_end_s",    "min_deg",          "max_deg",
    "range_deg", "peak_speed_deg_s", "duration_s", "counted",  "confidence", "cut_ambiguity_deg"};
// repetitions.csv as written before each repetition carried its cut's ambiguity; still read.
inline const std::vector<std::string> kRepetitionColumnsWithoutCutAmbiguity = {
    "angle",   "repetition", "t_start_s",        "t_peak_s",   "t_end_s", "min_deg",
    "max_deg", "range_deg",  "peak_speed_deg_s", "duration_s", "counted", "confidence"};
// repetitions.csv as written before each repetition carried its confidence; still read.
inline const std::vector<std::string> kRepetitionColumnsWithoutConfidence = {
    "angle",   "repetition", "t_start_s",        "t_peak_s",   "t_end_s", "min_deg",
    "max_deg", "range_deg",  "peak_speed_deg_s", "duration_s", "counted"};
// t_s, one column per angle, then one confidence column per angle.
std::vector<std::string> joint_angle_columns();
inline const std::vector<std::string> kOrientationColumns = {"t_us",      "w", "x", "y", "z", "uncertainty_rad",
                                                             "confidence"};
// imu_orientations/<id>.csv as written before each sample carried its uncertainty; still read.
inline const std::vector<std::string> kOrientationColumnsWithoutUncertainty = {"t_us", "w", "x", "y", "z"};
inline const std::vector<std::string> kForearmOrientationColumns = {
    "t_us", "w", "x", "y", "z", "pronation_rad", "uncertainty_rad", "confidence"};
// forearm_orientations/<id>.csv as written before each sample carried its uncertainty; still read.
inline const std::vector<std::string> kForearmOrientationColumnsWithoutUncertainty = {"t_us", "w", "x",
                                                                                      "y",    "z", "pronation_rad"};
inline const std::vector<std::string> kJointColumns = {"t_us", "joint", "joint_name", "x_m",
                                                       "y_m",  "z_m",   "source",     "confidence"};
inline const std::vector<std::string> kJointRotationColumns = {"t_us", "joint", "joint_name", "w", "x", "y", "z"};
inline const std::vector<std::string> kFitEnergyColumns = {"t_us", "fit_energy"};
inline const std::vector<std::string> kForearmColumns = {"t_us", "arm",           "qw",     "qx",        "qy",
                                                         "qz",   "pronation_rad", "source", "confidence"};
inline const std::vector<std::string> kImuPositionColumns = {"t_us", "device_id", "x_m", "y_m", "z_m", "source"};
inline const std::vector<std::string> kRecoveredSegmentColumns = {
    "device_id", "method",    "t_start_us", "t_end_us",  "t_us",      "imu_x_m", "imu_y_m", "imu_z_m", "elbow_x_m",
    "elbow_y_m", "elbow_z_m", "wrist_x_m",  "wrist_y_m", "wrist_z_m", "w",       "x",       "y",       "z"};
}  // namespace result_layout

class ResultFiles {
 public:
  // Creates `directory` (and parents); kFailedPrecondition when that fails.
  explicit ResultFiles(const std::filesystem::path& directory);
  ~ResultFiles();

  // kInvalidArgument naming the field for unsafe device ids or inconsistent array sizes.
  void write_orientations(const v1::ImuOrientationBatch& batch);
  void write_forearm_orientations(const v1::ForearmOrientationBatch& batch);
  // kInvalidArgument for more than 24 SMPL or 25 camera joints, or an unsafe device id.
  void write_frame(const v1::FrameResult& frame);
  // kInvalidArgument for an unsafe device id.
  void write_segment(const v1::RecoveredSegment& segment);
  // kInvalidArgument for a frame whose angles are not every JointAngleKind in order.
  void write_angles(const v1::FrameAngles& angles);
  void write_repetitions(const v1::RepetitionSummary& summary);
  void write_calibration(const v1::CalibrationReport& report);
  // Flushes and closes every file; kDataLoss when something could not be written.
  void close();

  std::uint64_t orientation_samples() const { return orientation_samples_; }
  std::uint64_t forearm_samples() const { return forearm_samples_; }  // live ones
  std::uint64_t offline_forearm_samples() const { return offline_forearm_samples_; }
  std::uint64_t frames() const { return frames_; }
  std::uint64_t imu_positions() const { return imu_positions_count_; }
  std::uint64_t recovered_segments() const { return recovered_segments_; }
  const std::filesystem::path& directory() const { return directory_; }

 private:
  CsvWriter& opened_file(std::optional<CsvWriter>& file, const char* name, const std::vector<std::string>& columns);

  std::filesystem::path directory_;
  std::map<std::string, std::unique_ptr<CsvWriter>> orientations_;
  std::map<std::string, std::unique_ptr<CsvWriter>> forearm_orientations_, offline_forearm_orientations_;
  std::optional<CsvWriter> smpl_joints_, smpl_rotations_, fit_energy_, camera_joints_, forearms_, imu_positions_,
      segments_, angles_;
  std::uint64_t orientation_samples_ = 0;
  std::uint64_t forearm_samples_ = 0;
  std::uint64_t offline_forearm_samples_ = 0;
  std::uint64_t frames_ = 0;
  std::uint64_t imu_positions_count_ = 0;
  std::uint64_t recovered_segments_ = 0;
};

}  // namespace posefuse::session
