#include "session/stages/arm_tracker.hpp"

#include <algorithm>
#include <cmath>

#include "common/error.hpp"
#include "forearm/forearm_model.hpp"
#include "forearm/gap_smoother.hpp"
#include "forearm/paper_recovery.hpp"
#include "session/stages/proto_values.hpp"

namespace posefuse::session {

namespace {

using forearm::Quat;
using forearm::Vec3;

// II-K.1: the boundary fits use 500 ms either side (the recoveries' default window).
constexpr double kBoundaryWindowS = 0.5;
// With the axis correction, how long (IMU time) an orientation waits for camera frames.
constexpr double kMaxOrientationWaitS = 1.0;

v1::Arm arm_enum(forearm::Side side) { return side == forearm::Side::kLeft ? v1::LEFT : v1::RIGHT; }

// Index of the last sample at or before t (samples sorted by t_us); npos when none.
template <class Series>
std::size_t index_at_or_before(const Series& series, std::int64_t t_us) {
  const auto it = std::upper_bound(series.begin(), series.end(), t_us,
                                   [](std::int64_t t, const auto& s) { return t < s.t_us; });
  return it == series.begin() ? static_cast<std::size_t>(-1) : static_cast<std::size_t>(it - series.begin() - 1);
}

// The samples of `series` with t in [t0, t1].
template <class Series>
Series slice(const Series& series, std::int64_t t0_us, std::int64_t t1_us) {
  Series out;
  for (const auto& s : series) {
    if (s.t_us >= t0_us && s.t_us <= t1_us) out.push_back(s);
  }
  return out;
}

}  // namespace

ArmTracker::ArmTracker(std::string device_id, forearm::Side side, const forearm::ForearmModel& model,
                       bool has_model, const Quat& K_from_W, const Quat& K_from_F_reference,
                       const forearm::GapSmootherOptions& smoother, double live_elbow_time_constant_s)
    : device_id_(std::move(device_id)),
      side_(side),
      model_(model),
      has_model_(has_model),
      K_from_W_(K_from_W),
      K_from_F_reference_(K_from_F_reference),
      smoother_options_(smoother),
      live_elbow_time_constant_s_(live_elbow_time_constant_s) {}

std::string ArmTracker::field() const { return "forearm[" + device_id_ + "]"; }

void ArmTracker::add_imu(const std::vector<std::int64_t>& t_us, const std::vector<Quat>& W_from_A,
                         const std::vector<Vec3>& specific_force_A, StageOutput& out) {
  for (std::size_t i = 0; i < t_us.size(); ++i) {
    if (!arm_.empty() && t_us[i] <= arm_.back().t_us) continue;  // clock mapping kept monotonic
    const forearm::ForearmSample s =
        forearm::forearm_sample(K_from_W_, W_from_A[i], model_.F_from_A, K_from_F_reference_, side_);
    arm_.push_back({t_us[i], s.K_from_A, specific_force_A[i]});
    K_from_F_imu_.push_back(K_from_F_imu_.empty() ? s.K_from_F
                                                  : geometry::same_hemisphere(s.K_from_F, K_from_F_imu_.back()));
  }
  // Without the axis correction nothing waits for the frames.
  if (!axis_correction_ && !arm_.empty()) {
    settle_orientations_up_to(arm_.back().t_us);
    emit_settled_orientations(out);
  }
}

void ArmTracker::settle_orientations_up_to(std::int64_t t_us) {
  const forearm::AxisCorrection correction = axis_correction();
  for (std::size_t i = K_from_F_.size(); i < arm_.size() && arm_[i].t_us <= t_us; ++i) {
    K_from_F_.push_back(K_from_F_sample(i));
    arm_[i].K_from_A = correction.K_from_A(arm_[i].K_from_A);
  }
}

void ArmTracker::emit_settled_orientations(StageOutput& out) {
  if (orientations_emitted_ == K_from_F_.size()) return;
  ForearmOrientations batch{device_id_, arm_enum(side_), {}, {}, {}};
  for (; orientations_emitted_ < K_from_F_.size(); ++orientations_emitted_) {
    const Quat& K_from_F = K_from_F_[orientations_emitted_];
    batch.t_us.push_back(arm_[orientations_emitted_].t_us);
    batch.K_from_F.push_back(K_from_F);
    batch.pronation_rad.push_back(forearm::pronation_angle(K_from_F_reference_, K_from_F, side_));
  }
  out.hand_on(std::move(batch));
}

Quat ArmTracker::K_from_F_sample(std::size_t i) const {
  if (i < K_from_F_.size()) return K_from_F_[i];
  return geometry::same_hemisphere(axis_correction().K_from_F(K_from_F_imu_[i]), K_from_F_imu_[i]);
}

std::vector<forearm::ArmSample> ArmTracker::arm_between(std::int64_t t0_us, std::int64_t t1_us) const {
  std::vector<forearm::ArmSample> samples = slice(arm_, t0_us, t1_us);
  // The settled samples are arm_'s first K_from_F_.size(); the later ones still hold eq. 11's
  // K_from_A: corrected as they will be.
  const forearm::AxisCorrection correction = axis_correction();
  for (forearm::ArmSample& sample : samples) {
    if (K_from_F_.empty() || sample.t_us > arm_[K_from_F_.size() - 1].t_us) {
      sample.K_from_A = correction.K_from_A(sample.K_from_A);
    }
  }
  return samples;
}

template <class SampleAt>
Quat ArmTracker::slerp_at(std::int64_t t_us, const SampleAt& sample_at) const {
  const std::size_t i = index_at_or_before(arm_, t_us);
  if (i == static_cast<std::size_t>(-1)) return sample_at(0);
  if (i + 1 >= arm_.size()) return sample_at(i);
  const double f = static_cast<double>(t_us - arm_[i].t_us) / static_cast<double>(arm_[i + 1].t_us - arm_[i].t_us);
  return sample_at(i).slerp(f, sample_at(i + 1)).normalized();
}

Quat ArmTracker::K_from_F_at(std::int64_t t_us) const {
  return slerp_at(t_us, [this](std::size_t i) { return K_from_F_sample(i); });
}

Quat ArmTracker::K_from_F_imu_at(std::int64_t t_us) const {
  return slerp_at(t_us, [this](std::size_t i) { return K_from_F_imu_[i]; });
}

void ArmTracker::use_axis_correction(const forearm::VisualAxisCorrectionOptions& options) {
  if (!arm_.empty()) throw_invalid(field(), "the axis correction must be set before the first IMU sample");
  axis_correction_.emplace(options);
}

forearm::AxisCorrection ArmTracker::axis_correction() const {
  return axis_correction_ ? axis_correction_->correction() : forearm::AxisCorrection{};
}

std::uint64_t ArmTracker::axis_correction_frames() const {
  return axis_correction_ ? axis_correction_->frames_used() : 0;
}

double ArmTracker::pronation_at(std::int64_t t_us) const {
  return forearm::pronation_angle(K_from_F_reference_, K_from_F_at(t_us), side_);
}

void ArmTracker::process(bool all, StageOutput& out) {
  const std::int64_t window_us = static_cast<std::int64_t>(std::llround(1e6 * kBoundaryWindowS));
  while (!frames_.empty() && !arm_.empty() && (all || frames_.front().t_us <= arm_.back().t_us)) {
    // The orientations up to this frame get the axis correction as it is before the frame.
    settle_orientations_up_to(frames_.front().t_us);
    forearm::TrackSample sample = visual_sample(frames_.front());
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
    process_frame(frames_.front(), sample, out);
    frames_.pop_front();
  }
  // Orientations before the next queued frame have seen every frame before them; without a
  // queued frame they wait for one at most kMaxOrientationWaitS (IMU time), at the end not at all.
  if (!arm_.empty()) {
    const auto max_wait_us = static_cast<std::int64_t>(std::llround(1e6 * kMaxOrientationWaitS));
    if (all) {
      settle_orientations_up_to(arm_.back().t_us);
    } else if (!frames_.empty()) {
      settle_orientations_up_to(frames_.front().t_us - 1);
    } else {
      settle_orientations_up_to(arm_.back().t_us - max_wait_us);
    }
    emit_settled_orientations(out);  // one batch per call
  }
  while (!pending_gaps_.empty() && !track_.empty() &&
         (all || track_.back().t_us >= pending_gaps_.front().t_end_us + window_us) &&
         fit_has_come_up_to(pending_gaps_.front().t_end_us + window_us)) {
    const PendingGap gap = pending_gaps_.front();
    pending_gaps_.erase(pending_gaps_.begin());
    // Seen too briefly after the gap to close it (a lone, mostly false, detection): the gap goes
    // on into the next one (forearm::visible_samples_after).
    const bool window_complete = track_.back().t_us >= gap.t_end_us + window_us;
    if (window_complete && forearm::visible_samples_after(track_, gap.t_end_us, kBoundaryWindowS) < 2) {
      if (!pending_gaps_.empty()) {
        pending_gaps_.front().t_start_us = gap.t_start_us;
        continue;
      }
      if (in_gap_) {
        gap_start_us_ = gap.t_start_us;
        continue;
      }
    }
    recover(gap.t_start_us, gap.t_end_us, out);
  }
}

forearm::TrackSample ArmTracker::visual_sample(const ArmFrame& frame) const {
  forearm::TrackSample sample{frame.t_us, Vec3::Zero(), false};
  if (has_model_ && frame.forearm_tracked && frame.strap_K) {
    const Quat K_from_F = K_from_F_at(frame.t_us);
    const forearm::VisualCheck check = forearm::check_visual_forearm(frame.elbow_K, frame.wrist_K, *frame.strap_K, K_from_F);
    if (check.accepted()) {
      sample.p_K = forearm::imu_position_from_strap(*frame.strap_K, frame.elbow_K, frame.wrist_K, K_from_F, model_.r_m);
      // The SDK's elbow is tracked here (forearm_tracked): a strap on another body part lies far from it.
      sample.visible = forearm::check_strap_against_elbow(sample.p_K, forearm::imu_position_from_elbow(
                                                                          frame.sdk_elbow_K, K_from_F, model_)) ==
                       forearm::VisualRejection::kNone;
      if (sample.visible) sample.visible = continues_track(sample.p_K, frame.t_us, K_from_F);
    }
  }
  return sample;
}

bool ArmTracker::continues_track(const Vec3& imu_K, std::int64_t t_us, const Quat& K_from_F) const {
  const forearm::OcclusionTestOptions options;
  const auto max_gap_us = static_cast<std::int64_t>(std::llround(1e6 * options.max_continuity_gap_s));
  // The last visible sample within the test's reach (a few frames back at most).
  for (auto previous = track_.rbegin(); previous != track_.rend() && t_us - previous->t_us <= max_gap_us; ++previous) {
    if (!previous->visible || previous->t_us >= t_us) continue;
    const Vec3 elbow = forearm::elbow_from_imu_position(imu_K, K_from_F, model_);
    const Vec3 previous_elbow = forearm::elbow_from_imu_position(previous->p_K, K_from_F_at(previous->t_us), model_);
    return forearm::check_strap_continuity(elbow, t_us, previous_elbow, previous->t_us, options) ==
           forearm::VisualRejection::kNone;
  }
  return true;
}

ArmTracker::Confirmation ArmTracker::confirm_detection(bool all, std::int64_t window_us) const {
  const std::int64_t window_end_us = frames_.front().t_us + window_us;
  for (std::size_t k = 1; k < frames_.size(); ++k) {
    const ArmFrame& frame = frames_[k];
    if (frame.t_us > window_end_us) return Confirmation::kLone;
    if (!all && frame.t_us > arm_.back().t_us) return Confirmation::kWait;  // its K_from_F is not known yet
    if (visual_sample(frame).visible) return Confirmation::kConfirmed;
  }
  return all ? Confirmation::kLone : Confirmation::kWait;
}

void ArmTracker::process_frame(const ArmFrame& frame, const forearm::TrackSample& sample, StageOutput& out) {
  const Quat K_from_F = K_from_F_at(frame.t_us);
  if (track_.empty() || frame.t_us > track_.back().t_us) track_.push_back(sample);
  if (frame.shoulder_tracked && (shoulder_.empty() || frame.t_us > shoulder_.back().t_us)) {
    shoulder_.push_back({frame.t_us, frame.shoulder_K});
  }
  // The smoother's elbow anchor (gap_smoother.hpp): the SDK elbow carried along the forearm.
  if (has_model_ && frame.sdk_elbow_seen && (elbow_anchor_.empty() || frame.t_us > elbow_anchor_.back().t_us)) {
    elbow_anchor_.push_back({frame.t_us, forearm::imu_position_from_elbow(frame.sdk_elbow_K, K_from_F, model_)});
  }

  v1::FitResult result;
  v1::FrameResult& out_frame = *result.mutable_frame();
  out_frame.set_t_us(frame.t_us);
  v1::ForearmOrientation& orientation = *out_frame.add_forearms();
  orientation.set_arm(arm_enum(side_));
  *orientation.mutable_k_from_f() = to_proto(K_from_F);
  orientation.set_pronation_rad(pronation_at(frame.t_us));
  orientation.set_source(v1::FUSED);
  orientation.set_confidence(1.0);

  std::optional<Vec3> position;
  v1::Source source = v1::SOURCE_UNSPECIFIED;
  if (sample.visible) {
    ++visible_frames_;
    last_visible_us_ = frame.t_us;
    if (axis_correction_ && frame.axis_from_depth) {
      axis_correction_->observe(K_from_F_imu_at(frame.t_us), frame.elbow_K, frame.wrist_K);
    }
    if (in_gap_) {
      pending_gaps_.push_back({gap_start_us_, frame.t_us});
      in_gap_ = false;
      // Kept in case this is a lone detection and the gap goes on (the next begin() then has too
      // few samples before it).
      paused_live_ = std::move(live_);
      live_.reset();
    }
    position = sample.p_K;
    source = v1::VISUAL;
  } else if (has_model_) {
    if (!in_gap_ && last_visible_us_) {
      in_gap_ = true;
      ++gaps_;
      gap_start_us_ = *last_visible_us_;
      live_.emplace(model_, K_from_W_);
      last_live_frame_us_ = gap_start_us_;
      try {
        live_->begin(track_, arm_, gap_start_us_);  // settled up to this frame: corrected
        live_next_arm_ = index_at_or_before(arm_, gap_start_us_) + 1;
      } catch (const Error& error) {
        live_.reset();
        if (paused_live_) {
          // Seen at too few frames to start afresh: the previous gap's estimate goes on (its
          // live_next_arm_ is still where it stopped).
          live_ = std::move(paused_live_);
        } else {
          out.warn("FOREARM_NO_LIVE_ESTIMATE", field(),
                   std::string("gap from t_us ") + std::to_string(gap_start_us_) + ": " + error.what());
        }
      }
      paused_live_.reset();
    }
    if (in_gap_ && live_) {
      const Vec3 shoulder = shoulder_.empty() ? frame.shoulder_K : shoulder_.back().p_K;
      while (live_next_arm_ < arm_.size() && arm_[live_next_arm_].t_us <= frame.t_us) {
        live_->update(arm_[live_next_arm_], shoulder);
        ++live_next_arm_;
      }
      // The SDK's elbow with the IMU's forearm axis bounds the integration's drift (live_gap.hpp),
      // less its bias where the fit's recent frames measure it (sdk_anchor_bias_from_fit).
      if (frame.sdk_elbow_seen && live_elbow_time_constant_s_ > 0.0 && last_live_frame_us_) {
        const double dt_s = 1e-6 * static_cast<double>(frame.t_us - *last_live_frame_us_);
        const Vec3 sdk_anchor = forearm::imu_position_from_elbow(frame.sdk_elbow_K, K_from_F, model_);
        live_->correct(sdk_anchor - sdk_anchor_bias_from_fit(frame.t_us).value_or(Vec3::Zero()),
                       1.0 - std::exp(-std::max(0.0, dt_s) / live_elbow_time_constant_s_));
      }
      last_live_frame_us_ = frame.t_us;
      if (live_next_arm_ > 0 && arm_[live_next_arm_ - 1].t_us > gap_start_us_) {
        position = live_->position_K();
        source = v1::PREDICTED;
      }
    }
  }
  if (position) {
    v1::ImuPosition& p = *out_frame.add_imu_positions();
    p.set_device_id(device_id_);
    *p.mutable_position_m() = to_proto(*position);
    p.set_source(source);
  }
  out.emit(std::move(result));
}

void ArmTracker::recover(std::int64_t t_start_us, std::int64_t t_end_us, StageOutput& out) {
  const std::string where = field() + ".gap[" + std::to_string(t_start_us) + ".." + std::to_string(t_end_us) + "]";
  // Only the data around the gap: validation and the smoother's system stay small in long sessions.
  const std::int64_t margin_us = 1'500'000;
  forearm::GapRecoveryInput input;
  input.track = slice(track_, t_start_us - margin_us, t_end_us + margin_us);
  forearm::occlude_inside(input.track, t_start_us, t_end_us);  // lone detections inside (process)
  input.arm = arm_between(t_start_us - margin_us, t_end_us + margin_us);
  input.shoulder = slice(shoulder_, t_start_us - 2 * margin_us, t_end_us + 2 * margin_us);
  // The fit's anchor where it covers at least half as many frames inside the gap as the SDK's (a
  // fit that stopped or skipped most of them leaves the gap to the SDK's).
  std::vector<forearm::ElbowAnchorSample> from_sdk = slice(elbow_anchor_, t_start_us - margin_us, t_end_us + margin_us);
  std::vector<forearm::ElbowAnchorSample> from_fit_elbows = fit_anchor_between(t_start_us - margin_us, t_end_us + margin_us);
  const auto inside_gap = [&](const std::vector<forearm::ElbowAnchorSample>& samples) {
    return std::count_if(samples.begin(), samples.end(),
                         [&](const auto& a) { return a.t_us > t_start_us && a.t_us < t_end_us; });
  };
  const bool from_fit = !from_fit_elbows.empty() && 2 * inside_gap(from_fit_elbows) >= inside_gap(from_sdk);
  forearm::GapSmootherOptions smoother_options = smoother_options_;
  if (from_fit) {
    input.elbow_anchor = std::move(from_fit_elbows);
    // The SDK's elbow alongside, with the SDK's sigmas and its own error line: where the fit goes
    // wrong behind the back, the two disagree (FitAnchorOptions::sdk_as_second_anchor).
    if (fit_anchor_->sdk_as_second_anchor) {
      input.second_elbow_anchor = std::move(from_sdk);
      smoother_options.second_anchor_sigma_m = smoother_options_.anchor_sigma_m;
      smoother_options.second_anchor_bias_prior_sigma_m = smoother_options_.anchor_bias_prior_sigma_m;
    }
    smoother_options.anchor_sigma_m = fit_anchor_->sigma_m;
    smoother_options.anchor_bias_prior_sigma_m = fit_anchor_->bias_prior_sigma_m;
  } else {
    input.elbow_anchor = std::move(from_sdk);
  }
  input.model = model_;
  input.K_from_W = K_from_W_;
  try {
    const std::vector<forearm::GapSpan> gaps = forearm::find_gaps(input.track);
    const auto gap = std::find_if(gaps.begin(), gaps.end(), [&](const auto& g) { return g.t_start_us == t_start_us; });
    if (gap == gaps.end()) throw Error(ErrorCode::kInternal, where, "gap not found in its own track");
    const forearm::RecoveredGap paper = forearm::recover_gap_paper(input, *gap);
    const forearm::RecoveredGap smoother = forearm::recover_gap_smoother(input, *gap, smoother_options);
    for (const auto& [method, recovered] :
         {std::pair{v1::RecoveredSegment::PAPER, &paper}, std::pair{v1::RecoveredSegment::SMOOTHER, &smoother}}) {
      v1::FitResult result;
      v1::RecoveredSegment& segment = *result.mutable_recovered_segment();
      segment.set_arm(arm_enum(side_));
      segment.set_device_id(device_id_);
      segment.set_method(method);
      segment.set_t_start_us(t_start_us);
      segment.set_t_end_us(t_end_us);
      for (std::size_t i = 0; i < recovered->t_us.size(); ++i) {
        const Quat K_from_F = K_from_F_at(recovered->t_us[i]);
        const Vec3 strap_centre = recovered->p_K[i] - K_from_F * Vec3(model_.r_m, 0.0, 0.0);
        v1::RecoveredSegment::Sample& s = *segment.add_samples();
        s.set_t_us(recovered->t_us[i]);
        *s.mutable_imu_m() = to_proto(recovered->p_K[i]);
        *s.mutable_elbow_m() = to_proto(strap_centre + K_from_F * Vec3(0.0, -model_.d_se_m, 0.0));
        *s.mutable_wrist_m() = to_proto(strap_centre + K_from_F * Vec3(0.0, model_.d_sw_m, 0.0));
        *s.mutable_k_from_f() = to_proto(K_from_F);
      }
      out.emit(std::move(result));
    }
  } catch (const Error& error) {
    out.warn("FOREARM_GAP_NOT_RECOVERED", where, error.what());
  }
}

void ArmTracker::use_fit_anchor(const FitAnchorOptions& options) {
  if (!(options.sigma_m > 0.0) || !(options.reference_energy > 0.0) || !(options.bias_prior_sigma_m > 0.0) ||
      !(options.max_wait_s >= 0.0) || !(options.live_max_age_s >= 0.0) || !(options.live_bias_window_s >= 0.0) ||
      !std::isfinite(options.sigma_m + options.reference_energy + options.bias_prior_sigma_m + options.max_wait_s +
                     options.live_max_age_s + options.live_bias_window_s)) {
    throw_invalid(field() + ".fit_anchor",
                  "sigma_m, reference_energy and bias_prior_sigma_m must be positive and finite, max_wait_s, "
                  "live_max_age_s and live_bias_window_s >= 0");
  }
  fit_anchor_ = options;
}

void ArmTracker::add_fit_elbow(std::int64_t t_us, const Vec3& elbow_K, double fit_energy) {
  if (!has_model_ || !fit_anchor_) return;  // no gaps to recover, or the SDK's anchor
  if (!fit_elbows_.empty() && t_us <= fit_elbows_.back().t_us) return;
  fit_elbows_.push_back({t_us, elbow_K, fit_energy});
}

bool ArmTracker::fit_has_come_up_to(std::int64_t t_us) const {
  if (!fit_anchor_ || fit_finished_) return true;
  if (!fit_elbows_.empty() && fit_elbows_.back().t_us >= t_us) return true;
  // The fit may skip frames (FIT_FRAME) or stop; live results must not wait for ever.
  const auto max_wait_us = static_cast<std::int64_t>(std::llround(1e6 * fit_anchor_->max_wait_s));
  return !track_.empty() && track_.back().t_us > t_us + max_wait_us;
}

std::vector<forearm::ElbowAnchorSample> ArmTracker::fit_anchor_between(std::int64_t from_us, std::int64_t to_us) const {
  std::vector<forearm::ElbowAnchorSample> anchor;
  if (!fit_anchor_ || arm_.empty()) return anchor;
  const auto first = std::lower_bound(fit_elbows_.begin(), fit_elbows_.end(), std::max(from_us, arm_.front().t_us),
                                      [](const FitElbow& e, std::int64_t t) { return e.t_us < t; });
  for (auto e = first; e != fit_elbows_.end() && e->t_us <= std::min(to_us, arm_.back().t_us); ++e) {
    // A frame fitted with energy E is trusted as one with sqrt(E / reference) times the sigma.
    if (const auto a = fit_anchor_at(*e)) anchor.push_back({e->t_us, a->p_K, std::sqrt(a->variance_ratio)});
  }
  return anchor;
}

std::optional<ArmTracker::FitAnchorSample> ArmTracker::fit_anchor_at(const FitElbow& fit) const {
  if (!fit.elbow_K.allFinite() || !std::isfinite(fit.energy)) return std::nullopt;
  return FitAnchorSample{forearm::imu_position_from_elbow(fit.elbow_K, K_from_F_at(fit.t_us), model_),
                         std::max(1.0, fit.energy / fit_anchor_->reference_energy)};
}

std::optional<Vec3> ArmTracker::sdk_anchor_bias_from_fit(std::int64_t t_us) const {
  if (!fit_anchor_ || fit_elbows_.empty()) return std::nullopt;
  const auto max_age_us = static_cast<std::int64_t>(std::llround(1e6 * fit_anchor_->live_max_age_s));
  const std::int64_t newest_us = fit_elbows_.back().t_us;
  if (t_us - newest_us > max_age_us) return std::nullopt;
  const auto window_us = static_cast<std::int64_t>(std::llround(1e6 * fit_anchor_->live_bias_window_s));
  // The SDK's anchor minus the fit's at the fit's recent frames, weighted down where the fit's
  // energy is high (variance ratio E / reference).
  Vec3 sum = Vec3::Zero();
  double weights = 0.0;
  for (auto fit = fit_elbows_.rbegin(); fit != fit_elbows_.rend() && fit->t_us >= newest_us - window_us; ++fit) {
    const auto sdk = std::lower_bound(elbow_anchor_.begin(), elbow_anchor_.end(), fit->t_us,
                                      [](const forearm::ElbowAnchorSample& a, std::int64_t t) { return a.t_us < t; });
    if (sdk == elbow_anchor_.end() || sdk->t_us != fit->t_us) continue;
    const auto a = fit_anchor_at(*fit);
    if (!a) continue;
    sum += (sdk->p_K - a->p_K) / a->variance_ratio;
    weights += 1.0 / a->variance_ratio;
  }
  if (weights <= 0.0) return std::nullopt;
  return sum / weights;
}

void ArmTracker::finish_late(StageOutput& out) {
  fit_finished_ = true;
  process(true, out);
}

void ArmTracker::finish(StageOutput& out) {
  process(true, out);
  if (in_gap_) {
    out.warn("FOREARM_GAP_OPEN", field(),
             "the forearm was still occluded at the end (since t_us " + std::to_string(gap_start_us_) +
                 "): that gap cannot be recovered");
  }
}

}  // namespace posefuse::session
