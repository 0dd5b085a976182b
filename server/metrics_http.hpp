#pragma once
// A minimal HTTP/1.1 endpoint for Prometheus: GET /metrics answers the text exposition format,
// any other path 404, another method 405, a request that is not HTTP 400, a request head over
// the size limit 431. One thread serves every connection with poll(), so a slow or silent
// client delays nobody: each connection has a deadline for sending its request and reading
// the answer, connections beyond the limit are answered 503 and closed at once, and stopping
// closes whatever is still open without waiting for it.
#include <chrono>
#include <cstddef>
#include <functional>
#include <string>
#include <thread>

namespace posefuse::server {

struct MetricsHttpLimits {
  std::size_t max_connections = 16;
  // From accept to the last byte of the answer; a scraper needs milliseconds.
  std::chrono::milliseconds deadline{5000};
  std::size_t max_request_bytes = 8192;
};

class MetricsHttpServer {
 public:
  // `listen` is HOST:PORT with a numeric IPv4 host; port 0 picks a free port. Throws
  // posefuse::Error (field "--metrics-listen") when it cannot listen.
  MetricsHttpServer(const std::string& listen, std::function<std::string()> render, MetricsHttpLimits limits = {});
  ~MetricsHttpServer();
  MetricsHttpServer(const MetricsHttpServer&) = delete;
  MetricsHttpServer& operator=(const MetricsHttpServer&) = delete;

  int port() const { return port_; }

 private:
  void serve();

  std::function<std::string()> render_;
  const MetricsHttpLimits limits_;
  int listen_fd_ = -1;
  int stop_fd_ = -1;  // an eventfd: written once to wake serve() and end it
  int port_ = 0;
  std::thread thread_;
};

}  // namespace posefuse::server
