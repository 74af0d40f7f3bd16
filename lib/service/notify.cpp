// sd_notify(3), sd_watchdog_enabled(3), sd_listen_fds_with_names(3) and the progress-gated
// watchdog.
#include "service/notify.hpp"

#include <fcntl.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <systemd/sd-daemon.h>
#include <unistd.h>

#include <cerrno>
#include <cstddef>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <string>

#include "log/log.hpp"

namespace liftd::service {

Notifier Notifier::from_environment() {
  const char* socket = std::getenv("NOTIFY_SOCKET");
  return Notifier{socket != nullptr && *socket != '\0'};
}

int Notifier::notify(std::string_view state) {
  if (!enabled_) return 0;
  const std::string text(state);
  // sd_notify: > 0 sent, 0 no socket (environment changed since), < 0 -errno.
  const int result = sd_notify(0, text.c_str());
  return result < 0 ? -result : 0;
}

int Notifier::ready(std::string_view status) {
  if (!enabled_) return 0;
  const int result = sd_notifyf(0, "READY=1\nSTATUS=%s", status_line(status).c_str());
  return result < 0 ? -result : 0;
}

int Notifier::status(std::string_view status) {
  if (!enabled_) return 0;
  const int result = sd_notifyf(0, "STATUS=%s", status_line(status).c_str());
  return result < 0 ? -result : 0;
}

int Notifier::stopping(std::string_view status) {
  if (!enabled_) return 0;
  const int result = sd_notifyf(0, "STOPPING=1\nSTATUS=%s", status_line(status).c_str());
  return result < 0 ? -result : 0;
}

int Notifier::reloading(std::string_view status) {
  if (!enabled_) return 0;
  timespec now{};
  ::clock_gettime(CLOCK_MONOTONIC, &now);
  const auto usec = static_cast<unsigned long long>(now.tv_sec) * 1000000ULL +
                    static_cast<unsigned long long>(now.tv_nsec) / 1000ULL;
  const int result = sd_notifyf(0, "RELOADING=1\nSTATUS=%s\nMONOTONIC_USEC=%llu",
                                status_line(status).c_str(), usec);
  return result < 0 ? -result : 0;
}

int Notifier::watchdog() {
  return notify("WATCHDOG=1");
}

std::string status_line(std::string_view text) {
  std::string out(text);
  for (char& c : out) {
    if (c == '\n' || c == '\r') c = ' ';
  }
  return out;
}

std::optional<std::chrono::microseconds> watchdog_from_environment() {
  std::uint64_t usec = 0;
  const int result = sd_watchdog_enabled(0, &usec);
  if (result < 0) {
    log::event(log::Level::warn, "service", "watchdog_invalid",
               {{"errno", std::to_string(-result)}},
               std::string("WATCHDOG_USEC/WATCHDOG_PID are malformed (") + std::strerror(-result) +
                   "); running without the systemd watchdog");
    return std::nullopt;
  }
  if (result == 0) return std::nullopt;
  return std::chrono::microseconds(static_cast<std::chrono::microseconds::rep>(usec));
}

std::vector<ListenFd> listen_fds_from_environment() {
  char** names = nullptr;
  const int count = sd_listen_fds_with_names(1, &names);
  std::vector<ListenFd> out;
  if (count < 0) {
    log::event(log::Level::warn, "service", "listen_fds_invalid",
               {{"errno", std::to_string(-count)}},
               std::string("LISTEN_FDS/LISTEN_PID are malformed (") + std::strerror(-count) +
                   "); creating the API socket instead");
    return out;
  }
  for (int i = 0; i < count; ++i) {
    ListenFd fd;
    fd.fd = SD_LISTEN_FDS_START + i;
    if (names != nullptr && names[i] != nullptr) fd.name = names[i];
    out.push_back(std::move(fd));
  }
  if (names != nullptr) {
    for (int i = 0; i < count; ++i) std::free(names[i]);
    std::free(static_cast<void*>(names));
  }
  return out;
}

int pick_listen_fd(const std::vector<ListenFd>& fds, std::string_view name) {
  const auto usable = [](int fd) { return sd_is_socket_unix(fd, SOCK_STREAM, 1, nullptr, 0) > 0; };
  for (const auto& fd : fds) {
    if (fd.name == name && usable(fd.fd)) return fd.fd;
  }
  // A socket unit without FileDescriptorName= names its socket after the unit ("liftd.socket")
  // in systemd and "unknown" in systemd-socket-activate: take it when it is the only one.
  if (fds.size() == 1 && usable(fds.front().fd)) return fds.front().fd;
  return -1;
}

std::optional<std::string> unix_socket_path(int fd) {
  sockaddr_un address{};
  socklen_t length = sizeof address;
  // NOLINTNEXTLINE(cppcoreguidelines-pro-type-reinterpret-cast): the sockets API
  if (::getsockname(fd, reinterpret_cast<sockaddr*>(&address), &length) != 0 ||
      address.sun_family != AF_UNIX) {
    return std::nullopt;
  }
  const std::size_t offset = offsetof(sockaddr_un, sun_path);
  if (length <= offset || address.sun_path[0] == '\0') return std::string();  // unnamed, abstract
  return std::string(address.sun_path, strnlen(address.sun_path, length - offset));
}

void close_unused_listen_fds(const std::vector<ListenFd>& fds, int keep) {
  for (const auto& fd : fds) {
    if (fd.fd == keep) continue;
    log::event(log::Level::warn, "service", "listen_fd_unused",
               {{"fd", std::to_string(fd.fd)}, {"name", fd.name}},
               "systemd passed socket " + std::to_string(fd.fd) + " (\"" + fd.name +
                   "\") that is not a listening Unix stream socket for the API; closing it");
    ::close(fd.fd);
  }
}

namespace {

std::string json_string(std::string_view text) {
  std::string out = "\"";
  for (const char c : text) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char escaped[8];
      std::snprintf(escaped, sizeof escaped, "\\u%04x", static_cast<unsigned>(c));
      out += escaped;
    } else {
      out += c;
    }
  }
  return out + "\"";
}

}  // namespace

