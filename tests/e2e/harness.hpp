// Process-level test harness: one `liftd --simulate` per Lift (own directory, config and API
// socket), a client that keeps every event it reads, and helpers for travels, the trace and
// waiting on the simulated car. Time is real here (a real pty and cycle): helpers wait on events
// and protocol state with generous limits, never on fixed sleeps for the outcome.
#pragma once

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <thread>
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
  json call(json request, std::chrono::milliseconds timeout = 5s) {
    request["id"] = ++id_;
    if (!api_.send(request)) return nullptr;
    const auto end = Clock::now() + timeout;
    while (Clock::now() < end) {
      const json reply = next(end);
      if (reply.is_object() && reply.contains("id") && reply["id"] == id_) return reply;
    }
    return nullptr;
  }

  /// The first event named `name` after the last one a wait returned whose data satisfies
  /// `match`; null after `timeout`.
  json wait_event(const std::string& name, const std::function<bool(const json&)>& match,
                  std::chrono::milliseconds timeout) {
    const auto end = Clock::now() + timeout;
    while (true) {
      for (; cursor_ < events_.size(); ++cursor_) {
        const json& e = events_[cursor_];
        if (e["event"] == name && match(e["data"])) return events_[cursor_++];
      }
      if (Clock::now() >= end) return nullptr;
      next(std::min(end, Clock::now() + 200ms));
    }
  }

  /// Reads whatever arrives for `duration` (events are kept).
  void drain(std::chrono::milliseconds duration) {
    const auto end = Clock::now() + duration;
    while (Clock::now() < end) next(end);
  }

  /// Every event read so far.
  const std::vector<json>& events() const { return events_; }

 private:
  // The next line (an event is also appended to events_), or null at `end`.
  json next(Clock::time_point end) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(end - Clock::now());
    if (left.count() <= 0) return nullptr;
    json line = api_.next(left);
    if (line.is_object() && line.contains("event")) events_.push_back(line);
    return line;
  }

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
inline std::vector<std::string> daemon_env() {
  std::vector<std::string> env = {"PATH=/usr/bin:/bin", "TZ=UTC"};
  for (const char* name : {"ASAN_OPTIONS", "UBSAN_OPTIONS", "LSAN_OPTIONS"}) {
    if (const char* value = std::getenv(name)) env.push_back(std::string(name) + "=" + value);
  }
  return env;
}

/// One `liftd --simulate --config FILE` with the API socket in its own directory and no access
/// groups (the test's user owns the daemon), already watching events on its client.
class Lift {
 public:
  /// Starts the daemon with `"sim": {"dcp": dcp}` and `travel` merged into the config; waits
  /// until the link is up (setup_error() is empty then). `wrapper` runs the daemon (a program
  /// and its arguments before liftd's), e.g. a seccomp filter; `extra` is merged into the
  /// config last (another drive kind, its floors).
  Lift(const std::string& name, int dcp, const json& travel = json::object(),
       const std::vector<std::string>& wrapper = {}, const json& extra = json::object()) {
    std::string leaf = name;  // a parameterised test's name has a '/'
    std::replace(leaf.begin(), leaf.end(), '/', '-');
    dir_ = std::filesystem::temp_directory_path() /
           ("liftd-e2e-" + std::to_string(::getpid()) + "-" + leaf);
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
    socket_ = (dir_ / "api.sock").string();
    json config = {{"log", {{"level", "info"}}},
                   {"api",
                    {{"socket", socket_},
                     {"socket_group", ""},
                     {"read_group", ""},
                     {"control_group", ""},
                     {"inputs_group", ""}}},
                   {"sim", {{"dcp", dcp}}}};
    if (!travel.empty()) config["travel"] = travel;
    config.merge_patch(extra);
    const std::string config_path = (dir_ / "liftd.json").string();
    std::ofstream(config_path) << config.dump(2);
    std::vector<std::string> args = wrapper;
    for (const char* arg : {LIFTD_BINARY, "--simulate", "--config"}) args.emplace_back(arg);
    args.push_back(config_path);
    daemon_ = std::make_unique<liftd::testing::Process>(args, daemon_env(), dir_.string(), "liftd");
    // The link is up once I0, I1 and I3 went through (well under a second on a quiet machine;
    // 30 s allows for a loaded one).
    for (int i = 0; i < 300; ++i) {
      auto client = std::make_unique<Client>(socket_);
      if (client->connected()) {
        const json status = client->call({{"cmd", "status"}});
        if (status.is_object() && status["result"]["link"]["state"] == "up" &&
            status["result"]["car"]["floor"] == 0) {
          client_ = std::move(client);
          const json watch = client_->call({{"cmd", "watch"}, {"enable", true}});
          if (!watch.is_object() || !watch.value("ok", false)) error_ = "watch refused";
          return;
        }
      }
      std::this_thread::sleep_for(100ms);
    }
    error_ = "the link did not come up: " + daemon_->err();
  }
  ~Lift() {
    client_.reset();
    if (daemon_) {
      daemon_->signal(SIGTERM);
      daemon_->wait(5s);
      daemon_.reset();
    }
    std::error_code ignored;
    std::filesystem::remove_all(dir_, ignored);
  }
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
  std::optional<int> stop_daemon(int signal_number, std::chrono::milliseconds timeout) {
    daemon_->signal(signal_number);
    return daemon_->wait(timeout);
  }

