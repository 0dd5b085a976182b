#include "server/job_limits.hpp"

#include <algorithm>
#include <string>

#include "common/error.hpp"

namespace posefuse::server {

void validate_job_spec(const v1::JobSpec& spec) {
  if (spec.label().size() > kMaxLabelBytes) {
    throw_invalid("spec.label", "is " + std::to_string(spec.label().size()) + " bytes, at most " +
                                    std::to_string(kMaxLabelBytes) + " allowed");
  }
}

std::size_t effective_page_size(std::uint32_t requested) {
  return requested == 0 ? kDefaultPageSize : std::min<std::size_t>(requested, kMaxPageSize);
}

}  // namespace posefuse::server
