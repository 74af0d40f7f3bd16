// sd_notify protocol and the progress-gated watchdog.
#include "service/notify.hpp"

#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <cstdlib>
#include <cstring>
#include <string>

#include "log/log.hpp"

namespace liftd::service {

Notifier::Notifier(std::string socket) : socket_(std::move(socket)) {}

Notifier Notifier::from_environment() {
  const char* socket = std::getenv("NOTIFY_SOCKET");
  if (socket == nullptr || *socket == '\0') return Notifier{};
  return Notifier{socket};
}

Notifier::~Notifier() {
  if (fd_ >= 0) ::close(fd_);
}

Notifier::Notifier(Notifier&& other) noexcept
    : socket_(std::move(other.socket_)), fd_(std::exchange(other.fd_, -1)) {
  other.socket_.clear();
}

Notifier& Notifier::operator=(Notifier&& other) noexcept {
  if (this != &other) {
    if (fd_ >= 0) ::close(fd_);
    socket_ = std::move(other.socket_);
    other.socket_.clear();
    fd_ = std::exchange(other.fd_, -1);
  }
  return *this;
}

int Notifier::notify(std::string_view state) {
  if (!enabled()) return 0;
  sockaddr_un address{};
  address.sun_family = AF_UNIX;
  if (socket_.size() >= sizeof(address.sun_path)) return ENAMETOOLONG;
  std::memcpy(address.sun_path, socket_.data(), socket_.size());
  // "@name" is an abstract socket: the address starts with a NUL and has no terminator.
  socklen_t length = static_cast<socklen_t>(offsetof(sockaddr_un, sun_path) + socket_.size());
  if (socket_.front() == '@') {
    address.sun_path[0] = '\0';
  } else {
    length = static_cast<socklen_t>(length + 1);
  }
  if (fd_ < 0) {
    fd_ = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    if (fd_ < 0) return errno;
  }
  const ssize_t sent = ::sendto(fd_, state.data(), state.size(), MSG_NOSIGNAL | MSG_DONTWAIT,
                                reinterpret_cast<const sockaddr*>(&address), length);
  return sent < 0 ? errno : 0;
}

int Notifier::ready(std::string_view status) {
  return notify("READY=1\nSTATUS=" + std::string(status));
}

int Notifier::status(std::string_view status) {
  return notify("STATUS=" + std::string(status));
}

int Notifier::stopping(std::string_view status) {
  return notify("STOPPING=1\nSTATUS=" + std::string(status));
}

int Notifier::watchdog() {
  return notify("WATCHDOG=1");
}

std::optional<std::chrono::microseconds> parse_watchdog(const char* usec, const char* pid,
                                                        pid_t self) {
  if (usec == nullptr || *usec == '\0') return std::nullopt;
  std::uint64_t value = 0;
  const char* end = usec + std::strlen(usec);
  const auto [rest, error] = std::from_chars(usec, end, value);
  if (error != std::errc{} || rest != end || value == 0) return std::nullopt;
  if (pid != nullptr && *pid != '\0') {
    std::int64_t owner = 0;
    const char* pid_end = pid + std::strlen(pid);
    const auto [pid_rest, pid_error] = std::from_chars(pid, pid_end, owner);
    if (pid_error != std::errc{} || pid_rest != pid_end || owner != self) return std::nullopt;
  }
  return std::chrono::microseconds(static_cast<std::chrono::microseconds::rep>(value));
}

std::optional<std::chrono::microseconds> watchdog_from_environment() {
  return parse_watchdog(std::getenv("WATCHDOG_USEC"), std::getenv("WATCHDOG_PID"), ::getpid());
}

Watchdog::Watchdog(asio::io_context& io, Notifier& notifier, std::chrono::microseconds timeout,
                   Probe probe)
    : timer_(io), notifier_(notifier), period_(timeout / 2), probe_(std::move(probe)) {}

void Watchdog::start() {
  running_ = true;
  tick();
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
                 "this lasts");
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
