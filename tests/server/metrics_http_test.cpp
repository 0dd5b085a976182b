// The metrics endpoint (server/metrics_http.hpp) against slow, silent, garbled and too many
// clients on loopback. No timing assertions: waits are for conditions, with generous bounds
// only against hangs.
#include <atomic>
#include <chrono>
#include <future>
#include <memory>
#include <string>
#include <thread>

#include <gtest/gtest.h>

#include "server/metrics_http.hpp"
#include "tests/server/http_client.hpp"

namespace posefuse::server {
namespace {

using namespace std::chrono_literals;

// Longer than any test here runs: connections end only by the behaviour under test.
constexpr std::chrono::milliseconds kNoDeadline = std::chrono::minutes(10);

std::unique_ptr<MetricsHttpServer> serve(std::string body, MetricsHttpLimits limits = {}) {
  return std::make_unique<MetricsHttpServer>(
      "127.0.0.1:0", [body] { return body; }, limits);
}

// A client that sends the start of a request and then one more byte every 50 ms, never ending
// its head, until the server drops it (or, against a hang, a minute has passed).
class Trickler {
 public:
  explicit Trickler(int port) : fd_(test::connect_loopback(port)) {
    test::send_text(fd_, "GET /metrics HTTP/1.1\r\nX-Slow: ");
    thread_ = std::thread([this] {
      for (int i = 0; i < 1200 && !stop_; ++i) {
        if (!test::send_text(fd_, "x")) {
          dropped_ = true;
          return;
        }
        std::this_thread::sleep_for(50ms);
      }
    });
  }
  ~Trickler() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
    ::close(fd_);
  }
  // Waits for the trickle to end; true when it ended because the server dropped it.
  bool wait_until_dropped() {
    if (thread_.joinable()) thread_.join();
    return dropped_;
  }
  bool dropped() const { return dropped_; }

 private:
  int fd_;
  std::atomic<bool> stop_{false}, dropped_{false};
  std::thread thread_;
};

// Asks for the metrics and never reads the answer.
int non_reader(int port) {
  const int fd = test::connect_loopback(port);
  test::send_text(fd, "GET /metrics HTTP/1.1\r\n\r\n");
  return fd;
}

// Larger than loopback's socket buffers on both sides, so that a client that does not read
// leaves the server with most of it unsent.
std::string large_body() { return std::string(48 << 20, 'm'); }

TEST(MetricsHttp, SlowSilentAndNonReadingClientsDoNotDelayAScrape) {
  const std::string body = large_body();
  auto server = serve(body, {.deadline = kNoDeadline});
  Trickler trickler(server->port());
  const int silent = test::connect_loopback(server->port());
  const int not_reading = non_reader(server->port());

  const std::string response = test::http_get(server->port(), "/metrics");
  EXPECT_EQ(response.rfind("HTTP/1.1 200 OK\r\n", 0), 0u) << response.substr(0, 200);
  EXPECT_EQ(test::http_body(response).size(), body.size());
  // Answered beside them, not after them: they are all still connected.
  EXPECT_FALSE(trickler.dropped());
  ::close(silent);
  ::close(not_reading);
}

TEST(MetricsHttp, ClientsAreDroppedAtTheirDeadline) {
  const std::string body = large_body();
  auto server = serve(body, {.deadline = 300ms});
  const int not_reading = non_reader(server->port());
  Trickler trickler(server->port());
  EXPECT_TRUE(trickler.wait_until_dropped());
  // Its deadline came first: the answer stops short.
  const std::string response = test::read_to_end(not_reading);
  EXPECT_LT(test::http_body(response).size(), body.size());
  ::close(not_reading);
}

TEST(MetricsHttp, StoppingDoesNotWaitForSlowClients) {
  auto server = serve(large_body(), {.deadline = kNoDeadline});
  Trickler trickler(server->port());
  const int silent = test::connect_loopback(server->port());
  const int not_reading = non_reader(server->port());
  ASSERT_FALSE(trickler.dropped());

  // The bound is only against a hang: the trickle alone would go on for a minute.
  auto stopped = std::async(std::launch::async, [&server] { server.reset(); });
  ASSERT_EQ(stopped.wait_for(30s), std::future_status::ready);
  EXPECT_TRUE(trickler.wait_until_dropped());
  EXPECT_EQ(test::read_to_end(silent), "");  // closed, unanswered
  ::close(silent);
  ::close(not_reading);
}

// Sends `request` whole, then returns whatever the server answers before closing.
std::string request_and_answer(int port, const std::string& request) {
  const int fd = test::connect_loopback(port);
  test::send_text(fd, request);  // may fail part way: the server may close first
  std::string response = test::read_to_end(fd);
  ::close(fd);
  return response;
}

TEST(MetricsHttp, BadRequestsGetAnErrorOrAClosedConnection) {
  auto server = serve("posefuse_workers 2\n");
  const int port = server->port();
  EXPECT_EQ(request_and_answer(port, "POST /metrics HTTP/1.1\r\n\r\n").rfind("HTTP/1.1 405 ", 0), 0u);
  EXPECT_EQ(request_and_answer(port, "GET /metrics/x HTTP/1.1\r\n\r\n").rfind("HTTP/1.1 404 ", 0), 0u);
  EXPECT_EQ(request_and_answer(port, "hello\r\n\r\n").rfind("HTTP/1.1 400 ", 0), 0u);
  constexpr char kBinary[] = "\0\xff\r\n GET \0 HTTP/1.1\r\n\r\n";
  EXPECT_EQ(request_and_answer(port, std::string(kBinary, sizeof kBinary - 1)).rfind("HTTP/1.1 400 ", 0), 0u);
  // Answered 431, though the client may see the connection reset first: the server closes
  // with the rest of the request unread.
  const std::string oversized =
      request_and_answer(port, "GET /metrics HTTP/1.1\r\nX: " + std::string(100000, 'a') + "\r\n\r\n");
  EXPECT_TRUE(oversized.empty() || oversized.rfind("HTTP/1.1 431 ", 0) == 0) << oversized.substr(0, 200);
  // Half a request, then the client goes away.
  const int fd = test::connect_loopback(port);
  test::send_text(fd, "GET /met");
  ::close(fd);

  const std::string response = test::http_get(port, "/metrics?x=1");
  EXPECT_EQ(response.rfind("HTTP/1.1 200 OK\r\n", 0), 0u) << response;
  EXPECT_EQ(test::http_body(response), "posefuse_workers 2\n");
}

TEST(MetricsHttp, ConnectionsBeyondTheLimitAreRefusedAtOnce) {
  auto server = serve("posefuse_workers 2\n", {.max_connections = 2, .deadline = kNoDeadline});
  const int first = test::connect_loopback(server->port());
  const int second = test::connect_loopback(server->port());
  EXPECT_EQ(test::http_get(server->port(), "/metrics").rfind("HTTP/1.1 503 ", 0), 0u);
  ::close(first);
  ::close(second);
  // Their slots come free once the server has seen them close.
  std::string response;
  for (int i = 0; i < 100 && response.rfind("HTTP/1.1 200 ", 0) != 0; ++i) {
    if (i > 0) std::this_thread::sleep_for(100ms);
    response = test::http_get(server->port(), "/metrics");
  }
  EXPECT_EQ(response.rfind("HTTP/1.1 200 OK\r\n", 0), 0u) << response;
}

}  // namespace
}  // namespace posefuse::server
