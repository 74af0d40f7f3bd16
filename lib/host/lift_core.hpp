// The daemon side every drive kind's lift shares, its controller running on a real-time thread
// behind lock-free queues: the io thread's wake-up on that thread's news, replies waiting for
// their controller, the `state` events, the service stop that lands a moving car first, and the
// reports of travels, faults and served calls.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <asio.hpp>

#include "api/backend.hpp"
#include "api/server.hpp"
#include "common/mono_time.hpp"
#include "host/host.hpp"
#include "lift/cause.hpp"
#include "lift/faults.hpp"
#include "lift/inputs.hpp"
#include "lift/rules.hpp"
#include "rt/cycle_runner.hpp"
#include "rt/rt_thread.hpp"

namespace liftd::daemon {

// Every lift's io thread alike.
/// The io thread looks at a lift's replies, events and watch stream when its real-time thread
/// says there is news (an eventfd the thread bumps after each cycle, frame or exchange), and at
/// least this often should the thread stall or the bus fall silent.
inline constexpr std::chrono::milliseconds kFallbackPoll{100};
/// The simulated I/O board reports its inputs this often (well inside inputs.timeout_ms).
inline constexpr std::chrono::milliseconds kSimInputsPeriod{100};
/// A service stop during a travel waits this long for the car to come to rest at a floor: a
/// stop from full speed at the next possible floor plus the drive's hold time takes a few
/// seconds; the unit's TimeoutStopSec=30s leaves room for the forced end and the rest of the
/// shutdown.
inline constexpr std::chrono::seconds kShutdownDeadline{20};

/// Publishes `state` events: at once for a discrete change, coalesced to api.state_rate_hz when
/// only the position (or a `continuous` member of the kind's details, e.g. a speed) moved.
class StatePublisher {
 public:
  explicit StatePublisher(int state_rate_hz, std::vector<std::string> continuous = {})
      : interval_(std::chrono::nanoseconds(std::chrono::seconds(1)) /
                  (state_rate_hz > 0 ? state_rate_hz : 1)),
        continuous_(std::move(continuous)) {}
  void publish(api::Server& server, api::StatusSnapshot status, MonoTime now);

 private:
  std::chrono::nanoseconds interval_;
  std::vector<std::string> continuous_;
  std::optional<api::StatusSnapshot> last_;
  MonoTime last_publish_{};
};

/// Wakes the io thread for a lift's real-time thread: `poll` runs on the io thread each time
/// the thread bumps fd() (CycleRunner, CanRunner and UssRunner take it as their notify fd) and
/// every kFallbackPoll besides, between start() and stop().
class ThreadWake {
 public:
  /// Throws std::runtime_error if the eventfd cannot be made.
  ThreadWake(asio::io_context& io, std::chrono::nanoseconds fallback);
  ThreadWake(const ThreadWake&) = delete;
  ThreadWake& operator=(const ThreadWake&) = delete;
  /// The eventfd the real-time thread writes to (open until this object is destroyed: stop
  /// the thread first).
  int fd() const noexcept { return fd_; }
  void start(std::function<void()> poll);
  void stop();
  bool running() const noexcept { return running_; }

 private:
  void wait_for_news();
  void arm_fallback();
  int fd_ = -1;
  asio::posix::stream_descriptor news_;  ///< owns fd_
  asio::steady_timer fallback_timer_;
  std::chrono::nanoseconds fallback_;
  std::function<void()> poll_;
  bool running_ = false;
};

/// What the wind-down reads of a controller's snapshot.
struct RestFacts {
  bool shutting_down = false;  ///< the controller took the shutdown command
  bool quiesced = false;       ///< at rest, no travel signal in the last telegram
  std::optional<std::size_t> floor;
  std::optional<std::int64_t> position_mm;
};

/// A service stop must not leave a moving car to the drive's own timeout: the
/// controller stops the travel as `stop` does and refuses new ones; the stop completes once the
/// car is at rest with every travel signal off, or, after `deadline`, with every signal dropped
/// at once and `grace` for the last telegrams to go out.
class WindDown {
 public:
  /// `send_shutdown(force)` posts the controller's shutdown command (false: its queue was full).
  WindDown(Host& daemon, std::function<bool(bool force)> send_shutdown,
           std::chrono::nanoseconds deadline, std::chrono::nanoseconds grace)
      : daemon_(daemon),
        send_shutdown_(std::move(send_shutdown)),
        deadline_(deadline),
        grace_(grace) {}
  /// Starts the wind-down; `moving`: a travel is running (journalled with its target floor).
  void start(std::function<void()> done, bool moving, std::optional<std::size_t> target_floor,
             MonoTime now);
  /// Every poll: completes `done` once the controller reports rest (or the deadline forced it).
  void check(const RestFacts& facts, MonoTime now);

