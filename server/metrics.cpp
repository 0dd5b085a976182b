#include "server/metrics.hpp"

#include <cstdio>

namespace posefuse::server {

namespace {

void header(std::string& out, const char* name, const char* type, const char* help) {
  out += "# HELP ";
  out += name;
  out += ' ';
  out += help;
  out += "\n# TYPE ";
  out += name;
  out += ' ';
  out += type;
  out += '\n';
}

std::string number(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.9g", value);
  return text;
}

void sample(std::string& out, const char* name, const std::string& labels, double value) {
  out += name;
  if (!labels.empty()) out += "{" + labels + "}";
  out += ' ' + number(value) + '\n';
}

template <class Map>
void increment(Map& map, std::string_view key) {
  auto it = map.find(key);
  if (it == map.end()) it = map.emplace(std::string(key), typename Map::mapped_type{}).first;
  ++it->second;
}

// Label values go out unescaped: tenant names are [A-Za-z0-9_.-] (server/security.hpp), status
// and state names are enum names.
std::string labels(std::string_view tenant, std::string_view name = {}, std::string_view value = {}) {
  std::string out;
  if (!tenant.empty()) out = "tenant=\"" + std::string(tenant) + "\"";
  if (!name.empty()) {
    if (!out.empty()) out += ',';
    out += std::string(name) + "=\"" + std::string(value) + "\"";
  }
  return out;
}

template <class Counts>
void samples(std::string& out, const char* name, const Counts& counts) {
  for (const auto& [label_set, n] : counts) sample(out, name, label_set, static_cast<double>(n));
}

}  // namespace

void Metrics::count(Counts& counts, const std::string& label_set) {
  std::lock_guard lock(mu_);
  increment(counts, label_set);
}

void Metrics::session_started(std::string_view tenant) { count(sessions_started_, labels(tenant)); }
void Metrics::session_refused(std::string_view tenant) { count(sessions_refused_, labels(tenant)); }
void Metrics::session_finished(std::string_view tenant, std::string_view status) {
  count(sessions_finished_, labels(tenant, "status", status));
}
void Metrics::chunk_received(std::string_view tenant) { count(chunks_received_, labels(tenant)); }
void Metrics::item_error(std::string_view tenant) { count(item_errors_, labels(tenant)); }
void Metrics::job_submit_finished(std::string_view tenant, std::string_view status) {
  count(job_submits_, labels(tenant, "status", status));
}

void Metrics::stage_time(std::string_view stage, double seconds) {
  std::lock_guard lock(mu_);
  auto it = stages_.find(stage);
  if (it == stages_.end()) it = stages_.emplace(std::string(stage), StageTotals{}).first;
  ++it->second.calls;
  it->second.seconds += seconds;
}

void Metrics::job_finished(std::string_view tenant, std::string_view state) {
  count(jobs_finished_, labels(tenant, "state", state));
}

std::string Metrics::render(const Gauges& gauges) const {
  std::string out;
  header(out, "posefuse_sessions_in_flight", "gauge", "Fit calls running now.");
  sample(out, "posefuse_sessions_in_flight", "", gauges.sessions_in_flight);
  header(out, "posefuse_queued_chunks", "gauge", "Chunks received and waiting for the pipeline, over all sessions.");
  sample(out, "posefuse_queued_chunks", "", static_cast<double>(queued_chunks_.load()));
  header(out, "posefuse_worker_queue_depth", "gauge", "Tasks waiting for a worker thread.");
  sample(out, "posefuse_worker_queue_depth", "", static_cast<double>(gauges.worker_queue));
  header(out, "posefuse_workers", "gauge", "Worker threads.");
  sample(out, "posefuse_workers", "", gauges.workers);
  header(out, "posefuse_upload_spool_bytes", "gauge", "Bytes the uploads in transit hold, together (--max-spool-mb).");
  sample(out, "posefuse_upload_spool_bytes", "", static_cast<double>(gauges.upload_spool_bytes));

  std::lock_guard lock(mu_);
  // Tenant "" always has its line, so that a server without tenants shows its zeros.
  header(out, "posefuse_sessions_started_total", "counter", "Fit calls admitted, by tenant.");
  if (!sessions_started_.contains("")) sample(out, "posefuse_sessions_started_total", "", 0);
  samples(out, "posefuse_sessions_started_total", sessions_started_);
  header(out, "posefuse_sessions_refused_total", "counter",
         "Fit calls refused with RESOURCE_EXHAUSTED (--max-sessions, --tenant-max-sessions), by tenant.");
  if (!sessions_refused_.contains("")) sample(out, "posefuse_sessions_refused_total", "", 0);
  samples(out, "posefuse_sessions_refused_total", sessions_refused_);
  header(out, "posefuse_sessions_finished_total", "counter", "Fit calls finished, by tenant and status.");
  samples(out, "posefuse_sessions_finished_total", sessions_finished_);
  header(out, "posefuse_chunks_received_total", "counter", "Session chunks received by Fit calls, by tenant.");
  if (!chunks_received_.contains("")) sample(out, "posefuse_chunks_received_total", "", 0);
  samples(out, "posefuse_chunks_received_total", chunks_received_);
  header(out, "posefuse_item_errors_total", "counter", "Chunks or items answered with ItemError, by tenant.");
  if (!item_errors_.contains("")) sample(out, "posefuse_item_errors_total", "", 0);
  samples(out, "posefuse_item_errors_total", item_errors_);
  header(out, "posefuse_stage_calls_total", "counter", "Pipeline stage calls, by stage.");
  for (const auto& [stage, totals] : stages_) {
    sample(out, "posefuse_stage_calls_total", "stage=\"" + stage + "\"", static_cast<double>(totals.calls));
  }
  header(out, "posefuse_stage_seconds_total", "counter", "Wall time in pipeline stages, by stage.");
  for (const auto& [stage, totals] : stages_) {
    sample(out, "posefuse_stage_seconds_total", "stage=\"" + stage + "\"", totals.seconds);
  }
  header(out, "posefuse_job_submits_total", "counter",
         "SubmitJob calls (uploads and jobs by reference) finished, by tenant and status.");
  samples(out, "posefuse_job_submits_total", job_submits_);
  header(out, "posefuse_jobs_finished_total", "counter", "Batch jobs finished, by tenant and state.");
  samples(out, "posefuse_jobs_finished_total", jobs_finished_);
  return out;
}

}  // namespace posefuse::server
