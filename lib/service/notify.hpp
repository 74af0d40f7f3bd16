// systemd service protocol through libsystemd: sd_notify(3) (READY=1, STATUS=, STOPPING=1,
// RELOADING=1, WATCHDOG=1), sd_watchdog_enabled(3), sd_listen_fds_with_names(3), and our
// watchdog that pings only while the daemon makes progress. Never call any of this from the
// real-time cycle thread: libsystemd formats, allocates and makes system calls.
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
#include <vector>

namespace liftd::service {

/// Sends notifications to the service manager with sd_notify(3). Disabled (every call a no-op
/// that succeeds) when $NOTIFY_SOCKET was not set at construction, i.e. when not started by
/// systemd with Type=notify.
class Notifier {
 public:
  /// A disabled notifier.
  Notifier() = default;
  /// The notifier for $NOTIFY_SOCKET (disabled when unset or empty).
  static Notifier from_environment();

  /// True when a notification socket was configured.
  bool enabled() const { return enabled_; }

  /// Sends raw state lines ("KEY=value\n..."); returns 0 or the errno of the failure.
  int notify(std::string_view state);
  /// READY=1 with a STATUS= line: startup (or a reload) is complete.
  int ready(std::string_view status);
  /// STATUS= line a technician reads in `systemctl status liftd`.
  int status(std::string_view status);
  /// STOPPING=1 with a STATUS= line: shutdown has begun.
  int stopping(std::string_view status);
  /// RELOADING=1 with a STATUS= line and MONOTONIC_USEC= (CLOCK_MONOTONIC now, as sd_notify(3)
  /// asks for): a configuration reload has begun; READY=1 ends it.
  int reloading(std::string_view status);
  /// WATCHDOG=1: the daemon is alive and making progress.
  int watchdog();

 private:
  explicit Notifier(bool enabled) : enabled_(enabled) {}
  bool enabled_ = false;
};

/// A STATUS= value on one line: newlines (which would start a new KEY=) become spaces.
std::string status_line(std::string_view text);

/// The watchdog timeout systemd asks for, from sd_watchdog_enabled(3) (WATCHDOG_USEC, checked
/// against WATCHDOG_PID): nullopt when there is none, when it is meant for another process,
/// or when the variables are malformed (then with a warning in the log).
std::optional<std::chrono::microseconds> watchdog_from_environment();

/// One socket passed by systemd (socket activation).
struct ListenFd {
  int fd = -1;       ///< the descriptor, from SD_LISTEN_FDS_START on
  std::string name;  ///< FileDescriptorName= of the socket unit ("unknown" when not named)
};

/// The sockets systemd passed to this process, from sd_listen_fds_with_names(3); unsets the
/// variables so nothing started later inherits them. Empty when not socket-activated.
std::vector<ListenFd> listen_fds_from_environment();

/// The passed descriptor that is a listening Unix stream socket named `name` (or the only
/// one when there is a single unnamed socket), or -1. Passed descriptors that are not used are
/// the caller's to close (close_unused_listen_fds).
int pick_listen_fd(const std::vector<ListenFd>& fds, std::string_view name);

/// The path a Unix socket is bound to: "" for an unnamed (or abstract) one, nullopt when `fd` is
/// not a Unix socket.
std::optional<std::string> unix_socket_path(int fd);

/// Closes every passed descriptor except `keep`, logging each one it closes.
void close_unused_listen_fds(const std::vector<ListenFd>& fds, int keep);

/// How long a start that liftd refuses keeps answering clients on the socket systemd passed
/// (answer_refused_start) before it exits. It also paces the starts the socket makes for
/// clients that keep connecting, to one per this interval (the unit's RestartSec=).
inline constexpr std::chrono::milliseconds kRefusedStartLinger{2000};

/// A start liftd refuses (its configuration, or real time this machine does not give) with the
/// API socket passed by systemd: every client already waiting on `listen_fd`, and every one
/// that connects within `linger`, gets one line {"id":null,"ok":false,"error":{"code":
/// "not_ready","message":`message`}} and is closed. So the waiting clients learn why instead of
/// waiting, and the socket does not start liftd again at once for them (which would end in
/// systemd's start limit and a failed socket). Returns how many clients were answered.
std::size_t answer_refused_start(int listen_fd, std::string_view message,
                                 std::chrono::milliseconds linger);

/// Sends WATCHDOG=1 every half timeout on an io_context, but only while the progress probe
/// returns true; a stuck probe lets systemd's watchdog fire and restart the service.
class Watchdog {
 public:
  /// Decides whether the daemon made progress since the probe's previous call; called once at
  /// start() (its answer then only sets the baseline) and once per period after it.
  using Probe = std::function<bool()>;

  /// A watchdog for `timeout` (WATCHDOG_USEC) that pings through `notifier`.
  Watchdog(asio::io_context& io, Notifier& notifier, std::chrono::microseconds timeout,
           Probe probe);

  /// Starts pinging: one ping at once, then one every period() while the probe reports
  /// progress. The probe is asked at once only to take its baseline: the daemon has just
  /// started (READY=1), and a cycle that has not yet counted its first cycle is no stall. The
  /// first judgement comes one whole period later.
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
