#include "forearm/forearm_track.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "common/error.hpp"
#include "common/held_bytes.hpp"
#include "forearm/forearm_model.hpp"
#include "forearm/live_gap.hpp"
#include "forearm/occlusion_tests.hpp"
#include "forearm/orientation_uncertainty.hpp"
#include "forearm/time_series.hpp"

namespace posefuse::forearm {

namespace {

// II-K.1: a detection is confirmed by another within 500 ms (the recoveries' boundary window).
constexpr double kBoundaryWindowS = 0.5;
// With the axis correction, how long (IMU time) an orientation waits for camera frames.
constexpr double kMaxOrientationWaitS = 1.0;

std::int64_t microseconds(double seconds) { return static_cast<std::int64_t>(std::llround(1e6 * seconds)); }

}  // namespace

double camera_observed_rms_rad(double disagreement_rad) { return disagreement_rad / kDirectionRmsOverOrientationRms; }

ForearmTrack::ForearmTrack(Side side, const ForearmModel& model, bool has_model, const Quat& K_from_W,
                           const std::optional<Quat>& K_from_F_reference, double orientation_rms_rad,
                           std::optional<double> axis_rms_rad)
    : side_(side),
      model_(model),
      has_model_(has_model),
      K_from_W_(K_from_W),
      K_from_F_reference_(K_from_F_reference),
      orientation_rms_rad_(orientation_rms_rad),
      axis_rms_rad_(axis_rms_rad.value_or(kDirectionRmsOverOrientationRms * orientation_rms_rad)) {}

void ForearmTrack::set_mounting(const Quat& F_from_A, double orientation_rms_rad, std::optional<double> axis_rms_rad) {
  model_.F_from_A = F_from_A.normalized();
  mounting_changed_ = true;
  mounting_from_ = arm_.size();
  mounting_from_later_pose_ = false;
  orientation_rms_rad_ = orientation_rms_rad;
  axis_rms_rad_ = axis_rms_rad.value_or(kDirectionRmsOverOrientationRms * orientation_rms_rad);
}

void ForearmTrack::set_pronation_reference(const Quat& K_from_F_reference) {
  K_from_F_reference_ = K_from_F_reference.normalized();
  reference_from_ = arm_.size();
  mounting_changed_ = true;
  mounting_from_later_pose_ = mounting_from_ == reference_from_;
}

double ForearmTrack::pronation(std::size_t i, const Quat& K_from_F) const {
  if (!K_from_F_reference_ || i < reference_from_) return std::numeric_limits<double>::quiet_NaN();
  return pronation_angle(*K_from_F_reference_, K_from_F, side_);
}

void ForearmTrack::use_axis_correction(const VisualAxisCorrectionOptions& options) {
  if (!arm_.empty())
    throw_invalid("forearm.axis_correction", "the axis correction must be set before the first IMU sample");
  axis_correction_.emplace(options);
}

AxisCorrection ForearmTrack::axis_correction() const {
  return axis_correction_ ? axis_correction_->correction() : AxisCorrection{};
}

std::uint64_t ForearmTrack::axis_correction_frames() const {
  return axis_correction_ ? axis_correction_->frames_used() : 0;
}

std::optional<std::int64_t> ForearmTrack::oldest_queued_us() const {
  if (frames_.empty()) return std::nullopt;
  return frames_.front().t_us;
}

std::size_t ForearmTrack::held_bytes() const {
  using posefuse::held_bytes;
  return held_bytes(arm_) + held_bytes(K_from_F_imu_) + held_bytes(K_from_A_imu_) +
         held_bytes(orientation_rms_rad_of_) + held_bytes(axis_rms_rad_of_) + held_bytes(settled_rms_rad_) +
         held_bytes(filter_rms_rad_of_) + held_bytes(depth_axes_) + held_bytes(K_from_F_) + held_bytes(track_) +
         held_bytes(frames_);
}

void ForearmTrack::add_imu(const std::vector<std::int64_t>& t_us, const std::vector<Quat>& W_from_A,
                           const std::vector<Vec3>& specific_force_A,
                           const std::vector<double>& filter_uncertainty_rad) {
  for (std::size_t i = 0; i < t_us.size(); ++i) {
    if (!arm_.empty() && t_us[i] <= arm_.back().t_us) continue;                        // clock mapping kept monotonic
    const Quat K_from_A = (K_from_W_ * W_from_A[i]).normalized();                      // eq. 11
    const Quat K_from_F = K_from_F_from_imu(K_from_W_, W_from_A[i], model_.F_from_A);  // eq. 11
    arm_.push_back({t_us[i], K_from_A, specific_force_A[i]});
    K_from_A_imu_.push_back(K_from_A_imu_.empty() ? K_from_A
                                                  : geometry::same_hemisphere(K_from_A, K_from_A_imu_.back()));
    K_from_F_imu_.push_back(K_from_F_imu_.empty() ? K_from_F
                                                  : geometry::same_hemisphere(K_from_F, K_from_F_imu_.back()));
    // The filter's own uncertainty (start-up, lost samples) adds to the mounting's, independently.
    const double filter_rad = i < filter_uncertainty_rad.size() ? filter_uncertainty_rad[i] : 0.0;
    orientation_rms_rad_of_.push_back(std::hypot(orientation_rms_rad_, filter_rad));
    filter_rms_rad_of_.push_back(filter_rad);
    axis_rms_rad_of_.push_back(axis_rms_rad_);
  }
}

void ForearmTrack::add_frame(const ArmFrame& frame) { frames_.push_back(frame); }

void ForearmTrack::settle_orientations_up_to(std::int64_t t_us) {
  const AxisCorrection correction = axis_correction();
  for (std::size_t i = K_from_F_.size(); i < arm_.size() && arm_[i].t_us <= t_us; ++i) {
    K_from_F_.push_back(K_from_F_sample(i));
    settled_rms_rad_.push_back(std::max(orientation_rms_rad_of_[i], observed_rms_rad_));
    arm_[i].K_from_A = correction.K_from_A(arm_[i].K_from_A);
  }
}

void ForearmTrack::take_settled(std::vector<SettledArmSample>& out) {
  for (; settled_taken_ < K_from_F_.size(); ++settled_taken_) {
    const Quat& K_from_F = K_from_F_[settled_taken_];
    out.push_back({arm_[settled_taken_], K_from_F, pronation(settled_taken_, K_from_F),
                   settled_rms_rad_[settled_taken_], axis_rms_rad_of_[settled_taken_]});
  }
}

Quat ForearmTrack::K_from_F_sample(std::size_t i) const {
  if (i < K_from_F_.size()) return K_from_F_[i];
  return geometry::same_hemisphere(axis_correction().K_from_F(K_from_F_imu_[i]), K_from_F_imu_[i]);
}

template <class SampleAt>
Quat ForearmTrack::slerp_at(std::int64_t t_us, const SampleAt& sample_at) const {
  const std::size_t i = index_at_or_before(arm_, t_us);
  if (i == kNoIndex) return sample_at(0);
  if (i + 1 >= arm_.size()) return sample_at(i);
  const double f = static_cast<double>(t_us - arm_[i].t_us) / static_cast<double>(arm_[i + 1].t_us - arm_[i].t_us);
  return sample_at(i).slerp(f, sample_at(i + 1)).normalized();
}

Quat ForearmTrack::K_from_F_at(std::int64_t t_us) const {
  return slerp_at(t_us, [this](std::size_t i) { return K_from_F_sample(i); });
}

Quat ForearmTrack::K_from_F_imu_at(std::int64_t t_us) const {
  return slerp_at(t_us, [this](std::size_t i) { return K_from_F_imu_[i]; });
}

ForearmTrackOutput ForearmTrack::process(bool all) {
  ForearmTrackOutput out;
  const std::int64_t window_us = microseconds(kBoundaryWindowS);
  while (!frames_.empty() && !arm_.empty() && (all || frames_.front().t_us <= arm_.back().t_us)) {
    // The orientations up to this frame get the axis correction as it is before the frame.
    settle_orientations_up_to(frames_.front().t_us);
    TrackSample sample = visual_sample(frames_.front());
    // Support before it (a detection within the window): a short break in a visible run.
    const bool seen_just_before = last_visible_us_ && sample.t_us - *last_visible_us_ <= window_us;
    if (sample.visible && (track_.empty() || !track_.back().visible) && !seen_just_before) {
      const Confirmation confirmation = confirm_detection(all, window_us);
      if (confirmation == Confirmation::kWait) break;
      if (confirmation == Confirmation::kLone) {
        sample.visible = false;
        ++lone_detections_;
      }
    }
    out.frames.push_back(track_frame(frames_.front(), sample));
    frames_.pop_front();
  }
  // Orientations before the next queued frame have seen every frame before them; without a
  // queued frame they wait for one at most kMaxOrientationWaitS (IMU time), at the end not at
  // all.
  if (!arm_.empty()) {
    if (all) {
      settle_orientations_up_to(arm_.back().t_us);
    } else if (!frames_.empty()) {
      settle_orientations_up_to(frames_.front().t_us - 1);
    } else {
      settle_orientations_up_to(arm_.back().t_us - microseconds(kMaxOrientationWaitS));
    }
  }
  take_settled(out.samples);
  return out;
}

TrackSample ForearmTrack::visual_sample(const ArmFrame& frame) const {
  TrackSample sample{frame.t_us, Vec3::Zero(), false};
  if (has_model_ && frame.forearm_tracked && frame.strap_K) {
    const Quat K_from_F = K_from_F_at(frame.t_us);
    const VisualCheck check = check_visual_forearm(frame.elbow_K, frame.wrist_K, *frame.strap_K, K_from_F);
    if (check.accepted()) {
      sample.p_K = imu_position_from_strap(*frame.strap_K, frame.elbow_K, frame.wrist_K, K_from_F, model_.r_m);
      // The SDK's elbow is tracked here (forearm_tracked): a strap on another body part lies far from it.
      sample.visible = check_strap_against_elbow(sample.p_K, imu_position_from_elbow(frame.sdk_elbow_K, K_from_F,
                                                                                     model_)) == VisualRejection::kNone;
      if (sample.visible) sample.visible = continues_track(sample.p_K, frame.t_us, K_from_F);
    }
  }
  return sample;
}

bool ForearmTrack::continues_track(const Vec3& imu_K, std::int64_t t_us, const Quat& K_from_F) const {
  const OcclusionTestOptions options;
  const std::int64_t max_gap_us = microseconds(options.max_continuity_gap_s);
  // The last visible sample within the test's reach (a few frames back at most).
  for (auto previous = track_.rbegin(); previous != track_.rend() && t_us - previous->t_us <= max_gap_us; ++previous) {
    if (!previous->visible || previous->t_us >= t_us) continue;
    const Vec3 elbow = elbow_from_imu_position(imu_K, K_from_F, model_);
    const Vec3 previous_elbow = elbow_from_imu_position(previous->p_K, K_from_F_at(previous->t_us), model_);
    return check_strap_continuity(elbow, t_us, previous_elbow, previous->t_us, options) == VisualRejection::kNone;
  }
  return true;
}

ForearmTrack::Confirmation ForearmTrack::confirm_detection(bool all, std::int64_t window_us) const {
  const std::int64_t window_end_us = frames_.front().t_us + window_us;
  for (std::size_t k = 1; k < frames_.size(); ++k) {
    const ArmFrame& frame = frames_[k];
    if (frame.t_us > window_end_us) return Confirmation::kLone;
    if (!all && frame.t_us > arm_.back().t_us) return Confirmation::kWait;  // its K_from_F is not known yet
    if (visual_sample(frame).visible) return Confirmation::kConfirmed;
  }
  return all ? Confirmation::kLone : Confirmation::kWait;
}

void ForearmTrack::flag_orientation_step(TrackedArmFrame& tracked) {
  // With one mounting, K_from_F follows the IMU and the mounting it implies stays put; a change
  // (a new mounting estimate, a later pose, an axis correction, a wrong sample) shows as a step.
  // A step within the 99 % bound of the larger of the two frames' uncertainties is what they
  // allow (an uncertain mounting giving way to a better one); beyond it, the frames disagree.
  const Quat A_from_F = (tracked.K_from_A.conjugate() * tracked.K_from_F).normalized();
  const double rms_rad = tracked.orientation_rms_rad;
  if (last_frame_A_from_F_) {
    const double step_rad = geometry::angle_between(*last_frame_A_from_F_, A_from_F);
    if (step_rad > kBound99OverRms * std::max(rms_rad, last_frame_rms_rad_)) {
      tracked.orientation_step_rad = step_rad;
      tracked.orientation_rms_rad = std::max(rms_rad, step_rad);
      ++orientation_steps_;
      if (step_rad > largest_step_rad_) {
        largest_step_rad_ = step_rad;
        largest_step_us_ = tracked.frame.t_us;
      }
    }
  }
  last_frame_A_from_F_ = A_from_F;
  last_frame_rms_rad_ = rms_rad;
}

TrackedArmFrame ForearmTrack::track_frame(const ArmFrame& frame, const TrackSample& sample) {
  TrackedArmFrame tracked{frame, sample, K_from_F_at(frame.t_us), 0.0, 0.0, Quat::Identity(), 0.0};
  tracked.K_from_A = slerp_at(frame.t_us, [this](std::size_t i) { return K_from_A_imu_[i]; });
  const std::size_t i = index_at_or_before(arm_, frame.t_us);
  const std::size_t before = i == kNoIndex ? 0 : i, after = std::min(before + 1, arm_.size() - 1);
  tracked.pronation_rad = pronation(before, tracked.K_from_F);
  if (frame.axis_from_depth && frame.forearm_tracked) {
    const Vec3 axis_K = frame.wrist_K - frame.elbow_K;
    if (axis_K.norm() > 0.0 && axis_K.allFinite()) {
      const double d = std::acos(std::clamp((tracked.K_from_F * Vec3::UnitY()).dot(axis_K.normalized()), -1.0, 1.0));
      observed_rms_rad_ = camera_observed_rms_rad(d);
      if (depth_axes_.empty() || frame.t_us > depth_axes_.back().t_us) {
        depth_axes_.push_back({frame.t_us, axis_K.normalized()});
      }
    }
  }
  tracked.orientation_rms_rad =
      std::max({orientation_rms_rad_of_[before], orientation_rms_rad_of_[after], observed_rms_rad_});
  flag_orientation_step(tracked);
  if (track_.empty() || frame.t_us > track_.back().t_us) track_.push_back(sample);
  if (sample.visible) {
    ++visible_frames_;
    last_visible_us_ = frame.t_us;
    if (axis_correction_ && frame.axis_from_depth) {
      axis_correction_->observe(K_from_F_imu_at(frame.t_us), frame.elbow_K, frame.wrist_K);
    }
  }
  return tracked;
}

std::vector<SettledArmSample> ForearmTrack::offline_samples() const {
  std::vector<SettledArmSample> out;
  out.reserve(K_from_F_.size());
  if (!mounting_changed_) {
    for (std::size_t i = 0; i < K_from_F_.size(); ++i) {
      out.push_back({arm_[i], K_from_F_[i], pronation(i, K_from_F_[i]), settled_rms_rad_[i], axis_rms_rad_of_[i]});
    }
    return out;
  }
  // A changed mounting means a track without the axis correction (only a calibration at the start
  // gets one, and its mounting does not change): K_from_F is eq. 11's with the final mounting.
  const Quat A_from_F = model_.F_from_A.conjugate();
  std::vector<Quat> K_from_F(K_from_F_.size());
  for (std::size_t i = 0; i < K_from_F.size(); ++i) {
    K_from_F[i] = (K_from_A_imu_[i] * A_from_F).normalized();
    if (i > 0) K_from_F[i] = geometry::same_hemisphere(K_from_F[i], K_from_F[i - 1]);
  }
  // What each depth axis shows of the re-solved orientation at its frame.
  std::vector<double> observed_rms_rad(depth_axes_.size());
  // Samples not settled yet (offline_samples before process(true)) are not re-solved.
  const auto re_solved = [&](std::size_t i) { return K_from_F[std::min(i, K_from_F.size() - 1)]; };
  for (std::size_t k = 0; k < depth_axes_.size() && !K_from_F.empty(); ++k) {
    const Vec3 y_K = slerp_at(depth_axes_[k].t_us, re_solved) * Vec3::UnitY();
    observed_rms_rad[k] = camera_observed_rms_rad(std::acos(std::clamp(y_K.dot(depth_axes_[k].axis_K), -1.0, 1.0)));
  }
  // The filter's whole predicted error during the hold (the samples just before the pose was found).
  const double hold_imu_rms_rad =
      mounting_from_later_pose_ && mounting_from_ > 0 && mounting_from_ <= filter_rms_rad_of_.size()
          ? imu_orientation_rms_rad(filter_rms_rad_of_[mounting_from_ - 1])
          : 0.0;
  for (std::size_t i = 0; i < K_from_F.size(); ++i) {
    double rms_rad = std::hypot(orientation_rms_rad_, filter_rms_rad_of_[i]);
    if (mounting_from_later_pose_ && i < mounting_from_) {
      rms_rad = std::hypot(rms_rad, hold_imu_rms_rad, imu_orientation_rms_rad(filter_rms_rad_of_[i]));
    }
    // The frames on either side: offline, the one after the sample is known too.
    const std::size_t before = index_at_or_before(depth_axes_, arm_[i].t_us);
    if (before != kNoIndex) rms_rad = std::max(rms_rad, observed_rms_rad[before]);
    const std::size_t after = before == kNoIndex ? 0 : before + 1;
    if (after < depth_axes_.size()) rms_rad = std::max(rms_rad, observed_rms_rad[after]);
    const double pronation_rad = K_from_F_reference_ ? pronation_angle(*K_from_F_reference_, K_from_F[i], side_)
                                                     : std::numeric_limits<double>::quiet_NaN();
    out.push_back({arm_[i], K_from_F[i], pronation_rad, rms_rad, axis_rms_rad_});
  }
  return out;
}

}  // namespace posefuse::forearm
