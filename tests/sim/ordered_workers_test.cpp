// run_ordered: results arrive in job order, job i runs on worker i % workers, workers stay within
// their look-ahead, and the first failure (in job order) stops everything and is rethrown.
#include "sim/ordered_workers.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <stdexcept>
#include <string>
#include <vector>

using posefuse::sim::run_ordered;

TEST(OrderedWorkers, ResultsInJobOrderOnTheirWorkers) {
  for (const int workers : {1, 2, 3, 5}) {
    std::vector<std::int64_t> seen;
    std::atomic<std::int64_t> produced{0};
    run_ordered<std::pair<int, std::int64_t>>(
        workers, 50, 2,
        [&](int worker, std::int64_t job) {
          ++produced;
          return std::make_pair(worker, job * job);
        },
        [&](std::int64_t job, std::pair<int, std::int64_t>& result) {
          EXPECT_EQ(result.first, job % workers);
          EXPECT_EQ(result.second, job * job);
          // No worker runs more than its look-ahead (2 jobs each) past the consumer.
          EXPECT_LE(produced.load(), job + 1 + 2 * workers);
          seen.push_back(job);
        });
    ASSERT_EQ(seen.size(), 50u) << workers;
    for (std::int64_t i = 0; i < 50; ++i) EXPECT_EQ(seen[static_cast<std::size_t>(i)], i);
  }
}

TEST(OrderedWorkers, FirstFailingJobIsRethrownAfterTheEarlierResults) {
  std::vector<std::int64_t> seen;
  try {
    run_ordered<std::int64_t>(
        3, 100, 2,
        [](int, std::int64_t job) -> std::int64_t {
          if (job == 7 || job == 9) throw std::runtime_error("job " + std::to_string(job));
          return job;
        },
        [&](std::int64_t job, std::int64_t&) { seen.push_back(job); });
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), "job 7");
  }
  EXPECT_EQ(seen, (std::vector<std::int64_t>{0, 1, 2, 3, 4, 5, 6}));
}

TEST(OrderedWorkers, ConsumerFailureStopsTheWorkers) {
  std::atomic<std::int64_t> produced{0};
  EXPECT_THROW(run_ordered<int>(
                   2, 1000, 2,
                   [&](int, std::int64_t) {
                     ++produced;
                     return 0;
                   },
                   [](std::int64_t job, int&) {
                     if (job == 3) throw std::logic_error("writer failed");
                   }),
               std::logic_error);
  EXPECT_LE(produced.load(), 4 + 2 * 2);
}
