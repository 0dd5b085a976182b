#pragma once
// What a stage hands the stages after it: typed values, not wire protos. The pipeline delivers
// each value to the later stages that consume its kind and turns those the client sees into
// FitResults (result_encoder.hpp), so the wire format is written in one place.
#include <cstdint>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "forearm/forearm_track.hpp"
#include "forearm/gap_smoother.hpp"
#include "forearm/gap_tracker.hpp"
#include "geometry/quaternion.hpp"
#include "imu/imu_sample.hpp"
#include "measures/angle_series.hpp"
#include "measures/joint_angles.hpp"
#include "posefuse/v1/results.pb.h"

namespace posefuse::session {

// The IMU stage's orientation W_from_A for every sample of one IMU batch, beside the samples
// themselves (device clock). To the client: an ImuOrientationBatch.
struct ImuOrientations {
  std::string device_id;
  std::vector<imu::ImuSample> samples;
  std::vector<geometry::Quat> W_from_A;  // one per sample
  // The filter's predicted RMS error of each sample beyond its steady error: start-up and lost
  // samples (imu::RobustOrientationFilter::orientation_uncertainty_rad), rad.
  std::vector<double> uncertainty_rad;
};

// The forearm stage's forearm orientation K_from_F (paper 1 eq. 11) and pronation angle for
// arm IMU samples, on the camera clock, in time order. To the client: a ForearmOrientationBatch.
struct ForearmOrientations {
  std::string device_id;
  v1::Arm arm = v1::ARM_UNSPECIFIED;
  std::vector<std::int64_t> t_us;
  std::vector<geometry::Quat> K_from_F;
  std::vector<double> pronation_rad;        // NaN without the calibration pose
  std::vector<double> orientation_rms_rad;  // predicted RMS error (forearm/orientation_uncertainty.hpp)
  std::vector<double> axis_rms_rad;         // y_F's alone (SettledArmSample::axis_rms_rad)
  // The session re-solved at its end with the final mounting (ForearmTrack::offline_samples), sent
  // after every live batch; the live samples are not repeated in it.
  bool offline = false;
};

// The forearm stage's decision on one arm IMU once its calibration is over: tracked (with the
// forearm model and what the gap recovery needs) or not. Internal.
struct ArmTrackStart {
  std::string device_id;
  v1::Arm arm = v1::ARM_UNSPECIFIED;
  bool tracked = false;  // false: no calibration, no results for this arm
  forearm::ForearmModel model;
  bool has_model = false;  // the strap was seen in the calibration: r and d_se are known
  geometry::Quat K_from_W = geometry::Quat::Identity();
  forearm::GapSmootherOptions smoother;
  std::optional<forearm::FitAnchorOptions> fit_anchor;  // the body fit's elbows as the gap anchor
};

// One arm's settled IMU samples and tracked camera frames since the last (forearm_track.hpp),
// handed on after the ForearmOrientations of the same samples. Internal.
struct ArmTrack {
  std::string device_id;
  v1::Arm arm = v1::ARM_UNSPECIFIED;
  std::vector<forearm::SettledArmSample> samples;
  std::vector<forearm::TrackedArmFrame> frames;
};

// The orientations of one arm's settled samples, as the forearm stage hands them on.
inline ForearmOrientations forearm_orientations_of(const std::string& device_id, v1::Arm arm,
                                                   const std::vector<forearm::SettledArmSample>& samples) {
  ForearmOrientations out{device_id, arm, {}, {}, {}, {}, {}, false};
  for (const forearm::SettledArmSample& s : samples) {
    out.t_us.push_back(s.sample.t_us);
    out.K_from_F.push_back(s.K_from_F);
    out.pronation_rad.push_back(s.pronation_rad);
    out.orientation_rms_rad.push_back(s.orientation_rms_rad);
    out.axis_rms_rad.push_back(s.axis_rms_rad);
  }
  return out;
}

// Estimates as the client receives them in a FrameResult (results.proto), typed.
struct JointEstimate {
  geometry::Vec3 p_K = geometry::Vec3::Zero();
  v1::Source source = v1::SOURCE_UNSPECIFIED;
  double confidence = 0.0;
};
struct ForearmEstimate {
  v1::Arm arm = v1::ARM_UNSPECIFIED;
  geometry::Quat K_from_F = geometry::Quat::Identity();
  double pronation_rad = 0.0;
  v1::Source source = v1::SOURCE_UNSPECIFIED;
  double confidence = 0.0;
};
struct ImuPositionEstimate {
  std::string device_id;
  geometry::Vec3 p_K = geometry::Vec3::Zero();
  v1::Source source = v1::SOURCE_UNSPECIFIED;
};
// One depth frame's estimates: the frame merge's output (frame_merge.hpp). To the client: a
// FrameResult.
struct FrameEstimate {
  std::int64_t t_us = 0;
  std::vector<JointEstimate> smpl_joints;      // 24 or none
  std::vector<JointEstimate> camera_joints;    // 25 or none
  std::vector<geometry::Quat> smpl_rotations;  // K_from_joint, 24 with a body fit, else none
  std::vector<ForearmEstimate> forearms;
  std::vector<ImuPositionEstimate> imu_positions;
  double fit_energy = 0.0;  // paper 2 eq. 4; 0 without a fit
};

// The body fit's result for one depth frame: joints, the IMU forearm orientations turned onto
// the fitted forearms, the energy; `lost` when the energy is above fit.lost_energy. Internal.
struct FittedFrame {
  FrameEstimate estimate;
  bool lost = false;
};

// One arm's per-frame estimates from the gap stage (VISUAL / PREDICTED positions). Internal.
struct ArmFrameEstimates {
  std::string device_id;
  v1::Arm arm = v1::ARM_UNSPECIFIED;
  std::vector<forearm::ArmFrameEstimate> frames;
};

// A forearm trajectory recovered through a gap. To the client: a RecoveredSegment.
struct RecoveredSegment {
  std::string device_id;
  v1::Arm arm = v1::ARM_UNSPECIFIED;
  forearm::RecoveredGapSegment segment;
};

// "Every per-frame value of `source` at or before up_to_t_us has been handed on": how the frame
// merge knows a frame is complete. Every stage that contributes per-frame values hands one on at
// each camera frame; an inactive one says so with the largest time. Internal.
enum class FrameSource { kForearm, kBodyFit };
struct FramesDone {
  FrameSource source = FrameSource::kForearm;
  std::int64_t up_to_t_us = 0;
};

// The measures stage's ISB joint angles of one frame with a fitted body (measures/joint_angles.hpp).
// To the client: a FrameAngles.
struct FrameAngles {
  std::int64_t t_us = 0;
  measures::JointAngles angles{};
  v1::Source joints_source = v1::SOURCE_UNSPECIFIED;  // of the frame's SMPL joints
};

// Once, after the last frame: the repetitions of one angle, times in camera-clock seconds. To the
// client: a RepetitionSummary.
struct Repetitions {
  measures::SessionRepetitions repetitions;
};

using StageValue =
    std::variant<ImuOrientations, ForearmOrientations, ArmTrackStart, ArmTrack, FittedFrame, ArmFrameEstimates,
                 RecoveredSegment, FramesDone, FrameEstimate, FrameAngles, Repetitions>;

// The kinds, in StageValue's order, for the stages' consumes() and produces().
enum class ValueKind {
  kImuOrientations,
  kForearmOrientations,
  kArmTrackStart,
  kArmTrack,
  kFittedFrame,
  kArmFrameEstimates,
  kRecoveredSegment,
  kFramesDone,
  kFrameEstimate,
  kFrameAngles,
  kRepetitions
};
inline ValueKind kind_of(const StageValue& value) { return static_cast<ValueKind>(value.index()); }
const char* value_kind_name(ValueKind kind);

}  // namespace posefuse::session
