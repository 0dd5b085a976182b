#pragma once
// One calibrated forearm through its occlusion gaps (paper 1, II-K and II-L), after the body fit:
//  - every tracked camera frame (forearm_track.hpp): the IMU position, VISUAL from the strap or,
//    inside a gap, the causal live estimate (PREDICTED, live_gap.hpp) pulled towards the SDK's
//    elbow less its bias as the body fit's recent elbows measure it;
//  - every gap, once the boundary window after it has been seen (and, with the body fit's elbows
//    as the anchor, once the fit's frames up to there have come, at most max_wait_s of camera
//    time): recover_gap_paper and recover_gap_smoother.
// The body fit runs before this (docs/architecture.md, "Pipeline stages"), so its elbows are an
// ordinary earlier input: nothing here waits for a later stage.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "forearm/forearm_track.hpp"
#include "forearm/gap_smoother.hpp"
#include "forearm/live_gap.hpp"

namespace posefuse::forearm {

// The body fit's elbows (paper 2) as the gap smoother's elbow anchor instead of the camera
// skeleton's. Measured on the body render (docs/forearm.md "The body fit's elbow as the
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
  // (docs/forearm.md "Two anchors").
  bool sdk_as_second_anchor = true;
  double max_wait_s = 10.0;  // a gap waits at most this long (camera time) for the fit
  // The live estimate in a gap is pulled towards the SDK's elbow of each frame; the SDK's bias (it
  // turns with a period of seconds) is taken out as measured against the fit's frames of the last
  // live_bias_window_s before its newest, while that is at most live_max_age_s old.
  double live_max_age_s = 1.0;
  double live_bias_window_s = 0.5;
};

// One body-fit frame's elbow for one arm (SMPL joint, camera frame K) and the fit's energy there.
struct FitElbow {
  std::int64_t t_us = 0;
  Vec3 elbow_K = Vec3::Zero();
  double energy = 0.0;
};

enum class PositionSource { kNone, kVisual, kPredicted };

// The forearm at one camera frame: orientation and, where known, the IMU position.
struct ArmFrameEstimate {
  std::int64_t t_us = 0;
  Quat K_from_F = Quat::Identity();
  double pronation_rad = 0.0;  // NaN without the calibration pose
  Vec3 imu_K = Vec3::Zero();
  PositionSource source = PositionSource::kNone;
  double orientation_rms_rad = 0.0;  // K_from_F's predicted RMS error (orientation_uncertainty.hpp)
};

// A gap's recovered trajectory, one sample per recovered time.
struct RecoveredGapSample {
  std::int64_t t_us = 0;
  Vec3 imu_K = Vec3::Zero();
  Vec3 elbow_K = Vec3::Zero();
  Vec3 wrist_K = Vec3::Zero();
  Quat K_from_F = Quat::Identity();
};
enum class RecoveryMethod { kPaper, kSmoother };
struct RecoveredGapSegment {
  RecoveryMethod method = RecoveryMethod::kPaper;
  std::int64_t t_start_us = 0, t_end_us = 0;
  std::vector<RecoveredGapSample> samples;
};

// Something the tracker could not do; the session goes on.
struct ForearmWarning {
  std::string code, field, message;
};

class GapTracker {
 public:
  // `label` names the arm in warnings ("forearm[<label>]"). `live_elbow_time_constant_s`: in a gap
  // the live estimate is pulled towards the SDK's elbow carried along the IMU's forearm axis
  // (LiveGapEstimator::correct) with this time constant; 0 turns it off. On posefuse-sim's
  // protocol (docs/forearm.md) 0.5 / 0.15 / 0.1 / 0.05 s gave PREDICTED RMS 0.09-0.23 /
  // 0.07-0.11 / 0.07-0.09 / 0.065-0.08 m: over gaps of 2-4 s the SDK's 5-10 cm bias is smaller
  // than the integration's drift, so the anchor is followed closely.
  GapTracker(std::string label, const ForearmModel& model, bool has_model, const Quat& K_from_W,
             const GapSmootherOptions& smoother = {}, double live_elbow_time_constant_s = 0.05);

