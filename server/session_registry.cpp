#include "server/session_registry.hpp"

#include <vector>

namespace posefuse::server {

SessionRegistry::SessionRegistry(unsigned max_sessions, std::chrono::milliseconds check_interval)
    : max_sessions_(max_sessions), check_interval_(check_interval), monitor_([this] { monitor(); }) {}

SessionRegistry::~SessionRegistry() {
  {
    std::lock_guard lock(mu_);
    stopping_ = true;
  }
  changed_.notify_all();
  monitor_.join();
}

std::optional<std::uint64_t> SessionRegistry::try_admit() {
  std::lock_guard lock(mu_);
  if (active_ >= max_sessions_) return std::nullopt;
  ++active_;
  return next_id_++;
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
