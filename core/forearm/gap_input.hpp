#pragma once
// What every gap recovery needs (paper 1, II-K): the gaps in the IMU position track, boundary
// fits, net acceleration in K (eq. 12), the shoulder sphere (eq. 13), with input validation.
#include <cstdint>
#include <vector>

#include "forearm/forearm_types.hpp"

namespace posefuse::forearm {

// The IMU position an elbow estimate implies at a depth frame: the elbow carried along the IMU's
// forearm axis (imu_position_from_elbow, live_gap.hpp). The elbow is the camera skeleton's (the
// SDK's elbow error: a bias of several cm that turns slowly, occasional jumps) or the body fit's
// (paper 2; nearer the truth, worse on the frames it fits badly). Unlike the strap it is there in
// most gaps.
struct ElbowAnchorSample {
  std::int64_t t_us = 0;
  Vec3 p_K = Vec3::Zero();
  // This sample's sigma is GapSmootherOptions::anchor_sigma_m times this (finite, >= 1): the body
  // fit's anchor is trusted less on frames whose fit energy is high.
  double sigma_scale = 1.0;
};

struct GapRecoveryInput {
  std::vector<TrackSample> track;               // ~30 Hz, strictly increasing t_us
  std::vector<ArmSample> arm;                   // ~80 Hz, strictly increasing t_us
  std::vector<ShoulderSample> shoulder;         // strictly increasing t_us; interpolated (II-K.4)
  std::vector<ElbowAnchorSample> elbow_anchor;  // optional (smoother only); strictly increasing t_us
  // A second, independent anchor (optional, smoother only), with its own error c0 + tau c1 and
  // GapSmootherOptions::second_anchor_*: the camera skeleton's elbow alongside the body fit's,
  // whose errors come from different places.
  std::vector<ElbowAnchorSample> second_elbow_anchor;
  ForearmModel model;
  Quat K_from_W = Quat::Identity();  // eq. 7
};

// Throws posefuse::Error (kInvalidArgument) naming the first bad field: empty series, non-finite
// values (occluded track positions excepted), timestamps not strictly increasing, bad model.
void validate(const GapRecoveryInput& input);

// A maximal run of occluded track samples, bounded by the last visible sample before it
// (t_start_us) and the first visible one after it (t_end_us); -1 where there is none.
struct GapSpan {
  std::size_t first_occluded = 0;
  std::size_t last_occluded = 0;
  std::int64_t t_start_us = -1;
  std::int64_t t_end_us = -1;
};
std::vector<GapSpan> find_gaps(const std::vector<TrackSample>& track);

// Visible samples of `track` in [t_us, t_us + window_s]. A gap closes only where there are
// enough of them for its exit boundary fit (2, fit_boundary_line): a strap seen once inside a
// long occlusion is mostly a false detection (on the body render: 0.22 m off, behind the back,
// docs/forearm.md), and the gap goes on through it rather than becoming two gaps that neither
// recovery can close.
int visible_samples_after(const std::vector<TrackSample>& track, std::int64_t t_us, double window_s);

// Marks every sample strictly inside (t_start_us, t_end_us) occluded: one gap across the lone
// detections within it.
void occlude_inside(std::vector<TrackSample>& track, std::int64_t t_start_us, std::int64_t t_end_us);

// Position and velocity at `t_at_us` from a least-squares line through the visible track
// samples in [t_at - window, t_at] (side < 0) or [t_at, t_at + window] (side > 0) (II-K.1).
struct BoundaryState {
  Vec3 p_K = Vec3::Zero();
  Vec3 v_K = Vec3::Zero();
  int sample_count = 0;
};
// Throws posefuse::Error kFailedPrecondition "track.before_gap" / "track.after_gap" when fewer
// than 2 visible samples (at distinct times) lie in the window.
BoundaryState fit_boundary_line(const std::vector<TrackSample>& track, std::int64_t t_at_us, int side, double window_s);

// The arm IMU series resampled at any time: K_from_A by slerp, net acceleration (eq. 12) and
// the shoulder-sphere centre (eq. 13) by linear interpolation.
class ArmTimeline {
 public:
  explicit ArmTimeline(const GapRecoveryInput& input);  // input must be validated

  // Throws posefuse::Error kFailedPrecondition `field` when [t0, t1] is not inside the arm or
  // shoulder series.
  void require_coverage(std::int64_t t0_us, std::int64_t t1_us, const char* field) const;

  Quat K_from_A(double t_us) const;
  Vec3 net_acceleration_K(double t_us) const;  // eq. 12
  Vec3 sphere_centre_K(double t_us) const;     // eq. 13
  Vec3 shoulder_K(double t_us) const;
  // Arm sample times strictly inside (t0, t1).
  std::vector<std::int64_t> arm_times_between(std::int64_t t0_us, std::int64_t t1_us) const;

  const GapRecoveryInput& input() const { return input_; }
  const Vec3& gravity_K() const { return gravity_K_; }

 private:
  std::size_t arm_index_before(double t_us) const;
  const GapRecoveryInput& input_;
  Vec3 gravity_K_;
  std::vector<Vec3> net_acc_K_;
};

// What every recovery checks first: validate(input), a visible sample on both sides of the gap
// (kFailedPrecondition "track.before_gap" / "track.after_gap"), and arm and shoulder series
// covering it ("arm"). Returns the timeline over `input` (which must outlive it).
ArmTimeline checked_gap_timeline(const GapRecoveryInput& input, const GapSpan& gap);

// eq. 12: rot(K_from_A, a_measured) - rot(K_from_W, [0, 0, 9.81]).
Vec3 net_acceleration(const Quat& K_from_A, const Vec3& specific_force_A, const Vec3& gravity_K);

// eq. 13: the IMU lies on a sphere of radius d_ul around C = S - rot(K_from_F, [-r, -d_se, 0]).
Vec3 sphere_centre(const Vec3& shoulder_K, const Quat& K_from_F, const ForearmModel& model);

// The point of the sphere nearest p (radial snap, II-L.3); p at the centre stays unchanged.
Vec3 snap_to_sphere(const Vec3& p, const Vec3& centre, double radius);

// A recovered gap: positions at the gap's boundary times and every arm sample between them.
struct RecoveredGap {
  GapSpan span;
  std::vector<std::int64_t> t_us;
  std::vector<Vec3> p_K;
};
// Linear interpolation inside the recovered interval; throws kOutOfRange "t_us" outside it.
Vec3 position_at(const RecoveredGap& gap, std::int64_t t_us);

}  // namespace posefuse::forearm
