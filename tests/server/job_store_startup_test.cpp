// The real posefuse-server executable started on a data dir whose job store cannot be opened:
// it serves (Fit's health SERVING, the jobs' NOT_SERVING) instead of exiting, and opens the
// store once it can. The in-process server's behaviour is in job_store_faults_test.cpp; this
// one checks that main() goes the same way.
//
// The store cannot be opened because a folder stands where the database file should be: that
// stops SQLite whoever runs the test (a read-only folder does not stop root), and a full disk is
// not something a test may make.
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "client/fit_call.hpp"
#include "server/posefuse_server.hpp"
#include "tests/server/health_check.hpp"
#include "tests/server/server_process.hpp"
#include "tests/server/test_support.hpp"

namespace posefuse::server {
namespace {

namespace fs = std::filesystem;
using HealthResponse = grpc::health::v1::HealthCheckResponse;

TEST(JobStoreStartup, ServerExecutableStartsWithAnUnopenableStoreAndOpensItOnceItCan) {
  test::TempDir dir;
  const fs::path database = dir.path() / "data" / "jobs.sqlite";
  fs::create_directories(database);
  std::ofstream(database / "in-the-way") << "x";
  test::ServerProcess server(POSEFUSE_SERVER_BINARY,
                             {"--listen", "127.0.0.1:0", "--workers", "1", "--data-dir", (dir.path() / "data").string(),
                              "--job-heartbeat-s", "0.05"},
                             dir.path() / "server.log");
  const int port = server.port();
  const auto channel = client::make_channel("127.0.0.1:" + std::to_string(port));

  EXPECT_EQ(test::serving_status(channel, ""), HealthResponse::SERVING);
  EXPECT_EQ(test::serving_status(channel, v1::PoseFuse::service_full_name()), HealthResponse::SERVING);
  EXPECT_EQ(test::serving_status(channel, kJobsHealthService), HealthResponse::NOT_SERVING);
  EXPECT_NE(server.log().find("event=job_store_unavailable"), std::string::npos) << server.log();

  fs::remove_all(database);
  EXPECT_TRUE(test::wait_for_health(channel, kJobsHealthService, HealthResponse::SERVING)) << server.log();
  EXPECT_NE(server.log().find("event=job_store_opened"), std::string::npos) << server.log();
  EXPECT_TRUE(fs::is_regular_file(database));
  EXPECT_EQ(server.terminate(), 0) << server.log();
}

}  // namespace
}  // namespace posefuse::server
