#pragma once
// Server metrics in the Prometheus text exposition format (served by MetricsHttpServer).
// Counters are updated from any thread; gauges that other objects own (sessions in flight,
// worker queue) are passed in when rendering. The Fit and job counters are kept per tenant: the
// tenant names of the tokens file, which say which clinic but nothing about a patient; tenant
// "" (no tokens file, or tokens without a tenant) is rendered without the label, as before
// tenants existed.
#include <atomic>
#include <cstdint>
#include <map>
#include <mutex>
#include <string>
#include <string_view>

namespace posefuse::server {

class Metrics {
 public:
  void session_started(std::string_view tenant);
  void session_refused(std::string_view tenant);
  void session_finished(std::string_view tenant, std::string_view status);  // gRPC status code name
  void chunk_received(std::string_view tenant);
  void item_error(std::string_view tenant);
  // A SubmitJob call's end (an upload or a job by reference), by its gRPC status code name.
  void job_submit_finished(std::string_view tenant, std::string_view status);
  // Chunks read from clients and not yet processed, over all sessions.
  void queued_chunks_add(std::int64_t n) { queued_chunks_.fetch_add(n); }
  void stage_time(std::string_view stage, double seconds);
  void job_finished(std::string_view tenant, std::string_view state);

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
  // Counts by their Prometheus label set, e.g. `tenant="clinic-a",status="OK"`.
  using Counts = std::map<std::string, std::uint64_t, std::less<>>;
  void count(Counts& counts, const std::string& label_set);  // one more, under mu_

  std::atomic<std::int64_t> queued_chunks_{0};
  mutable std::mutex mu_;
  Counts sessions_started_, sessions_refused_;  // by tenant
  Counts sessions_finished_;                    // by tenant and status
  Counts chunks_received_, item_errors_;        // by tenant
  Counts job_submits_;                          // by tenant and status
  std::map<std::string, StageTotals, std::less<>> stages_;
  Counts jobs_finished_;  // by tenant and state
};

}  // namespace posefuse::server
