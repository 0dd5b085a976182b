// posefuse-server: serves posefuse.v1.PoseFuse, grpc.health.v1.Health and server reflection.
// Flags: docs/server.md. Stops gracefully on SIGINT or SIGTERM.
#include <csignal>
#include <cstdio>
#include <exception>
#include <string>
#include <string_view>

#include "common/error.hpp"
#include "server/log.hpp"
#include "server/posefuse_server.hpp"
#include "session/text_fields.hpp"

namespace {

using posefuse::server::ServerOptions;

constexpr const char* kUsage =
    "usage: posefuse-server [--listen HOST:PORT] [--workers N] [--max-sessions N]\n"
    "                       [--max-message-mb MB] [--idle-timeout-s S] [--max-queued-chunks N]\n"
    "                       [--shutdown-grace-s S] [--data-dir DIR] [--recordings-root DIR]\n"
    "                       [--max-jobs N] [--max-upload-mb MB] [--metrics-listen HOST:PORT]\n"
    "                       [--tls-cert FILE --tls-key FILE [--tls-client-ca FILE]]\n"
    "                       [--tokens-file FILE]\n"
    "defaults: --listen 127.0.0.1:50051 --workers <cores> --max-sessions 16 --max-message-mb 16\n"
    "          --idle-timeout-s 60 --max-queued-chunks 8 --shutdown-grace-s 10 --max-jobs 1\n"
    "          --max-upload-mb 8192\n"
    "batch jobs are off without --data-dir; SubmitJob by reference needs --recordings-root\n"
    "plaintext without --tls-cert; no token needed without --tokens-file (docs/server.md)\n";

unsigned parse_count(std::string_view text, const std::string& flag) {
  const std::uint64_t value = posefuse::session::parse_uint64(text, flag);
  if (value > 1'000'000) posefuse::throw_invalid(flag, "is too large");
  return static_cast<unsigned>(value);
}

// "--flag value" or "--flag=value".
ServerOptions parse_flags(int argc, char** argv) {
  ServerOptions options;
  for (int i = 1; i < argc; ++i) {
    std::string flag = argv[i];
    std::string value;
    if (flag == "--help" || flag == "-h") {
      std::fputs(kUsage, stdout);
      std::exit(0);
    }
    if (const auto eq = flag.find('='); eq != std::string::npos) {
      value = flag.substr(eq + 1);
      flag.resize(eq);
    } else if (i + 1 < argc) {
      value = argv[++i];
    } else {
      posefuse::throw_invalid(flag, "needs a value");
    }
    if (flag == "--listen") options.listen = value;
    else if (flag == "--workers") options.workers = parse_count(value, flag);
    else if (flag == "--max-sessions") options.max_sessions = parse_count(value, flag);
    else if (flag == "--max-message-mb") options.max_message_mb = posefuse::session::parse_double(value, flag);
    else if (flag == "--idle-timeout-s") options.idle_timeout_s = posefuse::session::parse_double(value, flag);
    else if (flag == "--max-queued-chunks") options.max_queued_chunks = parse_count(value, flag);
    else if (flag == "--shutdown-grace-s") options.shutdown_grace_s = posefuse::session::parse_double(value, flag);
    else if (flag == "--data-dir") options.data_dir = value;
    else if (flag == "--recordings-root") options.recordings_root = value;
    else if (flag == "--max-jobs") options.max_jobs = parse_count(value, flag);
    else if (flag == "--max-upload-mb") options.max_upload_mb = posefuse::session::parse_double(value, flag);
    else if (flag == "--metrics-listen") options.metrics_listen = value;
    else if (flag == "--tls-cert") options.tls_cert = value;
    else if (flag == "--tls-key") options.tls_key = value;
    else if (flag == "--tls-client-ca") options.tls_client_ca = value;
    else if (flag == "--tokens-file") options.tokens_file = value;
    else posefuse::throw_invalid(flag, "unknown flag (see --help)");
  }
  return options;
}

}  // namespace

int main(int argc, char** argv) {
  // Block the stop signals in every thread (threads inherit the mask), then wait for them here.
  sigset_t stop_signals;
  sigemptyset(&stop_signals);
  sigaddset(&stop_signals, SIGINT);
  sigaddset(&stop_signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &stop_signals, nullptr);

  try {
    posefuse::server::PoseFuseServer server(parse_flags(argc, argv));
    int signal_number = 0;
    sigwait(&stop_signals, &signal_number);
    posefuse::server::log_event("info", "signal", {{"signal", signal_number == SIGINT ? "SIGINT" : "SIGTERM"}});
    server.shutdown();
  } catch (const posefuse::Error& error) {
    std::fprintf(stderr, "posefuse-server: %s\n", error.what());
    return 2;
  } catch (const std::exception& error) {
    std::fprintf(stderr, "posefuse-server: %s\n", error.what());
    return 1;
  }
  return 0;
}