std::size_t answer_refused_start(int listen_fd, std::string_view message,
                                 std::chrono::milliseconds linger) {
  if (listen_fd < 0) return 0;
  const std::string line =
      "{\"id\":null,\"ok\":false,\"error\":{\"code\":\"not_ready\",\"message\":" +
      json_string(message) + "}}\n";
  const auto deadline = std::chrono::steady_clock::now() + linger;
  std::size_t answered = 0;
  // systemd passes a blocking socket: accept() would wait for the next client past the
  // deadline (for ever, if none comes). The API's acceptor makes it non-blocking too.
  const int flags = ::fcntl(listen_fd, F_GETFL);
  if (flags >= 0 && (flags & O_NONBLOCK) == 0) ::fcntl(listen_fd, F_SETFL, flags | O_NONBLOCK);
  for (;;) {
    // Everyone waiting now, then whoever comes before the deadline.
    for (;;) {
      const int client = ::accept4(listen_fd, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
      if (client < 0) {
        if (errno == EINTR || errno == ECONNABORTED) continue;
        break;  // EAGAIN: nobody waiting; anything else: nothing more to do with this socket
      }
      // One short line into an empty socket buffer: it fits, or the client is gone.
      [[maybe_unused]] const ssize_t sent = ::send(client, line.data(), line.size(), MSG_NOSIGNAL);
      // Whatever the client sent already is read and dropped: closing with it unread would
      // reset the connection instead of ending it.
      char sink[512];
      while (::recv(client, sink, sizeof sink, MSG_DONTWAIT) > 0) {
      }
      ::shutdown(client, SHUT_RDWR);
      ::close(client);
      ++answered;
    }
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) return answered;
    pollfd pfd{listen_fd, POLLIN, 0};
    if (::poll(&pfd, 1, static_cast<int>(left.count()) + 1) < 0 && errno != EINTR) {
      return answered;
    }
  }
}

Watchdog::Watchdog(asio::io_context& io, Notifier& notifier, std::chrono::microseconds timeout,
                   Probe probe)
    : timer_(io), notifier_(notifier), period_(timeout / 2), probe_(std::move(probe)) {}

void Watchdog::start() {
  running_ = true;
  // The baseline, not a judgement: right after READY=1 the cycle may not have counted its first
  // cycle yet, and a probe that compares with its previous answer (which starts at 0) would
  // call that a stall (a false watchdog_withheld after a healthy start).
  if (probe_) probe_();
  notifier_.watchdog();
  ++pings_sent_;
  schedule();
}

void Watchdog::stop() {
  running_ = false;
  timer_.cancel();
}

void Watchdog::tick() {
  if (!running_) return;
  const bool progress = !probe_ || probe_();
  if (progress) {
    if (stalled_) {
      log::event(log::Level::info, "service", "watchdog_resumed", {},
                 "progress resumed, sending WATCHDOG=1 again");
      stalled_ = false;
    }
    notifier_.watchdog();
    ++pings_sent_;
  } else {
    if (!stalled_) {
      log::event(log::Level::error, "service", "watchdog_withheld",
                 {{"timeout_ms", std::to_string(period_.count() * 2 / 1000)}},
                 "no progress: withholding WATCHDOG=1, systemd will restart the service if "
                 "this lasts",
                 log::Catalogued::WatchdogWithheld);
      stalled_ = true;
    }
    ++pings_withheld_;
  }
  schedule();
}

void Watchdog::schedule() {
  timer_.expires_after(period_);
  timer_.async_wait([this](const std::error_code& error) {
    if (!error) tick();
  });
}

}  // namespace liftd::service
