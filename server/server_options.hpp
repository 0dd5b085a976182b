#pragma once
// Everything the server is configured with (flags of posefuse-server, see docs/server.md).
#include <cstdint>
#include <string>

namespace posefuse::server {

struct ServerOptions {
  std::string listen = "127.0.0.1:50051";  // host:port; port 0 picks a free one
  unsigned workers = 0;                    // Fit and upload pipeline threads; 0 = one per CPU core
  unsigned max_sessions = 16;              // concurrent Fit calls; beyond: RESOURCE_EXHAUSTED
  // Concurrent Fit calls and uploads of one tenant (docs/server.md "Security"); 0: max_sessions
  // split evenly between the tokens file's tenants (fair_share_of_sessions).
  unsigned tenant_max_sessions = 0;
  double max_message_mb = 16.0;      // largest message received, MiB
  double idle_timeout_s = 60.0;      // a Fit stream silent this long is ended
  unsigned max_queued_chunks = 8;    // per session: read but not yet processed
  unsigned max_queued_results = 64;  // per session: computed but not yet sent
  // Per session or job: the most its pipeline may hold for later frames (server/session_memory.hpp);
  // 0 = half this machine's (or container's) memory split between max_sessions + max_jobs.
  double max_session_memory_mb = 0.0;
  double shutdown_grace_s = 10.0;  // calls in flight get this long to finish, then running jobs as long
  // Minimum stream rate (server/stream_rate.hpp): after stream_rate_grace_s of waiting for its
  // client, a Fit stream must have delivered at least min_stream_rate seconds of recording per
  // wall second or it is ended; 0 disables. 0.5 lets a live session lag to half real time.
  double min_stream_rate = 0.5;
  double stream_rate_grace_s = 60.0;
  // Batch jobs: off unless data_dir is set (job store: <data_dir>/jobs.sqlite unless job_store
  // names a PostgreSQL database; data_dir then holds only uploads in transit).
  std::string data_dir;
  std::string job_store;          // empty: SQLite; postgresql://... or key=value
  std::string role = "both";      // api | worker | both (docs/server.md "Job store")
  double job_lease_s = 30.0;      // a running job's lease; expired: another worker
  double job_heartbeat_s = 10.0;  // lease renewal, reaping and queue polling
  unsigned job_max_attempts = 3;  // claims before a job whose lease keeps expiring fails
  // A running attempt is stopped and its job FAILED (DEADLINE_EXCEEDED) after job_deadline_s,
  // or after job_stall_s without reading a chunk; 0 disables either. A chunk is read and
  // processed in well under a second, and a job runs several times faster than the session was
  // recorded, so 6 h is far beyond any honest job (a 2 h session) and 5 min without a chunk is
  // a read or a store that hangs.
  double job_deadline_s = 21600.0;
  double job_stall_s = 300.0;
  std::string recordings_root;    // SubmitJob by reference reads only under this
  unsigned max_jobs = 1;          // jobs running at once
  double max_upload_mb = 8192.0;  // SubmitJob by upload: whole recording, MiB
  double max_spool_mb = 16384.0;  // all uploads in transit together, MiB (server/spool_quota.hpp)
  std::string metrics_listen;     // IPv4 HOST:PORT for GET /metrics; empty = off
  // Security (docs/server.md "Security"): PEM files; TLS is on when tls_cert is set, mutual TLS
  // when tls_client_ca is set too. Bearer tokens are required when tokens_file is set.
  std::string tls_cert;
  std::string tls_key;
  std::string tls_client_ca;
  std::string tokens_file;
  // Serve plaintext or without tokens on an address beyond loopback (validate_options refuses
  // that otherwise): for a TLS-terminating proxy on a private network, or a port that serves
  // health only.
  bool insecure = false;
};

}  // namespace posefuse::server
