#include "fit/start_extrapolation.hpp"

#include <cmath>
#include <string>

#include "common/error.hpp"

namespace posefuse::fit {

void validate(const StartExtrapolationOptions& o) {
  const auto require = [](double value, const char* field) {
    if (!std::isfinite(value) || value < 0)
      throw_invalid(std::string("start_extrapolation.") + field,
                    std::to_string(value) + " must be finite and not negative");
  };
  require(o.velocity_gain, "velocity_gain");
  require(o.max_rotation_rad, "max_rotation_rad");
  require(o.max_translation_m, "max_translation_m");
  require(o.max_gap_ratio, "max_gap_ratio");
}

std::optional<Eigen::VectorXd> extrapolate_start(const body::PoseLayout& layout, const FittedPose& before_last,
                                                 const FittedPose& last, std::int64_t t_us,
                                                 const StartExtrapolationOptions& options) {
  validate(options);
  if (before_last.theta.size() != layout.size() || last.theta.size() != layout.size())
    throw_invalid("theta", "sizes " + std::to_string(before_last.theta.size()) + " and " +
                               std::to_string(last.theta.size()) + ", expected " + std::to_string(layout.size()));
  const double last_gap = static_cast<double>(last.t_us - before_last.t_us);
  const double gap = static_cast<double>(t_us - last.t_us);
  if (!(last_gap > 0) || !(gap > 0) || gap > options.max_gap_ratio * last_gap) return std::nullopt;
  const Eigen::VectorXd change = (options.velocity_gain * gap / last_gap) * (last.theta - before_last.theta);
  if (!change.allFinite()) return std::nullopt;
  for (int d = 0; d < layout.size(); ++d) {
    const bool translation = layout.dof(d).kind == body::DofKind::kTranslation;
    if (std::abs(change[d]) > (translation ? options.max_translation_m : options.max_rotation_rad)) return std::nullopt;
  }
  return Eigen::VectorXd(last.theta + change);
}

}  // namespace posefuse::fit
