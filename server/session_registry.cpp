#include "server/session_registry.hpp"

#include <algorithm>
#include <vector>

namespace posefuse::server {

unsigned fair_share_of_sessions(unsigned max_sessions, std::size_t tenants) {
  if (tenants <= 1) return max_sessions;
  return std::max(1u, static_cast<unsigned>(max_sessions / tenants));
}

SessionRegistry::SessionRegistry(unsigned max_sessions, unsigned max_per_tenant,
                                 std::chrono::milliseconds check_interval)
    : max_sessions_(max_sessions),
      max_per_tenant_(max_per_tenant),
      check_interval_(check_interval),
      monitor_([this] { monitor(); }) {}

SessionRegistry::~SessionRegistry() {
  {
    std::lock_guard lock(mu_);
    stopping_ = true;
  }
  changed_.notify_all();
  monitor_.join();
}

Admission SessionRegistry::try_admit(const std::string& tenant) {
  std::lock_guard lock(mu_);
  if (active_ >= max_sessions_) return {};
  const auto running = active_by_tenant_.find(tenant);
  if (running != active_by_tenant_.end() && running->second >= max_per_tenant_) return {std::nullopt, true};
  ++active_;
  ++active_by_tenant_[tenant];
  tenant_of_.emplace(next_id_, tenant);
  return {next_id_++, false};
}

std::string SessionRegistry::busy_message(const Admission& refused) const {
  if (refused.tenant_full) {
    return "tenant busy: " + std::to_string(max_per_tenant_) +
           " sessions and uploads of this tenant are running, its limit (--tenant-max-sessions); retry later";
  }
  return "server busy: " + std::to_string(max_sessions_) +
         " sessions and uploads are running (--max-sessions); retry later";
}

void SessionRegistry::watch(std::uint64_t id, std::weak_ptr<SupervisedSession> session) {
  std::lock_guard lock(mu_);
  sessions_[id] = std::move(session);
}

void SessionRegistry::release(std::uint64_t id) {
  {
    std::lock_guard lock(mu_);
    sessions_.erase(id);
    --active_;
    if (const auto tenant = tenant_of_.find(id); tenant != tenant_of_.end()) {
      if (--active_by_tenant_[tenant->second] == 0) active_by_tenant_.erase(tenant->second);
      tenant_of_.erase(tenant);
    }
  }
  changed_.notify_all();
}

unsigned SessionRegistry::active() const {
  std::lock_guard lock(mu_);
  return active_;
}

bool SessionRegistry::wait_for_active_at_most(unsigned n, std::chrono::milliseconds timeout) const {
  std::unique_lock lock(mu_);
  return changed_.wait_for(lock, timeout, [&] { return active_ <= n; });
}

void SessionRegistry::monitor() {
  std::unique_lock lock(mu_);
  while (!changed_.wait_for(lock, check_interval_, [this] { return stopping_; })) {
    // Check outside the lock: a session that ends itself calls release().
    std::vector<std::shared_ptr<SupervisedSession>> live;
    for (const auto& [id, weak] : sessions_) {
      if (auto session = weak.lock()) live.push_back(std::move(session));
    }
    lock.unlock();
    const auto now = std::chrono::steady_clock::now();
    for (const auto& session : live) session->check_idle(now);
    live.clear();  // a session's last reference may go here, outside the lock
    lock.lock();
  }
}

}  // namespace posefuse::server