  /// A request's reply (null on timeout).
  json call(const json& request) { return client_->call(request); }
  /// The `status` result.
  json status() { return client_->call({{"cmd", "status"}})["result"]; }
  /// Polls `status` until `drive.state` is `state`; false after `timeout`.
  bool wait_drive_state(const std::string& state, std::chrono::milliseconds timeout = 10s) {
    const auto end = Clock::now() + timeout;
    while (Clock::now() < end) {
      if (status()["drive"]["state"] == state) return true;
      client_->drain(50ms);
    }
    return false;
  }
  /// The flight-recorder files (liftd-trace-*.txt) in dir(), by name.
  std::vector<std::filesystem::path> trace_files() const {
    std::vector<std::filesystem::path> out;
    for (const auto& entry : std::filesystem::directory_iterator(dir_)) {
      const std::string name = entry.path().filename().string();
      if (name.rfind("liftd-trace-", 0) == 0 && entry.path().extension() == ".txt") {
        out.push_back(entry.path());
      }
    }
    std::sort(out.begin(), out.end());
    return out;
  }
  /// The car position from `status` (NaN when unknown).
  double position_mm() {
    const json p = status()["car"]["position_mm"];
    return p.is_number() ? p.get<double>() : std::nan("");
  }

  /// Waits for the next travel event `finished` or `aborted` (null after `timeout`).
  json wait_travel_end(std::chrono::milliseconds timeout = 60s) {
    return client_->wait_event(
        "travel", [](const json& d) { return d["event"] == "finished" || d["event"] == "aborted"; },
        timeout);
  }
  /// Waits for the travel event `type` (null after `timeout`).
  json wait_travel(const std::string& type, std::chrono::milliseconds timeout = 10s) {
    return client_->wait_event(
        "travel", [&](const json& d) { return d["event"] == type; }, timeout);
  }

  /// Polls status until the car is moving farther than `mm` from where it started (`from_mm`);
  /// false after `timeout`.
  bool wait_moved(double from_mm, double mm, std::chrono::milliseconds timeout = 20s) {
    const auto end = Clock::now() + timeout;
    while (Clock::now() < end) {
      const double p = position_mm();
      if (std::abs(p - from_mm) >= mm) return true;
      client_->drain(30ms);
    }
    return false;
  }

  /// The newest `count` master frames from `trace`: {t_us, command byte}.
  std::vector<std::pair<std::int64_t, int>> newest_commands(int count) {
    std::vector<std::pair<std::int64_t, int>> out;
    const json trace = client_->call({{"cmd", "trace"}, {"count", count}});
    for (const auto& f : trace["result"]["frames"]) {
      const std::string tx = f["tx"];
      out.emplace_back(f["t_us"].get<std::int64_t>(), std::stoi(tx.substr(0, 2), nullptr, 16));
    }
    return out;
  }

