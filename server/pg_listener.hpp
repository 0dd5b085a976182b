#pragma once
// LISTEN on one PostgreSQL channel, on a thread and connection of its own. The constructor
// connects (throwing StoreUnavailable when it cannot), so nothing sent after it is missed. A
// dropped connection (the database restarting) is reconnected with a short back-off;
// notifications sent meanwhile are lost, so on_connected runs after every reconnection and the
// caller re-reads what it follows.
#include <atomic>
#include <functional>
#include <memory>
#include <string>
#include <thread>

#include "server/pg_connection.hpp"

namespace posefuse::server {

class PgListener {
 public:
  PgListener(std::string conninfo, std::string channel, std::function<void(const std::string& payload)> on_notification,
             std::function<void()> on_connected);
  ~PgListener();  // stops the thread
  PgListener(const PgListener&) = delete;
  PgListener& operator=(const PgListener&) = delete;

 private:
  std::unique_ptr<PgConnection> listen();
  void run();

  const std::string conninfo_;
  const std::string channel_;
  std::function<void(const std::string&)> on_notification_;
  std::function<void()> on_connected_;
  std::atomic<bool> stop_{false};
  std::unique_ptr<PgConnection> connection_;  // the thread's alone once it runs
  std::thread thread_;
};

}  // namespace posefuse::server
