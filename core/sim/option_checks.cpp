#include "sim/option_checks.hpp"

#include <cmath>

#include "common/error.hpp"

namespace posefuse::sim {

void require_finite(double value, const std::string& field) {
  if (!std::isfinite(value)) throw_invalid(field, "must be finite, got " + std::to_string(value));
}

void require_positive(double value, const std::string& field) {
  if (!(value > 0) || !std::isfinite(value)) {
    throw_invalid(field, "must be positive and finite, got " + std::to_string(value));
  }
}

void require_non_negative(double value, const std::string& field) {
  if (!(value >= 0) || !std::isfinite(value)) {
    throw_invalid(field, "must be finite and >= 0, got " + std::to_string(value));
  }
}

void require_probability(double value, const std::string& field) {
  if (!(value >= 0 && value <= 1)) {
    throw_invalid(field, "must be a probability in [0, 1], got " + std::to_string(value));
  }
}

void require_interval(double begin, double end, const std::string& field) {
  if (!std::isfinite(begin) || !std::isfinite(end) || end < begin) {
    throw_invalid(field, "interval [" + std::to_string(begin) + ", " + std::to_string(end) +
                             "] must be finite with end >= begin");
  }
}

}  // namespace posefuse::sim