  // Use the body fit's elbows as the gap smoother's anchor (before the first frame). A gap then
  // waits for the fit's frames up to the end of its boundary window after it, at most max_wait_s
  // of camera time; one where the fit has fewer than half as many frames inside it as the camera
  // skeleton uses the SDK's anchor. Throws kInvalidArgument for non-positive sigmas.
  void use_fit_anchor(const FitAnchorOptions& options);

  // Settled IMU samples (forearm_track.hpp), in time order; earlier or equal times are dropped.
  void add_samples(const std::vector<SettledArmSample>& samples);
  // The next tracked frame (after the samples up to its time): its estimate.
  ArmFrameEstimate add_frame(const TrackedArmFrame& frame);
  // One fitted frame's elbow for this arm (in time order; others dropped).
  void add_fit_elbow(const FitElbow& fit);
  // The gaps whose boundary window after them (and the fit's frames) are complete; with `all`
  // (end of session) every pending gap with what exists.
  std::vector<RecoveredGapSegment> recover_ready(bool all);
  // No more fit elbows will come: gaps stop waiting for them.
  void fit_finished() { fit_finished_ = true; }
  // End of session: the pending gaps recovered, a gap still open reported.
  std::vector<RecoveredGapSegment> finish();
  // The warnings since the last call.
  std::vector<ForearmWarning> take_warnings();

  std::uint64_t gaps() const { return gaps_; }
  // The memory the session's samples take (session::Stage::held_bytes).
  std::size_t held_bytes() const;

 private:
  void recover(std::int64_t t_start_us, std::int64_t t_end_us, std::vector<RecoveredGapSegment>& out);
  std::vector<ElbowAnchorSample> fit_anchor_between(std::int64_t from_us, std::int64_t to_us) const;
  bool fit_has_come_up_to(std::int64_t t_us) const;
  std::optional<Vec3> sdk_anchor_bias_from_fit(std::int64_t t_us) const;
  struct FitAnchorSample {
    Vec3 p_K;
    double variance_ratio;  // max(1, E / reference_energy)
  };
  std::optional<FitAnchorSample> fit_anchor_at(const FitElbow& fit) const;
  Quat K_from_F_at(std::int64_t t_us) const;  // slerped between the settled samples
  std::string field() const { return "forearm[" + label_ + "]"; }

  std::string label_;
  ForearmModel model_;
  bool has_model_;
  Quat K_from_W_;
  GapSmootherOptions smoother_options_;
  double live_elbow_time_constant_s_;

  std::vector<ArmSample> arm_;  // settled: K_from_A axis-corrected
  std::vector<Quat> K_from_F_;  // one per arm_ sample
  std::vector<TrackSample> track_;
  std::vector<ShoulderSample> shoulder_;
  std::vector<ElbowAnchorSample> elbow_anchor_;  // the SDK's
  std::optional<FitAnchorOptions> fit_anchor_;
  std::vector<FitElbow> fit_elbows_;
  bool fit_finished_ = false;

  std::optional<std::int64_t> last_visible_us_;
  bool in_gap_ = false;
  std::int64_t gap_start_us_ = 0;
  std::optional<LiveGapEstimator> live_;
  std::optional<LiveGapEstimator> paused_live_;  // the last gap's, until the next gap starts
  std::size_t live_next_arm_ = 0;
  std::optional<std::int64_t> last_live_frame_us_;
  struct PendingGap {
    std::int64_t t_start_us, t_end_us;
  };
  std::vector<PendingGap> pending_gaps_;
  std::vector<ForearmWarning> warnings_;
  std::uint64_t gaps_ = 0;
};

}  // namespace posefuse::forearm
