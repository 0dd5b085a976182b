// The default memory budget of a session (server/session_memory.hpp): half the usable memory,
// split between the sessions and jobs that may run at once; a container's cgroup limit counts.
#include <gtest/gtest.h>

#include "server/session_memory.hpp"

namespace posefuse::server {
namespace {

constexpr std::uint64_t kGiB = 1ull << 30;

TEST(SessionMemory, ACgroupLimitBelowThePhysicalMemoryIsWhatIsUsable) {
  EXPECT_EQ(usable_memory_bytes(24 * kGiB, std::nullopt), 24 * kGiB);
  EXPECT_EQ(usable_memory_bytes(24 * kGiB, "max\n"), 24 * kGiB);
  EXPECT_EQ(usable_memory_bytes(24 * kGiB, "4294967296\n"), 4 * kGiB);
  EXPECT_EQ(usable_memory_bytes(4 * kGiB, "68719476736\n"), 4 * kGiB);
  EXPECT_EQ(usable_memory_bytes(4 * kGiB, ""), 4 * kGiB);
  EXPECT_EQ(usable_memory_bytes(4 * kGiB, "0\n"), 4 * kGiB);
  EXPECT_GT(usable_memory_bytes(), 0u);
}

TEST(SessionMemory, TheDefaultBudgetSplitsHalfTheMemoryBetweenSessionsAndJobs) {
  // 16 sessions and 1 job on 24 GiB: 12 GiB / 17.
  EXPECT_EQ(default_session_memory_bytes(24 * kGiB, 16, 1), 12 * kGiB / 17);
  EXPECT_EQ(default_session_memory_bytes(2 * kGiB, 1, 1), kGiB / 2);
  // Never below 64 MiB, whatever the counts.
  EXPECT_EQ(default_session_memory_bytes(kGiB, 1000, 1), 64ull << 20);
}

TEST(SessionMemory, TheFlagIsInMiB) {
  ServerOptions options;
  options.max_session_memory_mb = 512;
  EXPECT_EQ(session_memory_bytes(options), 512ull << 20);
}

}  // namespace
}  // namespace posefuse::server
