#pragma once
// Argument checks shared by the simulator's option structs: each throws posefuse::Error
// (kInvalidArgument) naming the field and the value.
#include <string>

namespace posefuse::sim {

void require_finite(double value, const std::string& field);
void require_positive(double value, const std::string& field);      // > 0 and finite
void require_non_negative(double value, const std::string& field);  // >= 0 and finite
void require_probability(double value, const std::string& field);   // in [0, 1]
// begin and end finite, end >= begin; `field` names the end.
void require_interval(double begin, double end, const std::string& field);

}  // namespace posefuse::sim
