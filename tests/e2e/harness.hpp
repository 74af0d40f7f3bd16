// Process-level test harness: one `liftd --simulate` per Lift (own directory, config and API
// socket), a client that keeps every event it reads, and helpers for travels, the trace and
// waiting on the simulated car. Time is real here (a real pty and cycle): helpers wait on events
// and protocol state with generous limits, never on fixed sleeps for the outcome. Compiled once
// (harness.cpp, library e2e_harness) for every e2e binary.
#pragma once

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "daemon/process.hpp"
#include "support/api_client.hpp"

namespace liftd::e2e {

using namespace std::chrono_literals;
using nlohmann::json;
using Clock = std::chrono::steady_clock;

/// A client of the API socket (over the shared testing::ApiClient) that keeps every event it
/// reads in `events()`, so a test can count them afterwards; replies are matched by id.
class Client {
 public:
  /// Connects to `path`; connected() says whether it worked.
  explicit Client(const std::string& path) : api_(path) {}

  /// True when the socket is connected.
  bool connected() const { return api_.connected(); }

  /// Sends a request with a fresh id and returns its reply, or null after `timeout`.
  json call(json request, std::chrono::milliseconds timeout = 5s);

  /// The first event named `name` after the last one a wait returned whose data satisfies
  /// `match`; null after `timeout`.
  json wait_event(const std::string& name, const std::function<bool(const json&)>& match,
                  std::chrono::milliseconds timeout);

  /// Reads whatever arrives for `duration` (events are kept).
  void drain(std::chrono::milliseconds duration);

  /// Every event read so far.
  const std::vector<json>& events() const { return events_; }

 private:
  // The next line (an event is also appended to events_), or null at `end`.
  json next(Clock::time_point end);

  liftd::testing::ApiClient api_;
  int id_ = 0;
  std::vector<json> events_;
  std::size_t cursor_ = 0;
};

/// Level of floor `floor` in the default building (6 floors, 3000 mm apart).
inline double level_mm(int floor) {
  return 3000.0 * floor;
}

/// The environment a daemon gets: a minimal PATH plus the sanitizer options of the test run.
std::vector<std::string> daemon_env();

/// One `liftd --simulate --config FILE` with the API socket in its own directory and no access
/// groups (the test's user owns the daemon), already watching events on its client.
class Lift {
 public:
  /// Starts the daemon with `"sim": {"dcp": dcp}` and `travel` merged into the config; waits
  /// until the link is up (setup_error() is empty then). `wrapper` runs the daemon (a program
  /// and its arguments before liftd's), e.g. a seccomp filter; `extra` is merged into the
  /// config last (another drive kind, its floors).
  Lift(const std::string& name, int dcp, const json& travel = json::object(),
       const std::vector<std::string>& wrapper = {}, const json& extra = json::object());
  ~Lift();
  Lift(const Lift&) = delete;
  Lift& operator=(const Lift&) = delete;

  /// Empty when the daemon runs with the link up; otherwise what went wrong.
  const std::string& setup_error() const { return error_; }
  /// The watching client (replies and every event).
  Client& api() { return *client_; }
  /// The API socket's path (for more clients).
  const std::string& socket() const { return socket_; }
  /// The daemon's own directory: its config, its API socket, and so its runtime directory
  /// (flight-recorder files).
  const std::filesystem::path& dir() const { return dir_; }
  /// Sends `signal_number` to the daemon (it keeps running unless the signal ends it).
  void signal(int signal_number) { daemon_->signal(signal_number); }
  /// The daemon's stderr so far (for failure messages).
  std::string log() const { return daemon_->err(); }
  /// Sends `signal_number` to the daemon and waits for it to exit: its exit code, or nullopt
  /// if it still runs after `timeout`.
  std::optional<int> stop_daemon(int signal_number, std::chrono::milliseconds timeout);

  /// A request's reply (null on timeout).
  json call(const json& request) { return client_->call(request); }
  /// The `status` result.
  json status();
  /// Polls `status` until `drive.state` is `state`; false after `timeout`.
  bool wait_drive_state(const std::string& state, std::chrono::milliseconds timeout = 10s);
  /// The flight-recorder files (liftd-trace-*.txt) in dir(), by name.
  std::vector<std::filesystem::path> trace_files() const;
  /// The car position from `status` (NaN when unknown).
  double position_mm();

  /// Waits for the next travel event `finished` or `aborted` (null after `timeout`).
  json wait_travel_end(std::chrono::milliseconds timeout = 60s);
  /// Waits for the travel event `type` (null after `timeout`).
  json wait_travel(const std::string& type, std::chrono::milliseconds timeout = 10s);

  /// Polls status until the car is moving farther than `mm` from where it started (`from_mm`);
  /// false after `timeout`.
  bool wait_moved(double from_mm, double mm, std::chrono::milliseconds timeout = 20s);

  /// The newest `count` master frames from `trace`: {t_us, command byte}.
  std::vector<std::pair<std::int64_t, int>> newest_commands(int count);

  /// True when drive enable (B0, DCP 9.1.1) is off in each of the newest `count` frames, checked
  /// until it holds or 2 s passed (the cycle withdraws it within a few cycles of standstill).
  bool b0_off_in_newest(int count = 5);

  /// Events named `name` whose data satisfies `match`, counted over everything read so far.
  int count_events(const std::string& name, const std::function<bool(const json&)>& match);

 private:
  std::filesystem::path dir_;
  std::string socket_;
  std::unique_ptr<liftd::testing::Process> daemon_;
  std::unique_ptr<Client> client_;
  std::string error_;
};

/// The text of a file ("" when it cannot be read).
std::string file_text(const std::filesystem::path& path);

/// `trace save` as a client sends it, on any drive kind: the reply carries the newest frame and
/// names a liftd-trace-*.txt in the lift's directory with more than `min_records` records; the
/// journal says `<kind>: flight recorder (` and names the file; a second save at once is refused
/// `busy` (one rate limit for every lift). Returns the file's text ("" on a failed expectation).
std::string expect_trace_save_writes_file(Lift& lift, const std::string& kind, int min_records);

/// SIGUSR1 writes one flight-recorder file, the journal names it once it is complete, and the
/// daemon runs on with its link up. Returns the file's text ("" on a failed expectation).
std::string expect_sigusr1_writes_file(Lift& lift);

/// Monotonic now in microseconds, comparable with the trace's t_us (both CLOCK_MONOTONIC).
std::int64_t mono_us();

}  // namespace liftd::e2e
