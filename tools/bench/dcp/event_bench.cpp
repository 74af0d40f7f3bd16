// event-bench: how fast the daemon passes news both ways. Runs the real daemon wiring in
// process (Daemon + DcpLift with the simulated lift on a pty, the cycle thread at its configured
// priority, the API server) with one watcher and one dispatcher client, and measures, from the
// flight recorder's timestamps (the cycle thread's CLOCK_MONOTONIC) and the clients' own:
//   - drive reply -> watcher: from the reply in which the drive's status byte changed to the
//     watcher receiving the `state` event that shows the new byte;
//   - travel request -> ok: from the client writing `travel` to its `ok` reply, which the
//     daemon sends when the cycle has taken the command (the next frame acts on it);
//   - travel request -> command byte: to the first master frame whose command byte differs
//     from the one before the request (drive enable B0 and the travel bits; with
//     travel.use_start_parameters this comes after the I7 exchange on the channel, DCP 5.12.7).
// Prints p50, p99 and max in milliseconds and in 15 ms cycles.
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <mutex>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "common/mono_time.hpp"
#include "daemon/daemon.hpp"
#include "dcp/host/dcp_lift.hpp"
#include "host/lift_common.hpp"
#include "log/log.hpp"
#include "rt/flight_recorder.hpp"
#include "service/notify.hpp"
#include "support/api_client.hpp"

namespace {

using namespace std::chrono_literals;
using liftd::mono_now;
using liftd::MonoTime;
using nlohmann::json;

constexpr double kCycleMs = 15.0;  // DCP 7.2

/// The status byte (DCP 3.2: S0..S7) as the API spells it out.
std::uint8_t status_byte(const json& s) {
  static constexpr const char* kBits[] = {"ready",         "travel_active",   "advance_warning",
                                          "general_fault", "below_levelling", "accepted",
                                          "brake_open",    "message_error"};
  std::uint8_t b = 0;
  for (int i = 0; i < 8; ++i) {
    if (s.value(kBits[i], false)) b = static_cast<std::uint8_t>(b | (1U << i));
  }
  return b;
}

struct Seen {
  MonoTime at;
  std::uint8_t status;
};

struct Figures {
  std::vector<double> ms;
  void add(std::chrono::nanoseconds d) {
    ms.push_back(std::chrono::duration<double, std::milli>(d).count());
  }
  void print(const char* name) {
    std::sort(ms.begin(), ms.end());
    if (ms.empty()) {
      std::printf("  %-38s no samples\n", name);
      return;
    }
    const double p50 = ms[ms.size() / 2];
    const double p99 = ms[std::min(ms.size() - 1, ms.size() * 99 / 100)];
    std::printf("  %-38s %6zu %8.2f %8.2f %8.2f   %6.2f %6.2f %6.2f\n", name, ms.size(), p50, p99,
                ms.back(), p50 / kCycleMs, p99 / kCycleMs, ms.back() / kCycleMs);
  }
};

}  // namespace

