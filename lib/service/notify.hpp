// systemd service protocol: sd_notify datagrams (READY=1, STATUS=, STOPPING=1, WATCHDOG=1) and
// the watchdog that pings only while the daemon makes progress. Written by hand (a datagram to
// $NOTIFY_SOCKET) so tests can point it at a socket they bind.
#pragma once

#include <sys/types.h>

#include <asio/io_context.hpp>
#include <asio/steady_timer.hpp>
#include <chrono>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <string_view>

namespace liftd::service {

/// Sends notification datagrams to the service manager. Disabled (every call a no-op that
/// succeeds) when there is no socket, i.e. when not started by systemd with Type=notify.
class Notifier {
 public:
  /// A disabled notifier.
  Notifier() = default;
  /// A notifier for `socket`: a filesystem path, or "@name" for an abstract socket.
  explicit Notifier(std::string socket);
  /// The notifier for $NOTIFY_SOCKET (disabled when unset or empty).
  static Notifier from_environment();
  ~Notifier();
  Notifier(Notifier&& other) noexcept;
  Notifier& operator=(Notifier&& other) noexcept;
  Notifier(const Notifier&) = delete;
  Notifier& operator=(const Notifier&) = delete;

  /// True when a socket is configured.
  bool enabled() const { return !socket_.empty(); }
  /// The configured socket ("" when disabled).
  const std::string& socket() const { return socket_; }

  /// Sends raw state lines ("KEY=value\n..."); returns 0 or the errno of the failure.
  int notify(std::string_view state);
  /// READY=1 with a STATUS= line: startup is complete.
  int ready(std::string_view status);
  /// STATUS= line a technician reads in `systemctl status liftd`.
  int status(std::string_view status);
  /// STOPPING=1 with a STATUS= line: shutdown has begun.
  int stopping(std::string_view status);
  /// WATCHDOG=1: the daemon is alive and making progress.
  int watchdog();

 private:
  std::string socket_;
  int fd_ = -1;
};

/// The watchdog timeout systemd asks for, from the values of WATCHDOG_USEC and WATCHDOG_PID:
/// nullopt when usec is missing, malformed or 0, or when pid is set and is not `self`.
std::optional<std::chrono::microseconds> parse_watchdog(const char* usec, const char* pid,
                                                        pid_t self);
/// parse_watchdog() on this process's environment.
std::optional<std::chrono::microseconds> watchdog_from_environment();

/// Sends WATCHDOG=1 every half timeout on an io_context, but only while the progress probe
/// returns true; a stuck probe lets systemd's watchdog fire and restart the service.
class Watchdog {
 public:
  /// Decides whether the daemon is making progress; called once per period.
  using Probe = std::function<bool()>;

  /// A watchdog for `timeout` (WATCHDOG_USEC) that pings through `notifier`.
  Watchdog(asio::io_context& io, Notifier& notifier, std::chrono::microseconds timeout,
           Probe probe);

  /// Starts pinging: one ping at once, then one every period().
  void start();
  /// Stops pinging.
  void stop();
  /// Half the timeout (sd_watchdog_enabled(3) recommends pinging at half the interval).
  std::chrono::microseconds period() const { return period_; }
  /// WATCHDOG=1 datagrams sent so far.
  std::uint64_t pings_sent() const { return pings_sent_; }
  /// Periods in which the probe said no and nothing was sent.
  std::uint64_t pings_withheld() const { return pings_withheld_; }

 private:
  void tick();
  void schedule();

  asio::steady_timer timer_;
  Notifier& notifier_;
  std::chrono::microseconds period_;
  Probe probe_;
  bool running_ = false;
  bool stalled_ = false;
  std::uint64_t pings_sent_ = 0;
  std::uint64_t pings_withheld_ = 0;
};

}  // namespace liftd::service
