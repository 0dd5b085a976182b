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

void bound_stored_job(v1::Job& job) {
  if (job.label().size() <= kMaxLabelBytes) return;
  std::size_t end = kMaxLabelBytes;
  // Back off continuation bytes (10xxxxxx) so the cut label is still valid UTF-8.
  while (end > 0 && (static_cast<unsigned char>(job.label()[end]) & 0xC0) == 0x80) --end;
  job.mutable_label()->resize(end);
}

std::size_t effective_page_size(std::uint32_t requested) {
  return requested == 0 ? kDefaultPageSize : std::min<std::size_t>(requested, kMaxPageSize);
}

}  // namespace posefuse::server
