#pragma once
// One calibrated forearm seen by its IMU and the camera, in time order (paper 1, II-I and II-J):
// the part of the forearm fusion that needs neither the body fit nor the occlusion gaps.
//  - every arm IMU sample: K_from_A and K_from_F by eq. 11 and the pronation angle
//    (forearm_orientation.hpp), optionally turned slowly onto the depth-measured forearm axis of
//    the visible frames before it (visual_axis_correction.hpp);
//  - every camera frame, once the IMU samples reach past it: the IMU position from the strap by
//    eq. 10 and whether the II-J, elbow and continuity tests accept it (visible), with the
//    frame's K_from_F.
// What comes out (ForearmTrackOutput) is what the gap tracker (gap_tracker.hpp) and the body fit
// read; nothing here waits for them (docs/architecture.md, "Pipeline stages").
#include <cstdint>
#include <deque>
#include <optional>
#include <vector>

#include "forearm/forearm_orientation.hpp"
#include "forearm/forearm_types.hpp"
#include "forearm/orientation_uncertainty.hpp"
#include "forearm/visual_axis_correction.hpp"

namespace posefuse::forearm {

// What the camera showed of one arm in one camera frame.
struct ArmFrame {
  std::int64_t t_us = 0;  // camera clock
  Vec3 shoulder_K = Vec3::Zero();
  Vec3 elbow_K = Vec3::Zero();
  Vec3 wrist_K = Vec3::Zero();
  // elbow_K and wrist_K are the ends of the depth-fitted forearm axis (forearm_axis_depth.hpp),
  // not the SDK's joints: only such frames feed the axis correction.
  bool axis_from_depth = false;
  bool shoulder_tracked = false;
  bool forearm_tracked = false;  // elbow and wrist TRACKED
  // The SDK's own elbow (elbow_K may be the depth axis's) and whether the SDK gave one
  // (TRACKED or INFERRED): the live estimate's anchor in a gap.
  Vec3 sdk_elbow_K = Vec3::Zero();
  bool sdk_elbow_seen = false;
  Vec3 sdk_wrist_K = Vec3::Zero();           // the SDK's own wrist (wrist_K may be the depth axis's)
  Quat K_from_wrist_sdk = Quat(0, 0, 0, 0);  // zero when the SDK gave none
  std::optional<Vec3> strap_K;               // strap seen (II-I)
  // Upper arm direction (shoulder -> elbow) measured in depth (upper_arm_depth.hpp), while the
  // arm's mounting is still being estimated (calibration pose or motion).
  std::optional<Vec3> upper_arm_direction_K;
};

// An IMU sample once its orientation is settled (it will not change any more).
struct SettledArmSample {
  ArmSample sample;  // K_from_A as the gaps integrate it (axis-corrected)
  Quat K_from_F = Quat::Identity();
  double pronation_rad = 0.0;  // NaN without the calibration pose (no reference)
  // Predicted RMS angle of K_from_F's error (orientation_uncertainty.hpp), at least what the
  // camera's last forearm axis before it showed.
  double orientation_rms_rad = 0.0;
  // Predicted RMS angle of the forearm axis y_F's direction error: the mounting's axis and the
  // filter's steady error, before the filter's own uncertainty (lost samples, start-up) and the
  // camera's check. The body fit's imu term uses y_F alone, so this is what weights it: the roll
  // about y_F (+-30 deg from motion) does not move it. With the filter's uncertainty in it (then a gate),
  // the demo's right arm fed the imu term on 122 of 1581 samples instead of 981, and its fitted
  // joints were 44.7 mm off on average instead of 20.2 (docs/forearm.md).
  double axis_rms_rad = 0.0;
};

// A camera frame once tracked: the strap's IMU position when visible, and the forearm
// orientation at the frame's time.
struct TrackedArmFrame {
  ArmFrame frame;
  TrackSample visual;  // visual.visible: the strap position passed every test
  Quat K_from_F = Quat::Identity();
  double pronation_rad = 0.0;        // NaN without the calibration pose (no reference)
  double orientation_rms_rad = 0.0;  // the larger of the two samples' around the frame
  Quat K_from_A = Quat::Identity();  // eq. 11 at the frame's time, before any axis correction
  // The mounting this frame's K_from_F implies (K_from_A^-1 K_from_F, any axis correction in it)
  // moved this far from the previous frame's, more than either frame's uncertainty allows (the
  // 99 % bound); 0 otherwise. Such a frame's orientation_rms_rad is raised to the step.
  double orientation_step_rad = 0.0;
};

struct ForearmTrackOutput {
  std::vector<SettledArmSample> samples;  // settled since the last call, in time order
  std::vector<TrackedArmFrame> frames;    // tracked since the last call, in time order
};

// The camera's depth-measured forearm axis against an orientation's y axis, d apart: a direction
// error of an isotropic 3-D rotation error of RMS u has RMS sqrt(2/3) u, so the orientation is
// off by about d / sqrt(2/3) RMS at least, whatever its model predicts. Each sample's uncertainty
// is at least this (the last frame's with a depth axis). The depth axis's own error is not taken
// off: this errs towards less confidence, and never lets a persistent filter error through as
// "typical" noise.
double camera_observed_rms_rad(double disagreement_rad);

class ForearmTrack {
 public:
  // `has_model` false: the strap was never seen in the calibration, so r and d_se are unknown
  // and no frame is visible (orientations only). K_from_F_reference: the forearm in the
  // calibration pose, the zero of the pronation angle; none (a mounting from motion): the
  // pronation angle is NaN. orientation_rms_rad: the predicted RMS error of every K_from_F;
  // axis_rms_rad: that of its forearm axis y_F alone (forearm_axis_rms_rad), none: the orientation's
  // error taken as isotropic (kDirectionRmsOverOrientationRms times it).
  ForearmTrack(Side side, const ForearmModel& model, bool has_model, const Quat& K_from_W,
               const std::optional<Quat>& K_from_F_reference, double orientation_rms_rad,
               std::optional<double> axis_rms_rad = std::nullopt);

