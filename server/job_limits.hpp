#pragma once
// Size limits on what job calls accept and return, so that one submitter cannot make a listing
// too large for every other client to receive (gRPC clients refuse messages above 4 MiB by
// default).
#include <cstddef>

#include "posefuse/v1/service.pb.h"

namespace posefuse::server {

// JobSpec.label: a short note for people, stored with the job and returned in every listing.
inline constexpr std::size_t kMaxLabelBytes = 256;

// ListJobs: jobs per page (page_size 0 = the default; larger values are cut to the maximum)
// and serialised bytes per page, a quarter of gRPC's default receive limit.
inline constexpr std::size_t kDefaultPageSize = 50;
inline constexpr std::size_t kMaxPageSize = 1000;
inline constexpr std::size_t kMaxPageBytes = 1u << 20;

// GetJobResults: results read from the store at a time; the next page is read once the last
// one has been written to the client, so a call holds at most this many whatever the job made.
inline constexpr std::size_t kResultsPageSize = 64;

// Throws kInvalidArgument naming the field ("spec.label") for a spec beyond these limits.
void validate_job_spec(const v1::JobSpec& spec);

// `job` as job calls return it: a label stored before labels were bounded is cut to
// kMaxLabelBytes (at a UTF-8 character boundary), so that no single job is too large to list.
void bound_stored_job(v1::Job& job);

// The page size ListJobs uses for a requested one.
std::size_t effective_page_size(std::uint32_t requested);

}  // namespace posefuse::server
