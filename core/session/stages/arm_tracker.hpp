#pragma once
// One calibrated forearm through the session, in time order (paper 1, II-I to II-L), the part
// of the forearm stage that runs once the clocks, the camera alignment and the forearm model
// are known:
//  - every arm IMU sample: K_from_A and K_from_F by eq. 11, the pronation angle
//    (forearm_orientation.hpp) -> one ForearmOrientationBatch per call of add_imu;
//  - every camera frame: the IMU position from the strap by eq. 10 when the II-J tests accept
//    the visual forearm (VISUAL), else, inside a gap, the causal live estimate (PREDICTED)
//    -> one FrameResult;
//  - every gap, once the boundary window after it has been seen (and, with the body fit's anchor,
//    once the fit's frames up to there have come): recover_gap_paper and recover_gap_smoother
//    -> two RecoveredSegments.
#include <cstdint>
#include <deque>
#include <optional>
#include <string>
#include <vector>

#include "forearm/forearm_orientation.hpp"
#include "forearm/gap_input.hpp"
#include "forearm/gap_smoother.hpp"
#include "forearm/live_gap.hpp"
#include "forearm/occlusion_tests.hpp"
#include "forearm/visual_axis_correction.hpp"
#include "session/pipeline_stage.hpp"

namespace posefuse::session {

// The body fit's elbows (paper 2, BodyFitStage) as the gap smoother's elbow anchor instead of the
// camera skeleton's. Measured on the body render (docs/forearm.md "The body fit's elbow as the
// anchor"): behind the back the fit's elbows are 22-40 mm off where the SDK's are 77-79 mm off; on
// frames the fit loses the arm they can be 0.5-1.4 m off (energies up to 2400), and in live order
// one ran 41-61 mm off for 1.2 s at normal energies.
struct FitAnchorOptions {
  double sigma_m = 0.03;           // a well-fitted frame's anchor sample (the SDK's: 0.12 m)
  double reference_energy = 10.0;  // above it a sample's sigma grows as sqrt(energy / this)
  // The anchor's own error c0 + tau c1 (gap_smoother.hpp): the fit's elbow has no turning 5-10 cm
  // bias like the SDK's (0.15 m there). Measured: with 0.15 m the kick clip's right arm was worse
  // than with the SDK's anchor (34.5 against 25.7 mm RMS), with 0.03 m better (22.8 mm); the
  // protocol within 0.4 mm either way.
  double bias_prior_sigma_m = 0.03;
  // The SDK's elbow as the smoother's second anchor (GapRecoveryInput::second_elbow_anchor), with
  // the SDK anchor's sigmas: behind the back the fit's elbow goes 50-140 mm off for about 2 s
  // (docs/forearm.md "Two anchors"). Measured on protocol seeds 1-10: see there.
  bool sdk_as_second_anchor = true;
  double max_wait_s = 10.0;  // a gap waits at most this long (camera time) for the fit
  // The live estimate in a gap is pulled towards the SDK's elbow of each frame (the fit's comes
  // later); the SDK's bias (it turns with a period of seconds) is taken out as measured against
  // the fit's frames of the last live_bias_window_s before its newest, while that is at most
  // live_max_age_s old.
  double live_max_age_s = 1.0;
  double live_bias_window_s = 0.5;
};

// One body-fit frame's elbow for one arm (SMPL joint, camera frame K) and the fit's energy there.
struct FitElbow {
  std::int64_t t_us = 0;
  forearm::Vec3 elbow_K = forearm::Vec3::Zero();
  double energy = 0.0;
};

// What the stage saw of one arm in one camera frame.
struct ArmFrame {
  std::int64_t t_us = 0;  // camera clock
  forearm::Vec3 shoulder_K = forearm::Vec3::Zero();
  forearm::Vec3 elbow_K = forearm::Vec3::Zero();
  forearm::Vec3 wrist_K = forearm::Vec3::Zero();
  // elbow_K and wrist_K are the ends of the depth-fitted forearm axis (forearm_axis_depth.hpp),
  // not the SDK's joints: only such frames feed the axis correction.
  bool axis_from_depth = false;
  bool shoulder_tracked = false;
  bool forearm_tracked = false;  // elbow and wrist TRACKED
  // The SDK's own elbow (elbow_K may be the depth axis's) and whether the SDK gave one
  // (TRACKED or INFERRED): the live estimate's anchor in a gap.
  forearm::Vec3 sdk_elbow_K = forearm::Vec3::Zero();
  bool sdk_elbow_seen = false;
  forearm::Quat K_from_wrist_sdk = forearm::Quat(0, 0, 0, 0);  // zero when the SDK gave none
  std::optional<forearm::Vec3> strap_K;  // strap seen (II-I)
  // Upper arm direction (shoulder -> elbow) measured in depth, calibration frames only
  // (upper_arm_depth.hpp).
  std::optional<forearm::Vec3> upper_arm_direction_K;
};

class ArmTracker {
 public:
  // `has_model` false: the strap was never seen in the calibration, so r and d_se are unknown
  // and only orientations are produced.
  // `smoother` configures recover_gap_smoother (e.g. whether the SDK shoulder's sphere is used).
  // `live_elbow_time_constant_s`: in a gap the live estimate is pulled towards the SDK's elbow
  // carried along the IMU's forearm axis (LiveGapEstimator::correct) with this time constant;
  // 0 turns it off. On posefuse-sim's protocol (docs/forearm.md) 0.5 / 0.15 / 0.1 / 0.05 s gave
  // PREDICTED RMS 0.09-0.23 / 0.07-0.11 / 0.07-0.09 / 0.065-0.08 m: over gaps of 2-4 s the
  // SDK's 5-10 cm bias is smaller than the integration's drift, so the anchor is followed closely.
  ArmTracker(std::string device_id, forearm::Side side, const forearm::ForearmModel& model, bool has_model,
             const forearm::Quat& K_from_W, const forearm::Quat& K_from_F_reference,
             const forearm::GapSmootherOptions& smoother = {}, double live_elbow_time_constant_s = 0.05);

