#include "server/stream_rate.hpp"

#include <cmath>
#include <cstdio>

namespace posefuse::server {

std::optional<StreamRateShortfall> stream_rate_shortfall(const StreamRateRule& rule, double wall_s, double stream_s) {
  if (!(rule.min_rate > 0.0) || !std::isfinite(wall_s) || wall_s <= rule.grace_s || wall_s <= 0.0) {
    return std::nullopt;
  }
  const double delivered_s = std::isfinite(stream_s) && stream_s > 0.0 ? stream_s : 0.0;
  if (delivered_s >= rule.min_rate * wall_s) return std::nullopt;
  return StreamRateShortfall{wall_s, delivered_s, delivered_s / wall_s, rule.min_rate};
}

std::string describe(const StreamRateShortfall& shortfall, const StreamRateRule& rule) {
  char text[320];
  std::snprintf(text, sizeof text,
                "the session streamed %.3f s of recording in %.3f s (%.3gx real time), below the required %.3gx "
                "(--min-stream-rate; after the first %.3g s, --stream-rate-grace-s)",
                shortfall.stream_s, shortfall.wall_s, shortfall.rate, shortfall.required_rate, rule.grace_s);
  return text;
}

}  // namespace posefuse::server
