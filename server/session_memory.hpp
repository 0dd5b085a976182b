#pragma once
// The memory budget of one Fit session or job (--max-session-memory-mb, docs/server.md "Hostile
// input and faults"): what its pipeline holds for later frames (session::PipelineOptions::
// max_held_bytes), so that sessions sending frames far faster than a camera, or asking for long
// windows, end with RESOURCE_EXHAUSTED instead of taking the machine's memory from the others.
#include <cstdint>
#include <optional>
#include <string>

#include "server/server_options.hpp"

namespace posefuse::server {

// --max-session-memory-mb in bytes (resolved: PoseFuseServer replaces 0 by the default).
std::uint64_t session_memory_bytes(const ServerOptions& options);

// The memory this process may use: physical memory, or the cgroup's limit (a container's
// memory.max, `cgroup_memory_max`'s content) where that is lower.
std::uint64_t usable_memory_bytes(std::uint64_t physical_bytes, const std::optional<std::string>& cgroup_memory_max);
// The same for this machine and this process's cgroup (/sys/fs/cgroup/memory.max).
std::uint64_t usable_memory_bytes();

// The default budget: half the usable memory split evenly between the sessions and jobs that may
// run at once, so that together they cannot exhaust it; the other half is for what the budget
// does not count (the body model, messages in flight, queued results, allocator slack). At least
// 64 MiB.
std::uint64_t default_session_memory_bytes(std::uint64_t usable_bytes, unsigned max_sessions, unsigned max_jobs);

}  // namespace posefuse::server