  // Arm IMU samples on the camera clock, in time order (earlier or equal times are dropped).
  void add_imu(const std::vector<std::int64_t>& t_us, const std::vector<forearm::Quat>& W_from_A,
               const std::vector<forearm::Vec3>& specific_force_A, StageOutput& out);
  // Camera frames up to the last IMU sample (so K_from_F is interpolated, not extrapolated);
  // with `all` every queued frame (end of session). Then the gaps whose after-window is complete.
  void add_frame(const ArmFrame& frame) { frames_.push_back(frame); }
  void process(bool all, StageOutput& out);
  // End of session: a gap still open is reported, pending gaps are recovered with what exists
  // (except those waiting for the body fit's frames: finish_late).
  void finish(StageOutput& out);

  // Use the body fit's elbows as the gap smoother's anchor (before the first gap). Each gap then
  // waits for the fit's frames up to the end of its boundary window after it, at most
  // max_wait_s of camera time. A gap where the fit has fewer than half as many frames inside it as
  // the camera skeleton uses the SDK's anchor.
  void use_fit_anchor(const FitAnchorOptions& options);
  // One fitted frame's elbow for this arm and the fit's energy (in time order; others dropped).
  void add_fit_elbow(std::int64_t t_us, const forearm::Vec3& elbow_K, double fit_energy);
  void add_fit_elbow(const FitElbow& fit) { add_fit_elbow(fit.t_us, fit.elbow_K, fit.energy); }
  // The body fit has finished: the gaps that waited for it are recovered.
  void finish_late(StageOutput& out);

  // Turn every K_from_F (and the K_from_A the gaps integrate with) towards the depth-measured
  // forearm axis of the VISUAL frames (forearm/visual_axis_correction.hpp); call before the
  // first IMU sample. Only frames with axis_from_depth are used. The
  // orientations then wait for the camera frames up to their time (at most 1 s of IMU time when
  // no frame is queued), so each gets the correction of the frames before it whatever order
  // the streams arrive in; without it every add_imu emits its samples at once.
  void use_axis_correction(const forearm::VisualAxisCorrectionOptions& options);
  // The correction now (identity without it), and the frames it used so far.
  forearm::AxisCorrection axis_correction() const;
  std::uint64_t axis_correction_frames() const;

  std::uint64_t visible_frames() const { return visible_frames_; }
  std::uint64_t gaps() const { return gaps_; }
  // Detections with no other within 500 ms before or after them: counted, and treated as
  // occluded.
  std::uint64_t lone_detections() const { return lone_detections_; }

