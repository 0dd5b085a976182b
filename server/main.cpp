// posefuse-server: serves posefuse.v1.PoseFuse, grpc.health.v1.Health and server reflection.
// Flags: docs/server.md. Stops gracefully on SIGINT or SIGTERM.
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>
#include <vector>

#include "common/error.hpp"
#include "server/log.hpp"
#include "server/posefuse_server.hpp"
#include "server/server_config.hpp"

namespace {

constexpr const char* kUsage =
    "usage: posefuse-server [--config FILE] [--listen HOST:PORT] [--workers N] [--max-sessions N]\n"
    "                       [--tenant-max-sessions N] [--max-message-mb MB] [--idle-timeout-s S]\n"
    "                       [--max-queued-chunks N] [--max-session-memory-mb MB]\n"
    "                       [--min-stream-rate R] [--stream-rate-grace-s S]\n"
    "                       [--shutdown-grace-s S] [--data-dir DIR] [--recordings-root DIR]\n"
    "                       [--max-jobs N] [--max-upload-mb MB] [--max-spool-mb MB]\n"
    "                       [--metrics-listen HOST:PORT]\n"
    "                       [--tls-cert FILE --tls-key FILE [--tls-client-ca FILE]]\n"
    "                       [--tokens-file FILE] [--insecure] [--job-store postgresql://...]\n"
    "                       [--role api|worker|both] [--job-lease-s S] [--job-heartbeat-s S]\n"
    "                       [--job-max-attempts N] [--job-deadline-s S] [--job-stall-s S]\n"
    "defaults: --listen 127.0.0.1:50051 --workers <cores> --max-sessions 16 --max-message-mb 16\n"
    "          --idle-timeout-s 60 --max-queued-chunks 8 --shutdown-grace-s 10 --max-jobs 1\n"
    "          --max-upload-mb 8192 --max-spool-mb 16384 --role both --job-lease-s 30\n"
    "          --job-heartbeat-s 10 --job-max-attempts 3 --job-deadline-s 21600\n"
    "          --job-stall-s 300 --min-stream-rate 0.5 --stream-rate-grace-s 60\n"
    "batch jobs are off without --data-dir; SubmitJob by reference needs --recordings-root\n"
    "the job store is DIR/jobs.sqlite unless --job-store names a PostgreSQL database\n"
    "a Fit stream whose data advances slower than --min-stream-rate x real time after\n"
    "--stream-rate-grace-s ends DEADLINE_EXCEEDED (0 disables)\n"
    "plaintext without --tls-cert; no token needed without --tokens-file (docs/server.md)\n"
    "a --listen address beyond loopback needs --tls-cert, --tls-key and --tokens-file,\n"
    "or --insecure to serve without them\n"
    "--tenant-max-sessions 0 (the default) splits --max-sessions evenly between the tenants\n"
    "of --tokens-file\n"
    "--max-session-memory-mb 0 (the default): half this machine's memory split between\n"
    "--max-sessions + --max-jobs; a session holding more ends RESOURCE_EXHAUSTED\n"
    "--config FILE: 'key = value' lines, keys as the flags without '--' (max-sessions = 4),\n"
    "               '#' starts a comment line; flags given on the command line win\n";

}  // namespace

int main(int argc, char** argv) {
  // Block the stop signals in every thread (threads inherit the mask), then wait for them here.
  sigset_t stop_signals;
  sigemptyset(&stop_signals);
  sigaddset(&stop_signals, SIGINT);
  sigaddset(&stop_signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &stop_signals, nullptr);

  try {
    const posefuse::server::CommandLine command_line =
        posefuse::server::parse_server_command_line(std::vector<std::string>(argv + 1, argv + argc));
    if (command_line.help) {
      std::fputs(kUsage, stdout);
      return 0;
    }
    if (!command_line.config_file.empty()) {
      posefuse::server::log_event("info", "config", {{"file", command_line.config_file}});
    }
    posefuse::server::PoseFuseServer server(command_line.options);
    int signal_number = 0;
    sigwait(&stop_signals, &signal_number);
    posefuse::server::log_event("info", "signal", {{"signal", signal_number == SIGINT ? "SIGINT" : "SIGTERM"}});
    if (!server.shutdown().empty()) {
      // A job thread blocked inside a read would hold the server's destruction for ever; the
      // jobs' leases expire and another worker resumes them (docs/server.md, "Job store").
      std::fflush(stdout);
      std::fflush(stderr);
      std::_Exit(0);
    }
  } catch (const posefuse::Error& error) {
    std::fprintf(stderr, "posefuse-server: %s\n", error.what());
    return 2;
  } catch (const std::exception& error) {
    std::fprintf(stderr, "posefuse-server: %s\n", error.what());
    return 1;
  }
  return 0;
}
