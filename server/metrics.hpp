#pragma once
// Server metrics in the Prometheus text exposition format (served by MetricsHttpServer).
// Counters are updated from any thread; gauges that other objects own (sessions in flight,
// worker queue) are passed in when rendering.
#include <atomic>
#include <cstdint>
#include <map>
#include <mutex>
#include <string>
#include <string_view>

namespace posefuse::server {

class Metrics {
 public:
  void session_started() { sessions_started_.fetch_add(1); }
  void session_refused() { sessions_refused_.fetch_add(1); }
  void session_finished(std::string_view status);  // gRPC status code name
  void chunk_received() { chunks_received_.fetch_add(1); }
  void item_error() { item_errors_.fetch_add(1); }
  // Chunks read from clients and not yet processed, over all sessions.
  void queued_chunks_add(std::int64_t n) { queued_chunks_.fetch_add(n); }
  void stage_time(std::string_view stage, double seconds);
  void job_finished(std::string_view state);

  struct Gauges {
    unsigned sessions_in_flight = 0;
    std::size_t worker_queue = 0;
    unsigned workers = 0;
    std::uint64_t upload_spool_bytes = 0;  // uploads in transit, together (server/spool_quota.hpp)
  };
  std::string render(const Gauges& gauges) const;

 private:
  struct StageTotals {
    std::uint64_t calls = 0;
    double seconds = 0.0;
  };
  std::atomic<std::uint64_t> sessions_started_{0}, sessions_refused_{0}, chunks_received_{0}, item_errors_{0};
  std::atomic<std::int64_t> queued_chunks_{0};
  mutable std::mutex mu_;
  std::map<std::string, std::uint64_t, std::less<>> sessions_finished_;  // by status
  std::map<std::string, StageTotals, std::less<>> stages_;
  std::map<std::string, std::uint64_t, std::less<>> jobs_finished_;  // by state
};

}  // namespace posefuse::server
