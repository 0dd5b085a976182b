#include "server/deferred_job_store.hpp"

#include "server/job_store_errors.hpp"
#include "server/log.hpp"

namespace posefuse::server {

DeferredJobStore::DeferredJobStore(Opener open) : open_(std::move(open)) {
  try {
    this->open(true);
  } catch (const StoreUnavailable&) {
    // Logged by open(); the heartbeat tries again.
  }
}

std::string DeferredJobStore::problem() {
  std::lock_guard lock(mu_);
  return problem_;
}

void DeferredJobStore::open(bool first_try) {
  std::lock_guard lock(mu_);
  if (opened_) return;
  try {
    opened_ = open_();
  } catch (const Error& error) {
    const bool never_passes =
        dynamic_cast<const StoreMisconfigured*>(&error) != nullptr || error.code() == ErrorCode::kInvalidArgument;
    if (first_try && never_passes) throw;
    if (problem_ != error.what()) log_event("error", "job_store_unavailable", {{"error", error.what()}});
    problem_ = error.what();
  } catch (const std::exception& error) {
    if (problem_ != error.what()) log_event("error", "job_store_unavailable", {{"error", error.what()}});
    problem_ = error.what();
  }
  if (!opened_) throw StoreUnavailable("the job store cannot be opened: " + problem_);
  if (listener_) opened_->set_event_listener(listener_);
  problem_.clear();
  store_ = opened_.get();
  if (!first_try) log_event("info", "job_store_opened");
}

JobStore& DeferredJobStore::store() {
  if (JobStore* store = store_.load()) return *store;
  std::lock_guard lock(mu_);
  throw StoreUnavailable("the job store cannot be opened: " + problem_);
}

v1::Job DeferredJobStore::create(const v1::JobSpec& spec, const std::string& recording_path, const std::string& owner,
                                 std::int64_t now_unix_us) {
  return store().create(spec, recording_path, owner, now_unix_us);
}
std::optional<JobRecord> DeferredJobStore::get(const std::string& job_id) { return store().get(job_id); }
std::vector<v1::Job> DeferredJobStore::list(std::size_t limit, const std::string& after_job_id,
                                            const std::vector<v1::Job::State>& states, const std::string& owner) {
  return store().list(limit, after_job_id, states, owner);
}
void DeferredJobStore::update(const v1::Job& job) { store().update(job); }
void DeferredJobStore::append_results(const std::string& job_id, const std::vector<v1::FitResult>& results) {
  store().append_results(job_id, results);
}
std::vector<v1::FitResult> DeferredJobStore::results(const std::string& job_id, std::uint64_t first,
                                                     std::size_t limit) {
  return store().results(job_id, first, limit);
}
std::optional<JobRecord> DeferredJobStore::cancel(const std::string& job_id, const std::string& owner,
                                                  std::int64_t now_unix_us) {
  return store().cancel(job_id, owner, now_unix_us);
}
std::optional<JobRecord> DeferredJobStore::claim(const std::string& worker, std::chrono::milliseconds lease,
                                                 std::int64_t now_unix_us) {
  return store().claim(worker, lease, now_unix_us);
}
LeaseState DeferredJobStore::renew(const JobLease& lease, std::chrono::milliseconds duration) {
  return store().renew(lease, duration);
}
void DeferredJobStore::update_running(const JobLease& lease, const v1::Job& job) { store().update_running(lease, job); }
void DeferredJobStore::append_results(const JobLease& lease, const std::vector<v1::FitResult>& results) {
  store().append_results(lease, results);
}
void DeferredJobStore::release(const JobLease& lease, std::int64_t now_unix_us) { store().release(lease, now_unix_us); }
std::vector<ReapedJob> DeferredJobStore::reap(std::uint32_t max_attempts, std::int64_t now_unix_us) {
  return store().reap(max_attempts, now_unix_us);
}
void DeferredJobStore::probe() {
  if (!store_.load()) open(false);
  store().probe();
}
void DeferredJobStore::set_event_listener(std::function<void(const JobEvent&)> listener) {
  std::lock_guard lock(mu_);
  listener_ = listener;
  if (opened_) opened_->set_event_listener(std::move(listener));
}
std::string DeferredJobStore::keep_upload(const std::filesystem::path& spooled) { return store().keep_upload(spooled); }
std::filesystem::path DeferredJobStore::local_recording(const std::string& recording_path,
                                                        const std::filesystem::path& scratch_dir) {
  return store().local_recording(recording_path, scratch_dir);
}
void DeferredJobStore::drop_upload(const std::string& recording_path, const std::filesystem::path& scratch_dir) {
  store().drop_upload(recording_path, scratch_dir);
}

}  // namespace posefuse::server
