#pragma once
// Causal gap estimate for live use: the best position during an occlusion from data up to now,
// to be replaced by recover_gap_smoother's result when the gap ends (paper 1, V, names the
// non-causal recovery as its limit for real-time use).
//
// Entry state: the visible track in the 500 ms before the gap, with the IMU's own double
// integrated net acceleration (eq. 12) subtracted first, is fitted by a line. Unlike II-K.1's
// plain line this does not assume constant velocity in the window, so an arm accelerating into
// the gap keeps its real entry velocity. During the gap: velocity integrated from eq. 12 and
// damped towards zero with a time constant (unbounded drift becomes bounded), then the position
// is snapped onto the shoulder sphere (eq. 13) and the velocity's radial part removed.
#include <cstdint>
#include <vector>

#include "forearm/gap_input.hpp"

namespace posefuse::forearm {

struct LiveGapOptions {
  double boundary_window_s = 0.5;
  double velocity_time_constant_s = 1.5;  // damping of the integrated velocity
  bool use_shoulder_sphere = true;
};

class LiveGapEstimator {
 public:
  LiveGapEstimator(const ForearmModel& model, const Quat& K_from_W, const LiveGapOptions& options = {});

  // Starts a gap whose last visible track sample is at t_start_us. Reads only samples at or
  // before t_start_us. Throws posefuse::Error kFailedPrecondition "track.before_gap" (fewer than
  // 2 visible samples in the window) or "arm" (fewer than 2 arm samples in it);
  // kInvalidArgument for non-finite or out-of-order samples in the window.
  void begin(const std::vector<TrackSample>& track, const std::vector<ArmSample>& arm, std::int64_t t_start_us);

  // Advances to one arm sample inside the gap (strictly increasing times after t_start) with
  // the shoulder position at that time; returns the position estimate. Throws
  // kFailedPrecondition "gap" before begin(), kInvalidArgument "sample.*" on bad input.
  Vec3 update(const ArmSample& sample, const Vec3& shoulder_K);

  // Pulls the estimate towards an independent, drift-free but biased position of the IMU (e.g.
  // the SDK's elbow carried along the IMU's forearm axis, imu_position_from_elbow) by `gain` in
  // [0, 1]: a complementary filter, so that over a long gap the integration's drift is bounded by
  // that position's bias (5-10 cm for a skeleton SDK) instead of growing. The velocity is left as
  // it is. Throws kFailedPrecondition "gap" before begin(), kInvalidArgument "p_K" / "gain".
  void correct(const Vec3& p_K, double gain);

  bool active() const { return active_; }
  const Vec3& position_K() const { return p_K_; }
  const Vec3& velocity_K() const { return v_K_; }

 private:
  ForearmModel model_;
  Vec3 gravity_K_;
  LiveGapOptions options_;
  bool active_ = false;
  std::int64_t t_us_ = 0;
  Vec3 p_K_ = Vec3::Zero();
  Vec3 v_K_ = Vec3::Zero();
  Vec3 a_K_ = Vec3::Zero();  // net acceleration at t_us_
};

// The IMU where the forearm model puts it for an elbow position and K_from_F: F's origin lies
// d_se from the elbow along y_F, the IMU r along x_F (eq. 10 from the elbow's side).
Vec3 imu_position_from_elbow(const Vec3& elbow_K, const Quat& K_from_F, const ForearmModel& model);
// Its inverse: the elbow the model puts behind an IMU position.
Vec3 elbow_from_imu_position(const Vec3& imu_K, const Quat& K_from_F, const ForearmModel& model);

// Runs LiveGapEstimator over `gap` as it would run live (each estimate uses only data up to its
// time), at the same times as recover_gap_paper. Same errors as recover_gap_paper.
RecoveredGap recover_gap_live(const GapRecoveryInput& input, const GapSpan& gap, const LiveGapOptions& options = {});

}  // namespace posefuse::forearm
