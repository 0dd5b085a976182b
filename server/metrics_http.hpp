#pragma once
// A minimal HTTP/1.1 endpoint for Prometheus: GET /metrics answers the text exposition format,
// anything else 404. One connection at a time on its own thread (a scraper every few seconds
// is the only client); a slow client is dropped after a 2 s receive timeout.
#include <atomic>
#include <functional>
#include <string>
#include <thread>

namespace posefuse::server {

class MetricsHttpServer {
 public:
  // `listen` is HOST:PORT with a numeric IPv4 host; port 0 picks a free port. Throws
  // posefuse::Error (field "--metrics-listen") when it cannot listen.
  MetricsHttpServer(const std::string& listen, std::function<std::string()> render);
  ~MetricsHttpServer();
  MetricsHttpServer(const MetricsHttpServer&) = delete;
  MetricsHttpServer& operator=(const MetricsHttpServer&) = delete;

  int port() const { return port_; }

 private:
  void serve();
  void answer(int connection);

  std::function<std::string()> render_;
  int listen_fd_ = -1;
  int port_ = 0;
  std::atomic<bool> stopping_{false};
  std::thread thread_;
};

}  // namespace posefuse::server