 private:
  Host& daemon_;
  std::function<bool(bool)> send_shutdown_;
  std::chrono::nanoseconds deadline_;
  std::chrono::nanoseconds grace_;
  std::function<void()> done_;
  MonoTime until_{};
  bool forced_ = false;
};

/// The API error code for a controller's reply code (every lift's lift::ReplyCode).
api::ErrorCode to_api_error(lift::ReplyCode code) noexcept;

/// A controller's reply as the API's result: ok with its `detail`, `floor` (and `extended`, on
/// a lift whose travels can take a new target), or the error its code stands for. Every
/// controller's CommandReply has `code` (lift::ReplyCode), `detail` and `floor`.
template <typename Reply>
api::Result reply_result(const Reply& r) {
  if (r.code == lift::ReplyCode::Ok) {
    nlohmann::json result = nlohmann::json::object();
    if (!r.detail.empty()) result["detail"] = std::string(r.detail);
    if constexpr (requires { r.extended; }) {
      if (r.extended) result["extended"] = true;
    }
    if (r.floor) result["floor"] = *r.floor;
    return api::Result::ok(std::move(result));
  }
  return api::Result::fail(to_api_error(r.code), std::string(r.detail));
}

/// Tags from here up are a controller's own (the DCP controller's travel requests): never a
/// client's.
inline constexpr std::uint32_t kFirstControllerTag = 0xFFFF'FF00U;

/// Requests sent to a controller, waiting for its reply: the responder of each by tag, and how
/// its reply becomes the API's result. A controller that never answers (a stalled thread) fails
/// the request after a grace time. One for every lift; `Reply` is the controller's CommandReply
/// (tag, lift::ReplyCode code, detail, floor).
template <typename Reply>
class PendingReplies {
 public:
  /// The result of an ok reply, for a request whose answer carries more than reply_result()
  /// shows (a drive's answer to a parameter, an I-message, a mirror telegram).
  using Completion = std::function<api::Result(const Reply&)>;

  /// Keeps `done` under a new tag (never 0, "no reply wanted", nor a controller's own).
  std::uint32_t add(api::Responder done, MonoTime deadline, Completion complete = {}) {
    std::uint32_t tag = ++next_tag_;
    if (tag == 0 || tag >= kFirstControllerTag) tag = next_tag_ = 1;
    pending_[tag] = Pending{std::move(done), std::move(complete), deadline};
    return tag;
  }
  /// Answers the request `r` is the reply to: an ok reply through the request's completion (if
  /// it has one), every other through reply_result(). False when there is none (answered or
  /// expired already).
  bool answer(const Reply& r) {
    auto it = pending_.find(r.tag);
    if (it == pending_.end()) return false;
    Pending p = std::move(it->second);
    pending_.erase(it);
    p.done(r.code == lift::ReplyCode::Ok && p.complete ? p.complete(r) : reply_result(r));
    return true;
  }
  /// Answers the request of `tag` with `result` (false when there is none).
  bool complete(std::uint32_t tag, api::Result result) {
    auto it = pending_.find(tag);
    if (it == pending_.end()) return false;
    api::Responder done = std::move(it->second.done);
    pending_.erase(it);
    done(std::move(result));
    return true;
  }
  /// True while the request of `tag` waits for its reply.
  bool waiting(std::uint32_t tag) const { return pending_.count(tag) != 0; }
  /// Fails every request past its deadline with `message` (an internal error).
  void expire(MonoTime now, const std::string& message) {
    for (auto it = pending_.begin(); it != pending_.end();) {
      if (now > it->second.deadline) {
        api::Responder done = std::move(it->second.done);
        it = pending_.erase(it);
        done(api::Result::fail(api::ErrorCode::Internal, message));
      } else {
        ++it;
      }
    }
  }