 private:
  // The frame's IMU position from the strap (eq. 10) and whether the II-J, elbow and continuity
  // tests accept it.
  forearm::TrackSample visual_sample(const ArmFrame& frame) const;
  // forearm::check_strap_continuity against the last visible sample of the track.
  bool continues_track(const geometry::Vec3& imu_K, std::int64_t t_us, const geometry::Quat& K_from_F) const;
  // A detection that would start a visible run (the first after occluded frames, or the first
  // ever) with no accepted detection in the boundary window before it is used only once another
  // queued frame within the window after it is accepted too.
  enum class Confirmation { kConfirmed, kLone, kWait };
  Confirmation confirm_detection(bool all, std::int64_t window_us) const;
  void process_frame(const ArmFrame& frame, const forearm::TrackSample& sample, StageOutput& out);
  void recover(std::int64_t t_start_us, std::int64_t t_end_us, StageOutput& out);
  // The anchor samples for a gap's window: the fit's elbows when it has some there, else the SDK's.
  std::vector<forearm::ElbowAnchorSample> fit_anchor_between(std::int64_t from_us, std::int64_t to_us) const;
  // Whether the body fit's frames up to t_us have come (always true without the fit's anchor).
  bool fit_has_come_up_to(std::int64_t t_us) const;
  // The SDK's anchor minus the fit's over the fit's recent frames (FitAnchorOptions::live_*), or
  // none without a recent fit frame.
  std::optional<forearm::Vec3> sdk_anchor_bias_from_fit(std::int64_t t_us) const;
  // A fit frame's anchor: its elbow carried along the IMU's forearm axis, and its variance ratio
  // max(1, E / reference_energy); none without a finite elbow and energy.
  struct FitAnchorSample {
    forearm::Vec3 p_K;
    double variance_ratio;
  };
  std::optional<FitAnchorSample> fit_anchor_at(const FitElbow& fit) const;
  // Sample i's K_from_F as settled (with the axis correction of its time; not settled yet: with
  // the correction now), and slerped between samples at t_us; K_from_F_imu_at: eq. 11's, uncorrected.
  forearm::Quat K_from_F_sample(std::size_t i) const;
  forearm::Quat K_from_F_at(std::int64_t t_us) const;
  forearm::Quat K_from_F_imu_at(std::int64_t t_us) const;
  template <class SampleAt>
  forearm::Quat slerp_at(std::int64_t t_us, const SampleAt& sample_at) const;
  // Fixes the K_from_F of the samples up to t_us not settled yet with the axis correction as it
  // is now (which from then on also turns their K_from_A); emit_settled_orientations sends the
  // settled ones not sent yet as one ForearmOrientationBatch.
  void settle_orientations_up_to(std::int64_t t_us);
  void emit_settled_orientations(StageOutput& out);
  // The arm samples in [t0, t1] with K_from_A as the gaps integrate it (corrected).
  std::vector<forearm::ArmSample> arm_between(std::int64_t t0_us, std::int64_t t1_us) const;
  double pronation_at(std::int64_t t_us) const;
  std::string field() const;

  std::string device_id_;
  forearm::Side side_;
  forearm::ForearmModel model_;
  bool has_model_;
  forearm::Quat K_from_W_;
  forearm::Quat K_from_F_reference_;
  forearm::GapSmootherOptions smoother_options_;
  double live_elbow_time_constant_s_;

  // Every IMU sample; K_from_A is eq. 11's until the sample is settled, then corrected.
  std::vector<forearm::ArmSample> arm_;
  std::vector<forearm::Quat> K_from_F_imu_;  // eq. 11, before the axis correction
  std::vector<forearm::Quat> K_from_F_;      // as emitted (corrected), one per settled sample
  std::size_t orientations_emitted_ = 0;     // of K_from_F_
  std::optional<forearm::VisualAxisCorrection> axis_correction_;
  std::vector<forearm::TrackSample> track_;
  std::vector<forearm::ShoulderSample> shoulder_;
  std::vector<forearm::ElbowAnchorSample> elbow_anchor_;  // the SDK's
  std::optional<FitAnchorOptions> fit_anchor_;
  std::vector<FitElbow> fit_elbows_;
  bool fit_finished_ = false;
  std::deque<ArmFrame> frames_;  // queued, not yet processed

  std::optional<std::int64_t> last_visible_us_;
  bool in_gap_ = false;
  std::int64_t gap_start_us_ = 0;
  std::optional<forearm::LiveGapEstimator> live_;
  std::optional<forearm::LiveGapEstimator> paused_live_;  // the last gap's, until the next gap starts
  std::size_t live_next_arm_ = 0;
  std::optional<std::int64_t> last_live_frame_us_;
  struct PendingGap {
    std::int64_t t_start_us, t_end_us;
  };
  std::vector<PendingGap> pending_gaps_;
  std::uint64_t visible_frames_ = 0;
  std::uint64_t gaps_ = 0;
  std::uint64_t lone_detections_ = 0;
};

}  // namespace posefuse::session
