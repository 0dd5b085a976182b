#pragma once
// posefuse-server in a child process on loopback, for the server benchmarks: its resident
// memory and CPU time in /proc are the server's alone, not the clients'.
#include <sys/types.h>

#include <memory>
#include <string>
#include <vector>

#include "posefuse/v1/service.grpc.pb.h"
#include "server/server_options.hpp"

namespace posefuse::bench {

struct ServerProcess {
  pid_t pid = 0;
  int port = 0;
};

// Forks; the child serves `options` on 127.0.0.1:0 (listen is overwritten) until SIGTERM, its
// logs going to /dev/null. Fork before this process starts any thread: the child must not
// inherit a lock held by a thread that does not exist in it.
ServerProcess start_server_process(server::ServerOptions options);
void stop_server_process(const ServerProcess& server);

// VmRSS of a process, MiB (NaN when unreadable).
double rss_mib(pid_t pid);
// User + system CPU seconds of a process (all its threads) from /proc/PID/stat.
double process_cpu_s(pid_t pid);
// The 1-minute load average, as /proc/loadavg writes it.
std::string load_average();

// A stub on a connection of its own to 127.0.0.1:port, sending messages up to 64 MiB.
std::unique_ptr<v1::PoseFuse::Stub> new_stub(int port);

// "1,4,16" as numbers; kInvalidArgument naming `flag` for anything else.
std::vector<int> parse_int_list(const std::string& text, const std::string& flag);

}  // namespace posefuse::bench
