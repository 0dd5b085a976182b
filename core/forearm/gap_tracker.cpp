#include "forearm/gap_tracker.hpp"

#include <algorithm>
#include <cmath>

#include "common/error.hpp"
#include "common/held_bytes.hpp"
#include "forearm/forearm_model.hpp"
#include "forearm/gap_input.hpp"
#include "forearm/paper_recovery.hpp"
#include "forearm/time_series.hpp"

namespace posefuse::forearm {

namespace {

// II-K.1: the boundary fits use 500 ms either side (the recoveries' default window).
constexpr double kBoundaryWindowS = 0.5;
// Only the data around a gap goes into its recovery: validation and the smoother's system stay
// small in long sessions.
constexpr std::int64_t kRecoveryMarginUs = 1'500'000;

std::int64_t microseconds(double seconds) { return static_cast<std::int64_t>(std::llround(1e6 * seconds)); }

}  // namespace

GapTracker::GapTracker(std::string label, const ForearmModel& model, bool has_model, const Quat& K_from_W,
                       const GapSmootherOptions& smoother, double live_elbow_time_constant_s)
    : label_(std::move(label)),
      model_(model),
      has_model_(has_model),
      K_from_W_(K_from_W),
      smoother_options_(smoother),
      live_elbow_time_constant_s_(live_elbow_time_constant_s) {}

void GapTracker::use_fit_anchor(const FitAnchorOptions& options) {
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

void GapTracker::add_samples(const std::vector<SettledArmSample>& samples) {
  for (const SettledArmSample& s : samples) {
    if (!arm_.empty() && s.sample.t_us <= arm_.back().t_us) continue;
    arm_.push_back(s.sample);
    K_from_F_.push_back(s.K_from_F);
  }
}

Quat GapTracker::K_from_F_at(std::int64_t t_us) const {
  if (arm_.empty()) return Quat::Identity();
  const std::size_t i = index_at_or_before(arm_, t_us);
  if (i == kNoIndex) return K_from_F_.front();
  if (i + 1 >= arm_.size()) return K_from_F_[i];
  const double f = static_cast<double>(t_us - arm_[i].t_us) / static_cast<double>(arm_[i + 1].t_us - arm_[i].t_us);
  return K_from_F_[i].slerp(f, K_from_F_[i + 1]).normalized();
}

ArmFrameEstimate GapTracker::add_frame(const TrackedArmFrame& tracked) {
  const ArmFrame& frame = tracked.frame;
  const TrackSample& sample = tracked.visual;
  const Quat& K_from_F = tracked.K_from_F;
  ArmFrameEstimate estimate{
      frame.t_us, K_from_F, tracked.pronation_rad, Vec3::Zero(), PositionSource::kNone, tracked.orientation_rms_rad};
  if (track_.empty() || frame.t_us > track_.back().t_us) track_.push_back(sample);
  if (frame.shoulder_tracked && (shoulder_.empty() || frame.t_us > shoulder_.back().t_us)) {
    shoulder_.push_back({frame.t_us, frame.shoulder_K});
  }
  // The smoother's elbow anchor (gap_smoother.hpp): the SDK elbow carried along the forearm.
  if (has_model_ && frame.sdk_elbow_seen && (elbow_anchor_.empty() || frame.t_us > elbow_anchor_.back().t_us)) {
    elbow_anchor_.push_back({frame.t_us, imu_position_from_elbow(frame.sdk_elbow_K, K_from_F, model_)});
  }

  if (sample.visible) {
    last_visible_us_ = frame.t_us;
    if (in_gap_) {
      pending_gaps_.push_back({gap_start_us_, frame.t_us});
      in_gap_ = false;
      // Kept in case this is a lone detection and the gap goes on (the next begin() then has too
      // few samples before it).
      paused_live_ = std::move(live_);
      live_.reset();
    }
    estimate.imu_K = sample.p_K;
    estimate.source = PositionSource::kVisual;
    return estimate;
  }
  if (!has_model_) return estimate;
  if (!in_gap_ && last_visible_us_) {
    in_gap_ = true;
    ++gaps_;
    gap_start_us_ = *last_visible_us_;
    live_.emplace(model_, K_from_W_);
    last_live_frame_us_ = gap_start_us_;
    try {
      live_->begin(track_, arm_, gap_start_us_);
      live_next_arm_ = index_at_or_before(arm_, gap_start_us_) + 1;
    } catch (const Error& error) {
      live_.reset();
      if (paused_live_) {
        // Seen at too few frames to start afresh: the previous gap's estimate goes on (its
        // live_next_arm_ is still where it stopped).
        live_ = std::move(paused_live_);
      } else {
        warnings_.push_back({"FOREARM_NO_LIVE_ESTIMATE", field(),
                             "gap from t_us " + std::to_string(gap_start_us_) + ": " + error.what()});
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
      const Vec3 sdk_anchor = imu_position_from_elbow(frame.sdk_elbow_K, K_from_F, model_);
      live_->correct(sdk_anchor - sdk_anchor_bias_from_fit(frame.t_us).value_or(Vec3::Zero()),
                     1.0 - std::exp(-std::max(0.0, dt_s) / live_elbow_time_constant_s_));
    }
    last_live_frame_us_ = frame.t_us;
    if (live_next_arm_ > 0 && arm_[live_next_arm_ - 1].t_us > gap_start_us_) {
      estimate.imu_K = live_->position_K();
      estimate.source = PositionSource::kPredicted;
    }
  }
  return estimate;
}

std::vector<RecoveredGapSegment> GapTracker::recover_ready(bool all) {
  std::vector<RecoveredGapSegment> out;
  const std::int64_t window_us = microseconds(kBoundaryWindowS);
  while (!pending_gaps_.empty() && !track_.empty() &&
         (all || track_.back().t_us >= pending_gaps_.front().t_end_us + window_us) &&
         fit_has_come_up_to(pending_gaps_.front().t_end_us + window_us)) {
    const PendingGap gap = pending_gaps_.front();
    pending_gaps_.erase(pending_gaps_.begin());
    // Seen too briefly after the gap to close it (a lone, mostly false, detection): the gap goes
    // on into the next one (visible_samples_after).
    const bool window_complete = track_.back().t_us >= gap.t_end_us + window_us;
    if (window_complete && visible_samples_after(track_, gap.t_end_us, kBoundaryWindowS) < 2) {
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
  return out;
}

std::vector<RecoveredGapSegment> GapTracker::finish() {
  std::vector<RecoveredGapSegment> out = recover_ready(true);
  if (in_gap_) {
    warnings_.push_back({"FOREARM_GAP_OPEN", field(),
                         "the forearm was still occluded at the end (since t_us " + std::to_string(gap_start_us_) +
                             "): that gap cannot be recovered"});
  }
  return out;
}

std::size_t GapTracker::held_bytes() const {
  using posefuse::held_bytes;
  return held_bytes(arm_) + held_bytes(K_from_F_) + held_bytes(track_) + held_bytes(shoulder_) +
         held_bytes(elbow_anchor_) + held_bytes(fit_elbows_) + held_bytes(pending_gaps_) + held_bytes(warnings_);
}

std::vector<ForearmWarning> GapTracker::take_warnings() {
  std::vector<ForearmWarning> out;
  out.swap(warnings_);
  return out;
}

void GapTracker::recover(std::int64_t t_start_us, std::int64_t t_end_us, std::vector<RecoveredGapSegment>& out) {
  const std::string where = field() + ".gap[" + std::to_string(t_start_us) + ".." + std::to_string(t_end_us) + "]";
  const std::int64_t margin_us = kRecoveryMarginUs;
  GapRecoveryInput input;
  input.track = slice(track_, t_start_us - margin_us, t_end_us + margin_us);
  occlude_inside(input.track, t_start_us, t_end_us);  // lone detections inside (recover_ready)
  input.arm = slice(arm_, t_start_us - margin_us, t_end_us + margin_us);
  input.shoulder = slice(shoulder_, t_start_us - 2 * margin_us, t_end_us + 2 * margin_us);
  // The fit's anchor where it covers at least half as many frames inside the gap as the SDK's (a
  // fit that stopped or skipped most of them leaves the gap to the SDK's).
  std::vector<ElbowAnchorSample> from_sdk = slice(elbow_anchor_, t_start_us - margin_us, t_end_us + margin_us);
  std::vector<ElbowAnchorSample> from_fit_elbows = fit_anchor_between(t_start_us - margin_us, t_end_us + margin_us);
  const auto inside_gap = [&](const std::vector<ElbowAnchorSample>& samples) {
    return std::count_if(samples.begin(), samples.end(),
                         [&](const auto& a) { return a.t_us > t_start_us && a.t_us < t_end_us; });
  };
  const bool from_fit = !from_fit_elbows.empty() && 2 * inside_gap(from_fit_elbows) >= inside_gap(from_sdk);
  GapSmootherOptions smoother_options = smoother_options_;
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
    const std::vector<GapSpan> gaps = find_gaps(input.track);
    const auto gap = std::find_if(gaps.begin(), gaps.end(), [&](const auto& g) { return g.t_start_us == t_start_us; });
    if (gap == gaps.end()) throw Error(ErrorCode::kInternal, where, "gap not found in its own track");
    const RecoveredGap paper = recover_gap_paper(input, *gap);
    const RecoveredGap smoother = recover_gap_smoother(input, *gap, smoother_options);
    for (const auto& [method, recovered] :
         {std::pair{RecoveryMethod::kPaper, &paper}, std::pair{RecoveryMethod::kSmoother, &smoother}}) {
      RecoveredGapSegment segment{method, t_start_us, t_end_us, {}};
      for (std::size_t i = 0; i < recovered->t_us.size(); ++i) {
        const Quat K_from_F = K_from_F_at(recovered->t_us[i]);
        const Vec3 strap_centre = recovered->p_K[i] - K_from_F * Vec3(model_.r_m, 0.0, 0.0);
        segment.samples.push_back({recovered->t_us[i], recovered->p_K[i],
                                   strap_centre + K_from_F * Vec3(0.0, -model_.d_se_m, 0.0),
                                   strap_centre + K_from_F * Vec3(0.0, model_.d_sw_m, 0.0), K_from_F});
      }
      out.push_back(std::move(segment));
    }
  } catch (const Error& error) {
    warnings_.push_back({"FOREARM_GAP_NOT_RECOVERED", where, error.what()});
  }
}

void GapTracker::add_fit_elbow(const FitElbow& fit) {
  if (!has_model_ || !fit_anchor_) return;  // no gaps to recover, or the SDK's anchor
  if (!fit_elbows_.empty() && fit.t_us <= fit_elbows_.back().t_us) return;
  fit_elbows_.push_back(fit);
}

bool GapTracker::fit_has_come_up_to(std::int64_t t_us) const {
  if (!fit_anchor_ || fit_finished_) return true;
  if (!fit_elbows_.empty() && fit_elbows_.back().t_us >= t_us) return true;
  // The fit may skip frames (FIT_FRAME) or stop; live results must not wait for ever.
  return !track_.empty() && track_.back().t_us > t_us + microseconds(fit_anchor_->max_wait_s);
}

std::vector<ElbowAnchorSample> GapTracker::fit_anchor_between(std::int64_t from_us, std::int64_t to_us) const {
  std::vector<ElbowAnchorSample> anchor;
  if (!fit_anchor_ || arm_.empty()) return anchor;
  const auto first = std::lower_bound(fit_elbows_.begin(), fit_elbows_.end(), std::max(from_us, arm_.front().t_us),
                                      [](const FitElbow& e, std::int64_t t) { return e.t_us < t; });
  for (auto e = first; e != fit_elbows_.end() && e->t_us <= std::min(to_us, arm_.back().t_us); ++e) {
    // A frame fitted with energy E is trusted as one with sqrt(E / reference) times the sigma.
    if (const auto a = fit_anchor_at(*e)) anchor.push_back({e->t_us, a->p_K, std::sqrt(a->variance_ratio)});
  }
  return anchor;
}

std::optional<GapTracker::FitAnchorSample> GapTracker::fit_anchor_at(const FitElbow& fit) const {
  if (!fit.elbow_K.allFinite() || !std::isfinite(fit.energy)) return std::nullopt;
  return FitAnchorSample{imu_position_from_elbow(fit.elbow_K, K_from_F_at(fit.t_us), model_),
                         std::max(1.0, fit.energy / fit_anchor_->reference_energy)};
}

std::optional<Vec3> GapTracker::sdk_anchor_bias_from_fit(std::int64_t t_us) const {
  if (!fit_anchor_ || fit_elbows_.empty()) return std::nullopt;
  const std::int64_t newest_us = fit_elbows_.back().t_us;
  if (t_us - newest_us > microseconds(fit_anchor_->live_max_age_s)) return std::nullopt;
  const std::int64_t window_us = microseconds(fit_anchor_->live_bias_window_s);
  // The SDK's anchor minus the fit's at the fit's recent frames, weighted down where the fit's
  // energy is high (variance ratio E / reference).
  Vec3 sum = Vec3::Zero();
  double weights = 0.0;
  for (auto fit = fit_elbows_.rbegin(); fit != fit_elbows_.rend() && fit->t_us >= newest_us - window_us; ++fit) {
    const auto sdk = std::lower_bound(elbow_anchor_.begin(), elbow_anchor_.end(), fit->t_us,
                                      [](const ElbowAnchorSample& a, std::int64_t t) { return a.t_us < t; });
    if (sdk == elbow_anchor_.end() || sdk->t_us != fit->t_us) continue;
    const auto a = fit_anchor_at(*fit);
    if (!a) continue;
    sum += (sdk->p_K - a->p_K) / a->variance_ratio;
    weights += 1.0 / a->variance_ratio;
  }
  if (weights <= 0.0) return std::nullopt;
  return sum / weights;
}

}  // namespace posefuse::forearm
