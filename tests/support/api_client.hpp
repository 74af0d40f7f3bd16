// A line client of liftd's API socket for tests and benchmarks: connect, send requests, read
// replies and events with deadlines. Header-only.
#pragma once

#include <sys/socket.h>
#include <sys/time.h>
#include <sys/un.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <nlohmann/json.hpp>
#include <string>

namespace liftd::testing {

using namespace std::chrono_literals;
using nlohmann::json;

/// A line client of the API socket with a receive deadline.
class ApiClient {
 public:
  explicit ApiClient(const std::string& path) {
    fd_ = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
    sockaddr_un addr{};
    addr.sun_family = AF_UNIX;
    path.copy(addr.sun_path, sizeof(addr.sun_path) - 1);
    if (::connect(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0) {
      ::close(fd_);
      fd_ = -1;
    }
  }
  ~ApiClient() {
    if (fd_ >= 0) ::close(fd_);
  }
  bool connected() const { return fd_ >= 0; }

  /// Sends one request (false if the socket refused it).
  bool send(const json& request) { return send_line(request.dump()); }
  /// Sends one raw line (without its newline).
  bool send_line(const std::string& text) {
    const std::string line = text + "\n";
    return ::write(fd_, line.data(), line.size()) == static_cast<ssize_t>(line.size());
  }
  /// The next line as JSON, or null after `timeout`.
  json next(std::chrono::milliseconds timeout = 5s) {
    const auto end = std::chrono::steady_clock::now() + timeout;
    while (true) {
      if (auto pos = buffer_.find('\n'); pos != std::string::npos) {
        const std::string line = buffer_.substr(0, pos);
        buffer_.erase(0, pos + 1);
        return json::parse(line);
      }
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
          end - std::chrono::steady_clock::now());
      if (left.count() <= 0) return nullptr;
      timeval tv{0, static_cast<suseconds_t>(std::min<long>(left.count(), 200) * 1000)};
      ::setsockopt(fd_, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
      char chunk[4096];
      const ssize_t n = ::read(fd_, chunk, sizeof chunk);
      if (n > 0) buffer_.append(chunk, static_cast<std::size_t>(n));
      if (n == 0) return nullptr;
    }
  }
  /// Sends a request with an id and returns its reply (events in between are skipped).
  json call(json request, std::chrono::milliseconds timeout = 5s) {
    request["id"] = ++id_;
    send(request);
    const auto end = std::chrono::steady_clock::now() + timeout;
    while (std::chrono::steady_clock::now() < end) {
      json line = next(timeout);
      if (line.is_null()) break;
      if (line.contains("id") && line["id"] == id_) return line;
    }
    return nullptr;
  }
  /// Waits for an event `name` whose data satisfies `match`.
  template <typename Match>
  json wait_event(const std::string& name, Match match, std::chrono::milliseconds timeout) {
    const auto end = std::chrono::steady_clock::now() + timeout;
    while (std::chrono::steady_clock::now() < end) {
      json line = next(1s);
      if (line.is_object() && line.value("event", "") == name && match(line["data"])) return line;
    }
    return nullptr;
  }

 private:
  int fd_ = -1;
  int id_ = 0;
  std::string buffer_;
};

}  // namespace liftd::testing
