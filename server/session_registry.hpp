#pragma once
// Admission and supervision of Fit sessions and uploads: at most max_sessions at once, and at
// most max_per_tenant of one tenant's, so that one clinic cannot take every slot (beyond either
// the call is refused with RESOURCE_EXHAUSTED at once, never queued); and a monitor thread that
// ends sessions whose client has gone quiet for longer than the idle timeout.
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

namespace posefuse::server {

// What the registry needs from a session.
class SupervisedSession {
 public:
  virtual ~SupervisedSession() = default;
  virtual void check_idle(std::chrono::steady_clock::time_point now) = 0;
};

// The outcome of SessionRegistry::try_admit.
struct Admission {
  std::optional<std::uint64_t> id;  // the session's id; empty when refused
  bool tenant_full = false;         // refused by the per-tenant limit (else by max_sessions)
};

// The per-tenant limit when none is configured: the slots split evenly between the tenants
// (at least one each), so that every tenant can always have its share.
unsigned fair_share_of_sessions(unsigned max_sessions, std::size_t tenants);

class SessionRegistry {
 public:
  // max_per_tenant >= max_sessions: no per-tenant limit.
  SessionRegistry(unsigned max_sessions, unsigned max_per_tenant, std::chrono::milliseconds check_interval);
  ~SessionRegistry();
  SessionRegistry(const SessionRegistry&) = delete;
  SessionRegistry& operator=(const SessionRegistry&) = delete;

  // A session id for `tenant`, unless max_sessions are running, or max_per_tenant of `tenant`'s.
  Admission try_admit(const std::string& tenant);
  // The RESOURCE_EXHAUSTED message for a refused admission: the limit reached and its flag.
  std::string busy_message(const Admission& refused) const;
  void watch(std::uint64_t id, std::weak_ptr<SupervisedSession> session);
  // The session's slot is free again (its call is done).
  void release(std::uint64_t id);

  unsigned active() const;
  // Waits until at most `n` sessions are active; false on timeout (tests, shutdown).
  bool wait_for_active_at_most(unsigned n, std::chrono::milliseconds timeout) const;

 private:
  void monitor();

  const unsigned max_sessions_;
  const unsigned max_per_tenant_;
  const std::chrono::milliseconds check_interval_;
  mutable std::mutex mu_;
  mutable std::condition_variable changed_;
  unsigned active_ = 0;
  std::uint64_t next_id_ = 1;
  bool stopping_ = false;
  std::map<std::uint64_t, std::weak_ptr<SupervisedSession>> sessions_;
  std::map<std::uint64_t, std::string> tenant_of_;    // every admitted session's tenant
  std::map<std::string, unsigned> active_by_tenant_;  // tenants with sessions only
  std::thread monitor_;
};

}  // namespace posefuse::server
