#pragma once
// Scores a result directory against a ground-truth directory of the same layout (the client's
// results of `posefuse fit` against the simulator's gt/, session/result_files.hpp), both read by
// session::read_result_files. What `posefuse-score RESULT_DIR GT_DIR` prints.
//
// Streams, each matched to the truth by nearest t_us within ScoreOptions::tolerance_us (rows
// with no truth that near are counted as unmatched, never scored against a far one):
//  - imu_orientations/<id>.csv: W_from_A per device (device clock), paper 1 eqs. 14-15 and the
//    heading part of the error (about W's z; orientation_error.hpp);
//  - forearm_orientations/<id>.csv: K_from_F per arm IMU sample (camera clock), eqs. 14-15;
//    forearm_orientations_offline/<id>.csv (the offline solution) against the same truth;
//  - forearms.csv: K_from_F per camera frame and arm, eqs. 14-15;
//  - imu_positions.csv: |p_K - p_K true| per device over all frames, VISUAL and PREDICTED
//    frames, and the frames gt's occlusion.csv marks occluded (when given);
//    recovered_segments.csv: the recovered trajectory (PAPER, SMOOTHER) interpolated linearly
//    at every truth frame inside its segment;
//  - smpl_joints.csv, camera_joints.csv: mean and max joint error per joint group;
//  - joint_angles.csv: per ISB angle RMS and max error; repetitions.csv: counts and per
//    repetition range-of-motion error;
//  - calibration.json: K_from_W angle, per arm r, d_se, d_sw, d_ul and A_from_F, per device the
//    clock offset and gyro bias.
// Errors (posefuse::Error): no result files at all (kNotFound); a stream in the results whose
// truth file is missing (kNotFound naming it); a stream none of whose rows has a truth within
// the tolerance (kInvalidArgument: mismatched timestamps, e.g. a device clock against a camera
// clock). A truth stream without results is listed in `notes`.
#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "eval/forearm_errors.hpp"
#include "session/result_reader.hpp"

namespace posefuse::eval {

struct ScoreOptions {
  std::int64_t tolerance_us = 2000;  // nearest truth row must be this close
};

struct AngleScore {
  std::string stream;        // file, e.g. "forearm_orientations/imu_left.csv"
  std::string key;           // device id or arm
  ErrorSummary deg;          // eqs. 14-15
  ErrorSummary heading_deg;  // imu_orientations only (count 0 otherwise)
  std::size_t unmatched = 0;
  // Rows that carry a confidence (forearm orientations): those with confidence >= 0.5 and their
  // errors, how many of them are beyond 15 degrees, the rows whose error lies within the 99 %
  // bound of their predicted RMS (forearm/orientation_uncertainty.hpp) out of those with one,
  // and the seconds from the first row to the first confident one.
  std::size_t with_confidence = 0;
  ErrorSummary confident_deg;
  std::size_t confident_beyond_15_deg = 0;
  std::size_t with_uncertainty = 0, within_predicted_bound = 0;
  std::optional<double> first_confident_s;
};

struct PositionScore {
  std::string device_id;
  std::string subset;  // "all", "VISUAL", "PREDICTED", "occluded (gt)", "recovered PAPER", ...
  ErrorSummary m;
  std::size_t unmatched = 0;
};

struct JointGroupScore {
  std::string stream;  // smpl_joints.csv or camera_joints.csv
  std::string group;   // "torso+head", "left arm", "right arm", "legs"
  double mean_m = 0.0;
  double max_m = 0.0;
  std::size_t count = 0;  // joint rows that entered
  std::size_t unmatched = 0;
};

struct CalibrationScore {
  std::string name;  // "K_from_W", "RIGHT r", "clock_offset imu_left", ...
  std::string unit;  // "deg", "m", "us", "deg/s"
  double result = 0.0;
  double truth = 0.0;        // for angles between rotations: 0 (the error is the angle)
  double error = 0.0;        // result - truth, or the angle between the two rotations
  double uncertainty = 0.0;  // the result's own 1-sigma claim (0: it claims none)
};

// joint_angles.csv: per ISB angle, |result - truth| (wrapped to 180 deg) over the frames where
// both define it and the truth's is not held (confidence 0: the gimbal-locked plane of
// elevation); frames where only the truth defines it are counted as undefined.
struct JointAngleScore {
  std::string angle;  // measures::angle_name
  ErrorSummary deg;
  ErrorSummary confident_deg;  // the samples the result gives confidence >= measures::kConfidentAt
  std::size_t result_undefined = 0;
  std::size_t unmatched = 0;  // result frames with no truth frame within the tolerance
};

// repetitions.csv: counted repetitions against the truth's, each true repetition matched to the
// counted result repetition that overlaps it most in time. Where the result's dominant angle is
// not the truth's (e.g. the other arm of a symmetric exercise), the truth's joint_angles.csv
// series of the result's angle is segmented (default options) and scored instead, with a note.
struct RepetitionScore {
  std::string result_angle, truth_angle;
  std::size_t result_count = 0, truth_count = 0;
  std::size_t matched = 0;
  ErrorSummary range_deg;  // |range - true range| over matched repetitions
  // The same over the matched repetitions whose range the result gives confidence >=
  // measures::kConfidentAt (none for files without repetition confidences).
  ErrorSummary confident_range_deg;
};

struct ScoreReport {
  std::vector<AngleScore> orientations;
  std::vector<PositionScore> positions;
  std::vector<JointGroupScore> joints;
  std::vector<CalibrationScore> calibration;
  std::vector<JointAngleScore> joint_angles;
  std::optional<RepetitionScore> repetitions;
  std::vector<std::string> notes;

  const AngleScore* orientation(const std::string& stream, const std::string& key) const;
  const PositionScore* position(const std::string& device_id, const std::string& subset) const;
  const CalibrationScore* calibration_value(const std::string& name) const;
};

// Per camera frame and arm: whether the truth says the forearm is occluded (gt/occlusion.csv,
// written by the simulator only).
struct OcclusionRow {
  std::int64_t t_us = 0;
  v1::Arm arm = v1::ARM_UNSPECIFIED;
  bool occluded = false;
};
// Empty when the file does not exist; posefuse::Error for a malformed one.
std::vector<OcclusionRow> read_gt_occlusion(const std::filesystem::path& gt_directory);

ScoreReport score_results(const session::ResultDirectory& result, const session::ResultDirectory& truth,
                          const std::vector<OcclusionRow>& occlusion, const ScoreOptions& options = {});

// Reads both directories (and gt's occlusion.csv) and scores.
ScoreReport score_directories(const std::filesystem::path& result_directory, const std::filesystem::path& gt_directory,
                              const ScoreOptions& options = {});

// The tables posefuse-score prints.
std::string format_score_report(const ScoreReport& report);

}  // namespace posefuse::eval