  // A refined mounting (from motion) for the IMU samples added from now on; those before keep
  // theirs, each sample carrying the RMS errors it was made with.
  void set_mounting(const Quat& F_from_A, double orientation_rms_rad,
                    std::optional<double> axis_rms_rad = std::nullopt);
  // The calibration pose found later in the session: the pronation angle's zero for the IMU
  // samples added from now on (those before keep NaN).
  void set_pronation_reference(const Quat& K_from_F_reference);

  // Turn every K_from_F (and the K_from_A the gaps integrate with) towards the depth-measured
  // forearm axis of the visible frames; call before the first IMU sample. The orientations
  // wait for the camera frames up to their time (at most 1 s of IMU time when no frame is
  // queued) in any case, so each gets the correction and the camera check of the frames before
  // it whatever order the streams arrive in.
  void use_axis_correction(const VisualAxisCorrectionOptions& options);

  // Arm IMU samples on the camera clock, in time order (earlier or equal times are dropped).
  // `filter_uncertainty_rad`, per sample or empty (none): the orientation filter's predicted
  // error beyond its steady one, added to the mounting's in each sample's uncertainty.
  void add_imu(const std::vector<std::int64_t>& t_us, const std::vector<Quat>& W_from_A,
               const std::vector<Vec3>& specific_force_A, const std::vector<double>& filter_uncertainty_rad = {});
  void add_frame(const ArmFrame& frame);
  // Tracks the queued frames up to the last IMU sample (K_from_F interpolated, not extrapolated;
  // with `all`, every queued frame: end of session) and returns them with the samples settled.
  ForearmTrackOutput process(bool all);

  AxisCorrection axis_correction() const;  // identity without it
  std::uint64_t axis_correction_frames() const;
  std::uint64_t visible_frames() const { return visible_frames_; }
  // Frames flagged for an orientation step (TrackedArmFrame::orientation_step_rad), the largest
  // step and its frame's time.
  std::uint64_t orientation_steps() const { return orientation_steps_; }
  double largest_orientation_step_rad() const { return largest_step_rad_; }
  std::int64_t largest_orientation_step_us() const { return largest_step_us_; }
  // Detections with no other within 500 ms before or after them: counted, and treated as
  // occluded.
  std::uint64_t lone_detections() const { return lone_detections_; }
  // The whole session again with the mounting and pronation reference the track has now (call
  // after process(true)): the offline solution. Every IMU sample's K_from_F from the final
  // mounting, its pronation relative to the final reference (a calibration pose found late in the
  // session gives every sample its angle), and its uncertainty from the final mounting's and the
  // filter's, at least what the camera's depth axis at the frames on either side of it showed
  // against the re-solved orientation. A track whose mounting never changed returns its live
  // samples: they are already final (and may carry an axis correction the re-solve would lose).
  // A mounting from a calibration pose found later holds the IMU's orientation error during the
  // hold; at another orientation that error no longer cancels, and the sample's own does not
  // either. The samples before such a pose therefore also carry the filter's predicted error at
  // the hold and at their own time (imu_orientation_rms_rad of each), as independent errors: the
  // pose's measured uncertainty (kPoseCalibrationRmsRad) was measured forward in time from a pose
  // at the start, and an IMU whose error the filter under-predicts showed confident samples
  // beyond 15 degrees without them (docs/forearm.md "The offline solution").
  std::vector<SettledArmSample> offline_samples() const;
  bool mounting_changed() const { return mounting_changed_; }

