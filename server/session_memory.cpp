#include "server/session_memory.hpp"

#include <unistd.h>

#include <algorithm>
#include <charconv>
#include <fstream>
#include <sstream>

namespace posefuse::server {

std::uint64_t session_memory_bytes(const ServerOptions& options) {
  return static_cast<std::uint64_t>(options.max_session_memory_mb * (1 << 20));
}

std::uint64_t usable_memory_bytes(std::uint64_t physical_bytes, const std::optional<std::string>& cgroup_memory_max) {
  if (!cgroup_memory_max) return physical_bytes;
  // "max" (no limit) or a byte count, with a newline.
  const std::string& text = *cgroup_memory_max;
  std::uint64_t limit = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), limit);
  if (error != std::errc{} || limit == 0) return physical_bytes;
  return std::min(physical_bytes, limit);
}

std::uint64_t usable_memory_bytes() {
  const long pages = sysconf(_SC_PHYS_PAGES), page_size = sysconf(_SC_PAGE_SIZE);
  const std::uint64_t physical =
      pages > 0 && page_size > 0 ? static_cast<std::uint64_t>(pages) * static_cast<std::uint64_t>(page_size) : 0;
  std::optional<std::string> cgroup;
  if (std::ifstream file("/sys/fs/cgroup/memory.max"); file) {
    std::ostringstream text;
    text << file.rdbuf();
    cgroup = text.str();
  }
  return usable_memory_bytes(physical, cgroup);
}

std::uint64_t default_session_memory_bytes(std::uint64_t usable_bytes, unsigned max_sessions, unsigned max_jobs) {
  constexpr std::uint64_t kAtLeast = 64ull << 20;
  const std::uint64_t share = usable_bytes / 2 / std::max(1u, max_sessions + max_jobs);
  return std::max(kAtLeast, share);
}

}  // namespace posefuse::server
