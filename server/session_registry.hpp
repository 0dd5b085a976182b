#pragma once
// Admission and supervision of Fit sessions: at most max_sessions at once (beyond it the call
// is refused with RESOURCE_EXHAUSTED at once, never queued), and a monitor thread that ends
// sessions whose client has gone quiet for longer than the idle timeout.
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>

namespace posefuse::server {

// What the registry needs from a session.
class SupervisedSession {
 public:
  virtual ~SupervisedSession() = default;
  virtual void check_idle(std::chrono::steady_clock::time_point now) = 0;
};

class SessionRegistry {
 public:
  SessionRegistry(unsigned max_sessions, std::chrono::milliseconds check_interval);
  ~SessionRegistry();
  SessionRegistry(const SessionRegistry&) = delete;
  SessionRegistry& operator=(const SessionRegistry&) = delete;

  // A session id, or nothing when max_sessions are running.
  std::optional<std::uint64_t> try_admit();
  void watch(std::uint64_t id, std::weak_ptr<SupervisedSession> session);
  // The session's slot is free again (its call is done).
  void release(std::uint64_t id);

  unsigned active() const;
  // Waits until at most `n` sessions are active; false on timeout (tests, shutdown).
  bool wait_for_active_at_most(unsigned n, std::chrono::milliseconds timeout) const;

 private:
  void monitor();

  const unsigned max_sessions_;
  const std::chrono::milliseconds check_interval_;
  mutable std::mutex mu_;
  mutable std::condition_variable changed_;
  unsigned active_ = 0;
  std::uint64_t next_id_ = 1;
  bool stopping_ = false;
  std::map<std::uint64_t, std::weak_ptr<SupervisedSession>> sessions_;
  std::thread monitor_;
};

}  // namespace posefuse::server