  // The oldest frame not tracked yet (none: every frame added has been returned).
  std::optional<std::int64_t> oldest_queued_us() const;
  // The memory the session's samples and the queued frames take (session::Stage::held_bytes).
  std::size_t held_bytes() const;

 private:
  TrackSample visual_sample(const ArmFrame& frame) const;
  bool continues_track(const Vec3& imu_K, std::int64_t t_us, const Quat& K_from_F) const;
  // A detection that would start a visible run (the first after occluded frames, or the first
  // ever) with no accepted detection in the boundary window before it is used only once another
  // queued frame within the window after it is accepted too.
  enum class Confirmation { kConfirmed, kLone, kWait };
  Confirmation confirm_detection(bool all, std::int64_t window_us) const;
  void flag_orientation_step(TrackedArmFrame& tracked);
  TrackedArmFrame track_frame(const ArmFrame& frame, const TrackSample& sample);
  Quat K_from_F_sample(std::size_t i) const;
  Quat K_from_F_at(std::int64_t t_us) const;
  Quat K_from_F_imu_at(std::int64_t t_us) const;
  // NaN for samples before the reference's first one (sample index i).
  double pronation(std::size_t i, const Quat& K_from_F) const;
  template <class SampleAt>
  Quat slerp_at(std::int64_t t_us, const SampleAt& sample_at) const;
  void settle_orientations_up_to(std::int64_t t_us);
  void take_settled(std::vector<SettledArmSample>& out);

  Side side_;
  ForearmModel model_;
  bool has_model_;
  Quat K_from_W_;
  std::optional<Quat> K_from_F_reference_;
  std::size_t reference_from_ = 0;  // the first sample whose pronation uses it
  double orientation_rms_rad_;
  double axis_rms_rad_;

  // Every IMU sample; K_from_A is eq. 11's until the sample is settled, then corrected.
  std::vector<ArmSample> arm_;
  std::vector<Quat> K_from_F_imu_;              // eq. 11, before the axis correction
  std::vector<Quat> K_from_A_imu_;              // eq. 11, before the axis correction
  std::vector<double> orientation_rms_rad_of_;  // per sample, the mounting's and the filter's
  std::vector<double> axis_rms_rad_of_;         // per sample, y_F's alone (SettledArmSample::axis_rms_rad)
  std::vector<double> settled_rms_rad_;         // per settled sample: at least the camera's observed
  std::vector<double> filter_rms_rad_of_;       // per sample, the filter's own beyond its steady error
  // The depth-measured forearm axis (unit, camera frame) of every tracked frame that had one: the
  // offline solution's camera check.
  struct DepthAxis {
    std::int64_t t_us = 0;
    Vec3 axis_K = Vec3::UnitY();
  };
  std::vector<DepthAxis> depth_axes_;
  bool mounting_changed_ = false;  // set_mounting or set_pronation_reference after the start
  std::size_t mounting_from_ = 0;  // the first sample made with the current mounting
  // The current mounting came from a calibration pose found later (set_pronation_reference with
  // it): what the IMU's orientation error was during the hold is in it.
  bool mounting_from_later_pose_ = false;
  // The previous frame's implied mounting and uncertainty, and the frames flagged for a step.
  std::optional<Quat> last_frame_A_from_F_;
  double last_frame_rms_rad_ = 0.0;
  std::uint64_t orientation_steps_ = 0;
  double largest_step_rad_ = 0.0;
  std::int64_t largest_step_us_ = 0;
  double observed_rms_rad_ = 0.0;  // what the last camera forearm axis showed
  std::vector<Quat> K_from_F_;     // settled (corrected), one per settled sample
  std::size_t settled_taken_ = 0;  // of K_from_F_, returned by process()
  std::optional<VisualAxisCorrection> axis_correction_;
  std::vector<TrackSample> track_;
  std::deque<ArmFrame> frames_;  // queued, not yet tracked
  std::optional<std::int64_t> last_visible_us_;
  std::uint64_t visible_frames_ = 0;
  std::uint64_t lone_detections_ = 0;
};

}  // namespace posefuse::forearm
