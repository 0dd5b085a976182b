#pragma once
// Reads a result directory in the ResultFiles layout (result_files.hpp lists the files and
// columns) back into rows: the client's results of `posefuse fit` and the simulator's gt/ both
// go through this one reader, as both were written by one writer, so scoring compares like
// with like (eval/result_score.hpp).
//
// Every file is optional (the writer creates a file only when such results arrived); the
// directory itself must exist. Its files are opened beneath it without following links, and
// only regular files are read (session/recording_file.hpp): a link, a FIFO or a device where a
// file or folder of the layout belongs throws kInvalidArgument naming it. Each file present is checked the way the
// writer wrote it: the header row, the number of fields, numbers that parse and are finite, unit quaternions (within
// 1e-3), joint indices and names in SMPL / Kinect v2 order, enum names (source, arm, method), device ids that are safe
// file names, and t_us that never goes back in a file (per device in imu_positions.csv, whose devices are written as
// each is ready; per segment in recovered_segments.csv). forearms.csv is the exception: two stages write it (the
// forearm stage and, with fit.enabled, the body fit a few seconds later), so its rows are sorted by arm and time
// instead. A violation throws posefuse::Error (kInvalidArgument) whose field is "<file>:<line>:<column>".
#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "geometry/quaternion.hpp"
#include "posefuse/v1/results.pb.h"

namespace posefuse::session {

struct TimedOrientation {
  std::int64_t t_us = 0;
  geometry::Quat q = geometry::Quat::Identity();  // W_from_A (imu_orientations) or K_from_F
  // forearm_orientations only: NaN without a calibration pose.
  double pronation_rad = 0.0;
  // The predicted error and its confidence; none in files written before they were.
  std::optional<double> uncertainty_rad, confidence;
};

struct JointRow {
  std::int64_t t_us = 0;
  int joint = 0;
  geometry::Vec3 p_K = geometry::Vec3::Zero();
  v1::Source source = v1::SOURCE_UNSPECIFIED;
  double confidence = 0.0;
};

// One row of smpl_joint_rotations.csv: a fitted joint's global rotation.
struct JointRotationRow {
  std::int64_t t_us = 0;
  int joint = 0;  // SMPL order
  geometry::Quat K_from_joint = geometry::Quat::Identity();
};

// One row of fit_energy.csv: the body fit's energy E (paper 2 eq. 4) at a fitted frame.
struct FitEnergyRow {
  std::int64_t t_us = 0;
  double fit_energy = 0.0;
};

struct ForearmRow {
  std::int64_t t_us = 0;
  v1::Arm arm = v1::ARM_UNSPECIFIED;
  geometry::Quat K_from_F = geometry::Quat::Identity();
  double pronation_rad = 0.0;
  v1::Source source = v1::SOURCE_UNSPECIFIED;
  double confidence = 0.0;
};

struct ImuPositionRow {
  std::int64_t t_us = 0;
  std::string device_id;
  geometry::Vec3 p_K = geometry::Vec3::Zero();
  v1::Source source = v1::SOURCE_UNSPECIFIED;
};

struct RecoveredRow {
  std::string device_id;
  v1::RecoveredSegment::Method method = v1::RecoveredSegment::METHOD_UNSPECIFIED;
  std::int64_t t_start_us = 0, t_end_us = 0, t_us = 0;
  geometry::Vec3 imu_K = geometry::Vec3::Zero(), elbow_K = geometry::Vec3::Zero(), wrist_K = geometry::Vec3::Zero();
  geometry::Quat K_from_F = geometry::Quat::Identity();
};

// One row of joint_angles.csv: degrees per measures::Angle, none where undefined.
struct AngleRow {
  std::int64_t t_us = 0;                   // from t_s, rounded to the microsecond
  std::vector<std::optional<double>> deg;  // measures::kAngleCount
  std::vector<double> confidence;          // measures::kAngleCount
};

// One row of repetitions.csv.
struct RepetitionRow {
  std::string angle;  // measures::angle_name
  double t_start_s = 0, t_peak_s = 0, t_end_s = 0;
  double min_deg = 0, max_deg = 0, range_deg = 0, peak_speed_deg_s = 0, duration_s = 0;
  bool counted = false;
  double confidence = 0;  // of range_deg, 0..1; NaN in files written before repetitions carried one
  // Degrees (results.proto's Repetition.cut_ambiguity_deg); NaN in files written before it.
  double cut_ambiguity_deg = 0;
};

struct ResultDirectory {
  std::filesystem::path directory;
  std::set<std::string> files;  // the layout's files that were present, e.g. "imu_positions.csv",
                                // "imu_orientations/imu_left.csv"
  std::map<std::string, std::vector<TimedOrientation>> imu_orientations;              // by device id, device clock
  std::map<std::string, std::vector<TimedOrientation>> forearm_orientations;          // by device id, camera clock
  std::map<std::string, std::vector<TimedOrientation>> offline_forearm_orientations;  // the same, offline
  std::vector<JointRow> smpl_joints, camera_joints;
  std::vector<JointRotationRow> smpl_joint_rotations;  // t_us never goes back
  std::vector<FitEnergyRow> fit_energies;              // t_us never goes back
  std::vector<ForearmRow> forearms;
  std::vector<ImuPositionRow> imu_positions;
  std::vector<RecoveredRow> recovered;
  std::vector<AngleRow> joint_angles;  // t_us strictly increasing
  std::vector<RepetitionRow> repetitions;
  std::optional<v1::CalibrationReport> calibration;

  bool has(const std::string& file) const { return files.count(file) > 0; }
};

// kNotFound when `directory` is not a directory; kInvalidArgument as above.
ResultDirectory read_result_files(const std::filesystem::path& directory);

}  // namespace posefuse::session