  /// True when drive enable (B0, DCP 9.1.1) is off in each of the newest `count` frames, checked
  /// until it holds or 2 s passed (the cycle withdraws it within a few cycles of standstill).
  bool b0_off_in_newest(int count = 5) {
    const auto end = Clock::now() + 2s;
    while (true) {
      const auto frames = newest_commands(count);
      const bool off = !frames.empty() && std::all_of(frames.begin(), frames.end(), [](auto& f) {
        return (f.second & 0x01) == 0;
      });
      if (off || Clock::now() >= end) return off;
      client_->drain(50ms);
    }
  }

  /// Events named `name` whose data satisfies `match`, counted over everything read so far.
  int count_events(const std::string& name, const std::function<bool(const json&)>& match) {
    return static_cast<int>(
        std::count_if(client_->events().begin(), client_->events().end(),
                      [&](const json& e) { return e["event"] == name && match(e["data"]); }));
  }

 private:
  std::filesystem::path dir_;
  std::string socket_;
  std::unique_ptr<liftd::testing::Process> daemon_;
  std::unique_ptr<Client> client_;
  std::string error_;
};

/// The text of a file ("" when it cannot be read).
inline std::string file_text(const std::filesystem::path& path) {
  std::ifstream in(path);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

/// `trace save` as a client sends it, on any drive kind: the reply carries the newest frame and
/// names a liftd-trace-*.txt in the lift's directory with more than `min_records` records; the
/// journal says `<kind>: flight recorder (` and names the file; a second save at once is refused
/// `busy` (one rate limit for every lift). Returns the file's text ("" on a failed expectation).
inline std::string expect_trace_save_writes_file(Lift& lift, const std::string& kind,
                                                 int min_records) {
  const json r = lift.call({{"cmd", "trace"}, {"count", 1}, {"save", true}});
  EXPECT_TRUE(r.value("ok", false)) << r.dump();
  if (!r.value("ok", false)) return "";
  EXPECT_EQ(r["result"]["frames"].size(), 1U) << r.dump();
  const std::string path = r["result"]["file"];
  EXPECT_EQ(std::filesystem::path(path).parent_path(), lift.dir());
  EXPECT_EQ(std::filesystem::path(path).filename().string().rfind("liftd-trace-", 0), 0U) << path;
  EXPECT_GT(r["result"]["records"].get<int>(), min_records) << r.dump();
  EXPECT_NE(lift.log().find(kind + ": flight recorder ("), std::string::npos) << lift.log();
  EXPECT_NE(lift.log().find("after request [event=trace_written path=" + path), std::string::npos)
      << lift.log();
  const json again = lift.call({{"cmd", "trace"}, {"save", true}});
  EXPECT_EQ(again["error"]["code"], "busy") << again.dump();
  return file_text(path);
}

/// SIGUSR1 writes one flight-recorder file, the journal names it once it is complete, and the
/// daemon runs on with its link up. Returns the file's text ("" on a failed expectation).
inline std::string expect_sigusr1_writes_file(Lift& lift) {
  EXPECT_TRUE(lift.trace_files().empty());
  lift.signal(SIGUSR1);
  for (int i = 0; i < 100 && lift.log().find("after SIGUSR1") == std::string::npos; ++i) {
    lift.api().drain(50ms);
  }
  const std::vector<std::filesystem::path> files = lift.trace_files();
  EXPECT_EQ(files.size(), 1U) << lift.log();
  if (files.size() != 1) return "";
  EXPECT_NE(lift.log().find("written to " + files.front().string() + " after SIGUSR1"),
            std::string::npos)
      << lift.log();
  EXPECT_EQ(lift.status()["link"]["state"], "up") << "the daemon runs on";
  return file_text(files.front());
}

/// Monotonic now in microseconds, comparable with the trace's t_us (both CLOCK_MONOTONIC).
inline std::int64_t mono_us() {
  return std::chrono::duration_cast<std::chrono::microseconds>(Clock::now().time_since_epoch())
      .count();
}

}  // namespace liftd::e2e
