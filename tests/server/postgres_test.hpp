#pragma once
// A PostgreSQL cluster for a test: without PostgreSQL installed the test skips, unless
// POSEFUSE_REQUIRE_POSTGRES=1 (CI), which makes that a failure.
#include <cstdlib>
#include <memory>
#include <string>

#include <gtest/gtest.h>

#include "tests/server/postgres_cluster.hpp"

namespace posefuse::test {

// For a fixture's SetUp: a running cluster, or nullptr after recording a skip (PostgreSQL not
// installed) or a failure (not installed and POSEFUSE_REQUIRE_POSTGRES=1); gtest then skips the
// test body either way.
inline std::unique_ptr<PostgresCluster> start_postgres() {
  const std::filesystem::path bin = PostgresCluster::find_bin_dir();
  if (bin.empty()) {
    const char* required = std::getenv("POSEFUSE_REQUIRE_POSTGRES");
    const std::string reason =
        "PostgreSQL is not installed (no /usr/lib/postgresql/*/bin/initdb; scripts/setup.sh "
        "installs it from scripts/packages.txt)";
    if (required && std::string(required) == "1") {
      [&]() { FAIL() << reason << " and POSEFUSE_REQUIRE_POSTGRES=1 needs it"; }();
      return nullptr;
    }
    []() { GTEST_SKIP() << "PostgreSQL is not installed"; }();
    return nullptr;
  }
  return std::make_unique<PostgresCluster>(bin);
}

}  // namespace posefuse::test