// Over 120 lines: one benchmark run read top to bottom: the daemon, the watcher, the travels,
// the report.
int main(int argc, char** argv) {
  int travels = 10;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--travels") == 0 && i + 1 < argc) {
      travels = std::max(1, std::atoi(argv[++i]));
    } else {
      std::fprintf(stderr,
                   "usage: event-bench [--travels N]\n"
                   "  N travels between the lowest and the top floor (default 10)\n");
      return 2;
    }
  }
  namespace fs = std::filesystem;
  const fs::path dir =
      fs::temp_directory_path() / ("liftd-event-bench-" + std::to_string(getpid()));
  fs::create_directories(dir);
  ::setenv("XDG_RUNTIME_DIR", dir.c_str(), 1);
  liftd::log::init({liftd::log::Level::warn, liftd::log::Backend::text, "event-bench"});

  liftd::config::Config cfg = liftd::daemon::simulation_defaults();
  cfg.rt.lock_memory = true;  // as the service runs
  liftd::daemon::Daemon daemon(cfg, liftd::service::Notifier::from_environment(), std::nullopt);
  liftd::daemon::DcpLift app(daemon, cfg, true);
  std::thread daemon_thread([&] { daemon.run(); });
  auto fail = [&](const char* why) {
    std::fprintf(stderr, "event-bench: %s\n", why);
    daemon.request_stop("benchmark failed");
    daemon_thread.join();
    fs::remove_all(dir);
    return 1;
  };

  bool up = false;
  for (int i = 0; i < 300 && !up; ++i) {
    std::this_thread::sleep_for(100ms);
    liftd::testing::ApiClient probe(cfg.api.socket);  // the socket may not be there yet
    if (!probe.connected()) continue;
    const json s = probe.call({{"cmd", "status"}});
    up = s.is_object() && s["result"]["link"]["state"] == "up";
  }
  if (!up) return fail("the simulated link did not come up within 30 s");
  liftd::testing::ApiClient control(cfg.api.socket);

  // The watcher: every `state` event whose status byte differs from the last one seen.
  std::atomic<bool> stop{false};
  std::mutex seen_mutex;
  std::vector<Seen> seen;
  std::thread watcher([&] {
    liftd::testing::ApiClient w(cfg.api.socket);
    (void)w.next();  // hello
    (void)w.call({{"cmd", "watch"}, {"enable", true}});
    int last = -1;
    while (!stop.load()) {
      const json line = w.next(200ms);
      const MonoTime at = mono_now();
      if (!line.is_object() || line.value("event", "") != "state") continue;
      const std::uint8_t b = status_byte(line["data"]["dcp"]["status"]);
      if (b == last) continue;
      last = b;
      const std::lock_guard lock(seen_mutex);
      seen.push_back({at, b});
    }
  });

  Figures to_watcher, to_reply, to_frame;
  int floor = 0;
  int done = 0;
  while (done < travels) {
    const json status = control.call({{"cmd", "status"}});
    const bool idle = status.is_object() && status["ok"] == true &&
                      status["result"]["travel"]["state"] == "idle" &&
                      status["result"]["link"]["state"] == "up" &&
                      !status["result"]["dcp"]["status"]["travel_active"].get<bool>();
    if (!idle) {
      std::this_thread::sleep_for(50ms);
      continue;
    }
    // To the other end of the shaft from where the car is.
    const json& at_floor = status["result"]["car"]["floor"];
    floor = at_floor.is_number() && at_floor.get<int>() >= 3 ? 0 : 5;
    const MonoTime asked = mono_now();
    const json r = control.call({{"cmd", "travel"}, {"floor", floor}});
    to_reply.add(mono_now() - asked);
    if (!r.is_object() || r["ok"] != true) {
      std::fprintf(stderr, "event-bench: travel refused: %s\n", r.dump().c_str());
      stop = true;
      watcher.join();
      return fail("a travel request was refused");
    }
    // Until the car is idle again (the recorder keeps 30 s; a travel takes a few).
    std::this_thread::sleep_for(500ms);
    for (int i = 0; i < 600; ++i) {
      const json s = control.call({{"cmd", "status"}});
      if (s.is_object() && s["result"]["travel"]["state"] == "idle" &&
          !s["result"]["dcp"]["status"]["travel_active"].get<bool>()) {
        break;
      }
      std::this_thread::sleep_for(50ms);
    }
    std::this_thread::sleep_for(200ms);  // the last events reach the watcher
    const std::vector<liftd::rt::FrameRecord> records = app.cycle().recorder().copy();
    // travel request -> first frame acting on it
    int before = -1;
    for (const auto& rec : records) {
      if (rec.direction != liftd::rt::Direction::Tx || rec.length == 0) continue;
      if (rec.time < asked) {
        before = rec.bytes[0];
      } else if (before >= 0 && rec.bytes[0] != before) {
        to_frame.add(rec.time - asked);
        break;
      }
    }
    // drive reply with a new status byte -> the watcher sees it
    std::vector<Seen> got;
    {
      const std::lock_guard lock(seen_mutex);
      got = seen;
    }
    int last = -1;
    for (const auto& rec : records) {
      if (rec.direction != liftd::rt::Direction::Rx ||
          (rec.flags & liftd::rt::record_flag::kReply) == 0 ||
          (rec.flags & liftd::rt::record_flag::kBad) != 0) {
        continue;
      }
      const std::uint8_t b = rec.bytes[0];
      if (b != last && last >= 0 && rec.time >= asked) {
        // The first watcher sample at or after the reply with this byte.
        for (const Seen& s : got) {
          if (s.at >= rec.time && s.status == b) {
            to_watcher.add(s.at - rec.time);
            break;
          }
        }
      }
      last = b;
    }
    ++done;
  }
  stop = true;
  watcher.join();

  const auto rt_status = app.cycle().thread_status();
  std::printf("event-bench: %d travels 0 <-> 5, cycle thread %s; times in ms and in 15 ms cycles\n",
              travels, rt_status.realtime ? "SCHED_FIFO" : "SCHED_OTHER (not real-time)");
  std::printf("  %-38s %6s %8s %8s %8s   %6s %6s %6s\n", "", "n", "p50", "p99", "max", "p50/c",
              "p99/c", "max/c");
  to_watcher.print("drive reply -> watcher event");
  to_reply.print("travel request -> ok (cycle took it)");
  to_frame.print("travel request -> command byte");
  daemon.request_stop("benchmark done");
  daemon_thread.join();
  fs::remove_all(dir);
  return 0;
}
