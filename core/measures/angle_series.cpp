#include "measures/angle_series.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "common/held_bytes.hpp"

namespace posefuse::measures {

AngleSeries::AngleSeries(std::optional<Angle> angle) : named_(angle) {
  if (angle) {
    candidates_ = {*angle};
  } else {
    candidates_ = {Angle::kLeftElevation,     Angle::kRightElevation,    Angle::kLeftElbowFlexion,
                   Angle::kRightElbowFlexion, Angle::kLeftPronation,     Angle::kRightPronation,
                   Angle::kThoraxFlexion,     Angle::kThoraxLateralTilt, Angle::kThoraxAxialRotation};
  }
  series_deg_.assign(candidates_.size(), {});
  confidence_.assign(candidates_.size(), {});
}

bool AngleSeries::add(double t_s, const JointAngles& angles) {
  if (!t_s_.empty() && !(t_s > t_s_.back())) return false;
  t_s_.push_back(t_s);
  for (std::size_t c = 0; c < candidates_.size(); ++c) {
    const AngleValue& a = angles[static_cast<std::size_t>(candidates_[c])];
    const bool usable = a.defined && !a.held;
    series_deg_[c].push_back(usable ? a.deg : std::numeric_limits<double>::quiet_NaN());
    confidence_[c].push_back(
        usable ? static_cast<float>(std::isfinite(a.confidence) ? std::clamp(a.confidence, 0.0, 1.0) : 0.0) : 0.0f);
  }
  return true;
}

std::size_t AngleSeries::held_bytes() const {
  std::size_t held = posefuse::held_bytes(t_s_) + posefuse::held_bytes(series_deg_) + posefuse::held_bytes(confidence_);
  for (const std::vector<double>& series : series_deg_) held += posefuse::held_bytes(series);
  for (const std::vector<float>& series : confidence_) held += posefuse::held_bytes(series);
  return held;
}

std::optional<SessionRepetitions> AngleSeries::repetitions(const RepetitionOptions& options) const {
  if (t_s_.empty()) return std::nullopt;
  int chosen = 0;
  if (!named_) {
    chosen = dominant_series(series_deg_, confidence_, options.min_amplitude_deg);
    if (chosen < 0) return std::nullopt;
  }
  SessionRepetitions out;
  out.angle = candidates_[static_cast<std::size_t>(chosen)];
  out.detected = !named_;
  const auto c = static_cast<std::size_t>(chosen);
  out.summary = segment_repetitions(t_s_, series_deg_[c], options, confidence_[c]);
  return out;
}

}  // namespace posefuse::measures
