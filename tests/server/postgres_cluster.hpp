#pragma once
// A private PostgreSQL cluster for one test process: initdb into a fresh folder under /tmp,
// listening on a Unix socket in that folder only (no TCP), removed with everything in it
// afterwards. Debian's server binaries live in /usr/lib/postgresql/<version>/bin. PostgreSQL
// refuses to run as root, so as root the cluster runs as the `postgres` user, owning its folder.
// Tests start one through tests/server/postgres_test.hpp.
#include <pwd.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>

#include "server/pg_connection.hpp"

namespace posefuse::test {

class PostgresCluster {
 public:
  // The newest installed server's bin folder; empty when none is.
  static std::filesystem::path find_bin_dir() {
    std::filesystem::path best;
    std::error_code ignored;
    for (const auto& entry : std::filesystem::directory_iterator("/usr/lib/postgresql", ignored)) {
      const auto bin = entry.path() / "bin";
      if (std::filesystem::exists(bin / "initdb") && std::filesystem::exists(bin / "pg_ctl") &&
          (best.empty() || entry.path().filename().string() > best.parent_path().filename().string())) {
        best = bin;
      }
    }
    return best;
  }

  // Throws std::runtime_error with the commands' output when the cluster does not start.
  explicit PostgresCluster(std::filesystem::path bin) : bin_(std::move(bin)) {
    char pattern[] = "/tmp/posefuse_pg_XXXXXX";
    if (!::mkdtemp(pattern)) throw std::runtime_error("mkdtemp failed");
    dir_ = pattern;
    if (::geteuid() == 0) {
      const passwd* postgres = ::getpwnam("postgres");
      if (!postgres) throw std::runtime_error("running as root needs the 'postgres' user to run PostgreSQL");
      if (::chown(dir_.c_str(), postgres->pw_uid, postgres->pw_gid) != 0) {
        throw std::runtime_error("cannot chown " + dir_.string() + " to postgres");
      }
      as_user_ = "runuser -u postgres -- ";
    }
    ::chmod(dir_.c_str(), 0700);
    try {
      shell(bin_ / "initdb", "-D " + data() + " -A trust -U posefuse -E UTF8 --no-sync", "initdb");
      start();
    } catch (...) {
      run_quietly("-D " + data() + " -m immediate stop");
      std::error_code ignored;
      std::filesystem::remove_all(dir_, ignored);
      throw;
    }
  }

  ~PostgresCluster() {
    if (running_) run_quietly("-D " + data() + " -m immediate stop");
    std::error_code ignored;
    std::filesystem::remove_all(dir_, ignored);
  }
  PostgresCluster(const PostgresCluster&) = delete;
  PostgresCluster& operator=(const PostgresCluster&) = delete;

  // Unix socket only, no fsync (a test cluster needs no durability against power loss).
  void start() {
    shell(bin_ / "pg_ctl",
          "-D " + data() + " -l " + (dir_ / "server.log").string() + " -w -t 60 -o \"-k " + dir_.string() +
              " -c listen_addresses= -c fsync=off -c max_connections=200\" start",
          "pg_ctl start");
    running_ = true;
  }
  // `immediate`: as a crash (no checkpoint, clients cut off at once).
  void stop(bool immediate = true) {
    shell(bin_ / "pg_ctl", "-D " + data() + " -w -m " + (immediate ? "immediate" : "fast") + " stop", "pg_ctl stop");
    running_ = false;
  }

  std::string conninfo(const std::string& database) const {
    return "host=" + dir_.string() + " user=posefuse dbname=" + database;
  }
  // A new empty database (names are ours: "t1", "t2", ...).
  std::string create_database() {
    const std::string name = "t" + std::to_string(++databases_);
    server::PgConnection admin(conninfo("postgres"));
    admin.exec("CREATE DATABASE " + name);
    return name;
  }

 private:
  std::string data() const { return (dir_ / "data").string(); }
  void shell(const std::filesystem::path& program, const std::string& args, const std::string& what) {
    const std::filesystem::path out = dir_ / "command.out";
    const std::string command = as_user_ + program.string() + " " + args + " >" + out.string() + " 2>&1";
    if (std::system(command.c_str()) != 0) {
      std::ifstream in(out);
      std::stringstream text;
      text << in.rdbuf();
      std::ifstream log(dir_ / "server.log");
      text << log.rdbuf();
      throw std::runtime_error(what + " failed: " + text.str());
    }
  }
  void run_quietly(const std::string& args) {
    const std::string command = as_user_ + (bin_ / "pg_ctl").string() + " " + args + " >/dev/null 2>&1";
    [[maybe_unused]] const int ignored = std::system(command.c_str());
  }

  std::filesystem::path bin_;
  std::filesystem::path dir_;
  std::string as_user_;
  bool running_ = false;
  int databases_ = 0;
};

}  // namespace posefuse::test