 private:
  struct Pending {
    api::Responder done;
    Completion complete;
    MonoTime deadline{};
  };
  std::map<std::uint32_t, Pending> pending_;
  std::uint32_t next_tag_ = 0;
};

/// Posts `body` to a controller's command queue under a new tag of `pending`; `complete` makes
/// an ok reply the API's result (none: reply_result). A full queue, or as many replies owed as
/// the controller's reply queue holds, answers `busy` at once: nothing was queued, so nothing
/// took effect. Returns the tag (0 when refused).
template <typename Command, typename Controller, typename Reply, typename Body>
std::uint32_t post_command(Controller& controller, PendingReplies<Reply>& pending, Body&& body,
                           api::Responder done, std::chrono::nanoseconds grace,
                           std::string_view thread,
                           typename PendingReplies<Reply>::Completion complete = {}) {
  const std::uint32_t tag = pending.add(std::move(done), mono_now() + grace, std::move(complete));
  if (!controller.post(Command{tag, std::forward<Body>(body)})) {
    pending.complete(tag, api::Result::fail(api::ErrorCode::Busy,
                                            "the " + std::string(thread) +
                                                " thread has as many requests as it can take; "
                                                "nothing was done, try again"));
    return 0;
  }
  return tag;
}

/// "up" / "down" / anything else as a direction (the `inspection` command's argument).
lift::Direction direction_of(std::string_view name) noexcept;

/// The `calls` list of a controller's snapshot (`calls`, `call_count`).
template <typename Snapshot>
nlohmann::json calls_list(const Snapshot& s) {
  nlohmann::json list = nlohmann::json::array();
  for (std::size_t i = 0; i < s.call_count; ++i) list.push_back(s.calls[i]);
  return list;
}

/// The API server as a daemon component ("api"; a failure to start names `socket_path`) with
/// reloads applied to it.
void register_api(Host& daemon, api::Server& server, const std::string& socket_path);
/// The daemon's watchdog probe over a counter a live real-time thread keeps raising.
std::function<bool()> progress_probe(std::function<std::uint64_t()> progress);
/// After a real-time thread started: journals what it lacks, and false (the caller stops it)
/// when rt.require_realtime asked for real time it did not get (--simulate always runs).
bool accept_rt_thread(const config::Config& config, const rt::RtThreadStatus& status, bool simulate,
                      std::string_view thread);
/// Journals an event of a serial runner: port opened, open failed, lost, thread status.
void journal_port_event(const rt::CycleEvent& event);

/// drive.echo for the runners (io/line_echo.hpp).
io::EchoMode echo_mode(config::EchoMode mode) noexcept;
/// status `line_echo`: {"mode": "auto", "state": "present"} (docs/api.md).
nlohmann::json line_echo_json(io::EchoMode mode, io::EchoState state);

/// status.rt from what the real-time thread got.
api::RtInfo rt_info(const rt::RtThreadStatus& status, int priority);
/// "up", "down" or nullopt for no direction (status travel.direction).
std::optional<std::string> direction_name(lift::Direction direction);
/// The active faults of a controller's fault table, oldest first as the table lists them.
template <std::size_t N, typename TextFn, typename WallFn>
std::vector<api::FaultInfo> active_faults(const std::array<bool, N>& active,
                                          const std::array<MonoTime, N>& since, TextFn text,
                                          WallFn wall) {
  std::vector<api::FaultInfo> out;
  for (std::size_t i = 0; i < N; ++i) {
    if (!active[i]) continue;
    const auto code = static_cast<lift::FaultCode>(i);
    out.push_back(
        {std::string(lift::fault_code_name(code)), std::string(text(code)), wall(since[i])});
  }
  return out;
}
/// status car.doors from the machine inputs the controller sees: "reopening" (a reversal),
/// "locked", "closed" or "open"; none without valid inputs.
std::optional<std::string> door_state(const lift::Inputs& inputs);
/// status service.reason: the first of stopping, a fault, inspection, recall, a learning travel
/// and a drive that lets no travel start; empty when the car is in service (docs/api.md
/// `status`, the same on every drive kind).
std::string out_of_service(bool stopping, bool faulted, const lift::Inputs& inputs, bool learning,
                           drive::State drive_state);

/// Journals and publishes a fault that became active or ended.
void report_fault(api::Server& server, lift::FaultCode code, std::string_view text, bool active);
/// Journals and publishes a travel event of any drive kind with the API name of its `cause`
/// (lift::to_string; null when None, and the journal names it only for an aborted travel).
void report_travel(api::Server& server, std::string_view type, std::string_view kind,
                   lift::Cause cause, bool aborted, std::optional<std::int64_t> target_mm,
                   std::optional<std::int64_t> position_mm);
/// report_travel() for a controller's travel event (`type` Started/Finished/Aborted, `kind`,
/// `cause`, `floor`; to_string() of the kind found beside its type). A DCP travel event carries
/// its target and position itself and has types of its own (a target extended, a fast start
/// armed, a drive fault: DCP 4.1, 12, 9.1.6), named by its to_string().
template <typename TravelEvent, typename Controller>
void report_travel(api::Server& server, const TravelEvent& t, Controller& controller) {
  using Type = decltype(t.type);
  const bool aborted = t.type == Type::Aborted;
  if constexpr (requires { t.target_mm; }) {
    // A run without a destination carries none (docs/api.md `travel`).
    report_travel(server, to_string(t.type), to_string(t.kind), t.cause, aborted,
                  t.has_target() ? std::optional<std::int64_t>(t.target_mm) : std::nullopt,
                  t.position_mm);
  } else {
    const char* type = t.type == Type::Started    ? "started"
                       : t.type == Type::Finished ? "finished"
                                                  : "aborted";
    // The run's own target however it ends (an aborted travel named the floor it left).
    const auto floors = controller.floors_mm();
    const std::optional<std::int64_t> target_mm =
        t.target && *t.target < floors.size() ? std::optional<std::int64_t>(floors[*t.target])
                                              : std::nullopt;
    report_travel(server, type, Controller::CoreTypes::Travel::kind_name(t.kind), t.cause, aborted,
                  target_mm, controller.snapshot().position_mm);
  }
}
/// Journals and publishes a served call.
void report_call_served(api::Server& server, std::size_t floor);
/// liftd emptied the calls queue for `cause`: a journal line and the calls_dropped event with
/// the floors the queue held.
void report_calls_dropped(api::Server& server, const lift::DroppedCalls& dropped,
                          lift::Cause cause);

}  // namespace liftd::daemon
