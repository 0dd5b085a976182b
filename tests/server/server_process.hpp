#pragma once
// The real posefuse-server executable as a child process, for tests that need several
// processes or kill -9: its stdout and stderr go to a log file, the bound port is read from the
// `event=server_start ... port=N ` line (as tests/interop/run_interop.sh does).
#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cctype>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

extern char** environ;

namespace posefuse::test {

class ServerProcess {
 public:
  ServerProcess(const std::filesystem::path& binary, const std::vector<std::string>& args, std::filesystem::path log)
      : log_(std::move(log)) {
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 1, log_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_adddup2(&actions, 1, 2);
    std::vector<std::string> argv_strings{binary.string()};
    argv_strings.insert(argv_strings.end(), args.begin(), args.end());
    std::vector<char*> argv;
    for (std::string& arg : argv_strings) argv.push_back(arg.data());
    argv.push_back(nullptr);
    const int rc = posix_spawn(&pid_, binary.c_str(), &actions, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    if (rc != 0) {
      throw std::runtime_error("cannot start " + binary.string() + " (log " + log_.string() +
                               "): " + std::strerror(rc));
    }
  }
  ~ServerProcess() {
    if (pid_ > 0) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, nullptr, 0);
    }
  }
  ServerProcess(const ServerProcess&) = delete;
  ServerProcess& operator=(const ServerProcess&) = delete;

  // The port of a complete start line (" event=server_start ... port=N "), none before it is written.
  static std::optional<int> start_port(const std::string& text) {
    const std::size_t start = text.find(" event=server_start ");
    if (start == std::string::npos) return std::nullopt;
    const std::size_t at = text.find(" port=", start);
    if (at == std::string::npos || at > text.find('\n', start)) return std::nullopt;
    std::size_t end = at + 6;
    while (end < text.size() && std::isdigit(static_cast<unsigned char>(text[end]))) ++end;
    if (end == at + 6 || end >= text.size() || text[end] != ' ') return std::nullopt;
    return std::stoi(text.substr(at + 6, end - at - 6));
  }

  // The port from the start line; throws when the process exits first or after `timeout`.
  int port(std::chrono::seconds timeout = std::chrono::seconds(60)) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (std::chrono::steady_clock::now() < deadline) {
      const std::string text = log();
      if (const std::optional<int> port = start_port(text)) return *port;
      if (exited()) throw std::runtime_error("posefuse-server exited before serving:\n" + text);
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    throw std::runtime_error("posefuse-server did not serve in time:\n" + log());
  }

  void kill9() {
    ::kill(pid_, SIGKILL);
    wait_exit();
  }
  // SIGTERM, then the exit status.
  int terminate() {
    ::kill(pid_, SIGTERM);
    return wait_exit();
  }
  // The exit status (128 + signal when killed); -1 when still running after `timeout`.
  int wait_exit(std::chrono::seconds timeout = std::chrono::seconds(60)) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (pid_ > 0 && !exited()) {
      if (std::chrono::steady_clock::now() > deadline) return -1;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return status_;
  }

  std::string log() const {
    std::ifstream in(log_);
    std::stringstream text;
    text << in.rdbuf();
    return text.str();
  }

 private:
  bool exited() {
    if (pid_ <= 0) return true;
    int status = 0;
    if (::waitpid(pid_, &status, WNOHANG) != pid_) return false;
    status_ = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    pid_ = -1;
    return true;
  }

  std::filesystem::path log_;
  pid_t pid_ = -1;
  int status_ = -1;
};

}  // namespace posefuse::test
