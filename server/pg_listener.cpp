#include "server/pg_listener.hpp"

#include <poll.h>

#include <chrono>

#include <libpq-fe.h>

#include "server/log.hpp"

namespace posefuse::server {

PgListener::PgListener(std::string conninfo, std::string channel,
                       std::function<void(const std::string&)> on_notification, std::function<void()> on_connected)
    : conninfo_(std::move(conninfo)),
      channel_(std::move(channel)),
      on_notification_(std::move(on_notification)),
      on_connected_(std::move(on_connected)) {
  // The first connection here, so that every notification after construction is heard.
  connection_ = listen();
  thread_ = std::thread([this] { run(); });
}

PgListener::~PgListener() {
  stop_ = true;
  thread_.join();
}

std::unique_ptr<PgConnection> PgListener::listen() {
  auto connection = std::make_unique<PgConnection>(conninfo_);
  // The channel is our constant, never input; LISTEN takes no parameters.
  connection->exec("LISTEN " + channel_);
  return connection;
}

void PgListener::run() {
  // poll() wakes at least this often, so that stopping never waits long.
  constexpr int kPollMs = 100;
  while (!stop_) {
    if (!connection_) {
      try {
        connection_ = listen();
        log_event("info", "job_store_listen_reconnected");
        on_connected_();
      } catch (const std::exception&) {
        connection_.reset();
        for (int i = 0; i < 3 && !stop_; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(kPollMs));
        continue;
      }
    }
    PGconn* conn = connection_->raw();
    pollfd fd{PQsocket(conn), POLLIN, 0};
    if (::poll(&fd, 1, kPollMs) < 0) continue;
    if (PQconsumeInput(conn) == 0) {
      log_event("warning", "job_store_listen_lost");
      connection_.reset();
      continue;
    }
    while (PGnotify* notification = PQnotifies(conn)) {
      const std::string payload = notification->extra;
      PQfreemem(notification);
      on_notification_(payload);
    }
  }
}

}  // namespace posefuse::server
