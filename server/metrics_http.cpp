#include "server/metrics_http.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/eventfd.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <string_view>
#include <vector>

#include "common/error.hpp"

namespace posefuse::server {

namespace {

using Clock = std::chrono::steady_clock;

[[noreturn]] void fail(const std::string& listen, const std::string& what) {
  throw Error(ErrorCode::kFailedPrecondition, "--metrics-listen", "cannot listen on '" + listen + "': " + what);
}

std::string response(const char* status, const std::string& body, const char* extra_header = "") {
  return std::string("HTTP/1.1 ") + status + "\r\nContent-Type: text/plain; version=0.0.4; charset=utf-8\r\n" +
         extra_header + "Content-Length: " + std::to_string(body.size()) + "\r\nConnection: close\r\n\r\n" + body;
}

// The answer to a whole request head (up to its empty line).
std::string answer(std::string_view head, const std::function<std::string()>& render) {
  const std::string_view line = head.substr(0, head.find("\r\n"));  // METHOD TARGET HTTP/1.x
  const auto method_end = line.find(' ');
  const auto target_end = line.rfind(' ');
  if (method_end == std::string_view::npos || target_end == method_end ||
      line.substr(target_end + 1).rfind("HTTP/1.", 0) != 0) {
    return response("400 Bad Request", "not an HTTP/1 request; try GET /metrics\n");
  }
  if (line.substr(0, method_end) != "GET") {
    return response("405 Method Not Allowed", "only GET; try GET /metrics\n", "Allow: GET\r\n");
  }
  const std::string_view target = line.substr(method_end + 1, target_end - method_end - 1);
  if (target.substr(0, target.find('?')) != "/metrics") return response("404 Not Found", "not found; try /metrics\n");
  try {
    return response("200 OK", render());
  } catch (const std::exception&) {
    return response("500 Internal Server Error", "the metrics could not be rendered\n");
  }
}

struct Connection {
  int fd = -1;
  Clock::time_point deadline;
  std::string request;
  std::string response;  // set once the request is answered; then only writing remains
  std::size_t sent = 0;
};

// Reads what the client sent and answers once the request head is complete.
// False when the connection is done with (the client went away).
bool read_request(Connection& connection, const MetricsHttpLimits& limits, const std::function<std::string()>& render) {
  char buffer[4096];
  const ssize_t n = ::recv(connection.fd, buffer, sizeof buffer, 0);
  if (n < 0) return errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR;
  if (n == 0) return false;
  connection.request.append(buffer, static_cast<std::size_t>(n));
  const auto head_end = connection.request.find("\r\n\r\n");
  if (head_end != std::string::npos && head_end + 4 <= limits.max_request_bytes) {
    connection.response = answer(std::string_view(connection.request).substr(0, head_end), render);
  } else if (connection.request.size() > limits.max_request_bytes) {
    connection.response = response("431 Request Header Fields Too Large",
                                   "the request head is over " + std::to_string(limits.max_request_bytes) + " bytes\n");
  }
  return true;
}

// Sends what the socket takes of the answer. False when the connection is done with.
bool write_response(Connection& connection) {
  const ssize_t n = ::send(connection.fd, connection.response.data() + connection.sent,
                           connection.response.size() - connection.sent, MSG_NOSIGNAL | MSG_DONTWAIT);
  if (n < 0) return errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR;
  connection.sent += static_cast<std::size_t>(n);
  return connection.sent < connection.response.size();
}

// Until the nearest deadline; -1 (no timeout) without connections.
int poll_timeout_ms(const std::vector<Connection>& connections, Clock::time_point now) {
  if (connections.empty()) return -1;
  Clock::time_point nearest = connections.front().deadline;
  for (const Connection& connection : connections) nearest = std::min(nearest, connection.deadline);
  if (nearest <= now) return 0;
  return static_cast<int>(std::chrono::ceil<std::chrono::milliseconds>(nearest - now).count());
}

}  // namespace

MetricsHttpServer::MetricsHttpServer(const std::string& listen, std::function<std::string()> render,
                                     MetricsHttpLimits limits)
    : render_(std::move(render)), limits_(limits) {
  const auto colon = listen.rfind(':');
  if (colon == std::string::npos) throw_invalid("--metrics-listen", "expected HOST:PORT");
  sockaddr_in address{};
  address.sin_family = AF_INET;
  if (::inet_pton(AF_INET, listen.substr(0, colon).c_str(), &address.sin_addr) != 1) {
    throw_invalid("--metrics-listen", "'" + listen + "': the host must be a numeric IPv4 address");
  }
  int port = 0;
  try {
    port = std::stoi(listen.substr(colon + 1));
  } catch (const std::exception&) {
    throw_invalid("--metrics-listen", "'" + listen + "': bad port");
  }
  if (port < 0 || port > 65535) throw_invalid("--metrics-listen", "port out of range");
  address.sin_port = htons(static_cast<std::uint16_t>(port));

  listen_fd_ = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0);
  if (listen_fd_ < 0) fail(listen, std::strerror(errno));
  const int yes = 1;
  ::setsockopt(listen_fd_, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
  if (::bind(listen_fd_, reinterpret_cast<sockaddr*>(&address), sizeof address) != 0 || ::listen(listen_fd_, 64) != 0) {
    const std::string why = std::strerror(errno);
    ::close(listen_fd_);
    fail(listen, why);
  }
  socklen_t length = sizeof address;
  ::getsockname(listen_fd_, reinterpret_cast<sockaddr*>(&address), &length);
  port_ = ntohs(address.sin_port);
  stop_fd_ = ::eventfd(0, EFD_CLOEXEC);
  if (stop_fd_ < 0) {
    const std::string why = std::strerror(errno);
    ::close(listen_fd_);
    fail(listen, why);
  }
  thread_ = std::thread([this] { serve(); });
}

MetricsHttpServer::~MetricsHttpServer() {
  const std::uint64_t one = 1;
  [[maybe_unused]] const ssize_t written = ::write(stop_fd_, &one, sizeof one);
  thread_.join();
  ::close(stop_fd_);
  ::close(listen_fd_);
}

void MetricsHttpServer::serve() {
  std::vector<Connection> connections;
  std::vector<pollfd> waiting;
  for (;;) {
    waiting.assign({{stop_fd_, POLLIN, 0}, {listen_fd_, POLLIN, 0}});
    for (const Connection& connection : connections) {
      waiting.push_back({connection.fd, static_cast<short>(connection.response.empty() ? POLLIN : POLLOUT), 0});
    }
    if (::poll(waiting.data(), waiting.size(), poll_timeout_ms(connections, Clock::now())) < 0 && errno != EINTR) {
      break;
    }
    if (waiting[0].revents != 0) break;  // stopping: open connections are closed below, unanswered

    const Clock::time_point now = Clock::now();
    std::vector<Connection> open;
    for (std::size_t i = 0; i < connections.size(); ++i) {
      Connection& connection = connections[i];
      bool keep = now < connection.deadline;
      if (keep && waiting[i + 2].revents != 0) {
        if (connection.response.empty()) keep = read_request(connection, limits_, render_);
        // Written at once: a small answer usually fits the socket's buffer.
        if (keep && !connection.response.empty()) keep = write_response(connection);
      }
      if (keep) {
        open.push_back(std::move(connection));
      } else {
        ::close(connection.fd);
      }
    }
    connections = std::move(open);

    if (waiting[1].revents == 0) continue;
    for (int fd; (fd = ::accept4(listen_fd_, nullptr, nullptr, SOCK_CLOEXEC | SOCK_NONBLOCK)) >= 0;) {
      if (connections.size() >= limits_.max_connections) {
        const std::string busy = response("503 Service Unavailable", "too many connections; retry later\n");
        [[maybe_unused]] const ssize_t sent = ::send(fd, busy.data(), busy.size(), MSG_NOSIGNAL | MSG_DONTWAIT);
        ::close(fd);
        continue;
      }
      connections.push_back(Connection{fd, now + limits_.deadline, {}, {}, 0});
    }
  }
  for (const Connection& connection : connections) ::close(connection.fd);
}

}  // namespace posefuse::server
