// api-load-bench: what API load does to the real-time threads. Runs the real daemon wiring in
// process (Daemon + DcpLift with the simulated lift on a pty, the cycle thread at its configured
// priority, the API server), keeps the car travelling between the lowest and the top floor, and
// beside it a USS bus (tools/bench/uss/uss_bus.*: uss::UssRunner + uss::Master against simulated
// slaves on a pty at 38400 baud, the bus thread at the cycle's priority) and a reference loop: a
// bare SCHED_FIFO clock_nanosleep loop with the cycle's period and priority, which stands for what
// the platform gives any real-time thread. Each window (quiet, then 1, 8 and 32 clients sending
// `status` as fast as they can) measures all three at once, so the cycle's and the bus's wake-up
// lateness are read against the reference's under the same load in the same run (the criterion: at
// most 1.1 times the reference's p99, no skipped cycle the reference does not also show, no missing
// reply, no link fault). Also prints requests per second and request latency per load.
// With --board CPU it runs as docs/operations.md sets up a board ("Real-time settings of a
// board"): the real-time threads (the cycle, the USS bus, the reference loop and link, and the
// simulated drive and slaves, which stand for hardware outside the board) on that CPU, every
// other thread (liftd's io thread, the API clients) off it, and the unbound workqueue, where the
// tty's flip-buffer worker runs, on it for the run (put back at the end). A SCHED_IDLE thread
// keeps that CPU from halting (--no-idle-poll leaves it out): what the CPU's resume-latency
// setting does on a board with a cpuidle driver (docs/operations.md); a virtual machine's guest
// without one halts its virtual CPU whenever the real-time threads sleep, and its host then
// wakes it up to milliseconds late (measured here: the reference loop 2.2 ms late at worst, 3
// cycles skipped in 15 s, with no load at all).
#include <poll.h>
#include <sched.h>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "bench/uss/uss_bus.hpp"
#include "common/cpu_set.hpp"
#include "common/mono_time.hpp"
#include "daemon/daemon.hpp"
#include "dcp/host/dcp_lift.hpp"
#include "host/lift_common.hpp"
#include "log/log.hpp"
#include "rt/cpu_split.hpp"
#include "rt/cycle_runner.hpp"
#include "rt/histogram.hpp"
#include "rt/rt_thread.hpp"
#include "service/notify.hpp"
#include "support/api_client.hpp"
#include "support/reference_link.hpp"

namespace {

using namespace std::chrono_literals;
using liftd::mono_now;
using liftd::MonoTime;
using liftd::rt::HistogramData;
using nlohmann::json;
namespace rt = liftd::rt;
using liftd::bench::UssBus;
using liftd::bench::UssBusCounters;
using liftd::bench::UssBusStats;

/// A connected client that has read the greeting.
struct Client : liftd::testing::ApiClient {
  explicit Client(const std::string& path) : ApiClient(path) {
    if (connected()) (void)next();  // hello
  }
  bool ok() const { return connected(); }
};

/// The samples recorded between two copies of one histogram.
HistogramData window(const HistogramData& before, const HistogramData& after) {
  HistogramData d = after;
  d.count = after.count - before.count;
  d.sum_ns = after.sum_ns - before.sum_ns;
  d.max_ns = 0;
  for (std::size_t i = 0; i < d.bins.size() && i < before.bins.size(); ++i) {
    d.bins[i] = after.bins[i] - before.bins[i];
    if (d.bins[i] != 0) d.max_ns = static_cast<std::int64_t>(i + 1) * d.bin_width_ns;
  }
  return d;
}

struct LoadResult {
  double requests_per_s = 0;
  double latency_p50_us = 0;
  double latency_p99_us = 0;
  double fairness = 0;  // fewest requests of one client / most of one client (1 = even)
};

/// `clients` threads sending `status` back to back for `duration`.
LoadResult hammer(const std::string& socket, int clients, std::chrono::seconds duration) {
  std::atomic<bool> stop{false};
  std::vector<std::vector<double>> latencies(static_cast<std::size_t>(clients));
  std::vector<std::thread> threads;
  for (int c = 0; c < clients; ++c) {
    threads.emplace_back([&, c] {
      Client client(socket);
      if (!client.ok()) return;
      auto& mine = latencies[static_cast<std::size_t>(c)];
      mine.reserve(1 << 20);
      while (!stop.load(std::memory_order_relaxed)) {
        const auto t0 = std::chrono::steady_clock::now();
        if (client.call({{"cmd", "status"}}).is_null()) return;
        mine.push_back(
            std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0)
                .count());
      }
    });
  }
  std::this_thread::sleep_for(duration);
  stop = true;
  for (auto& t : threads) t.join();
  std::vector<double> all;
  std::size_t fewest = SIZE_MAX;
  std::size_t most = 0;
  for (const auto& l : latencies) {
    all.insert(all.end(), l.begin(), l.end());
    fewest = std::min(fewest, l.size());
    most = std::max(most, l.size());
  }
  std::sort(all.begin(), all.end());
  LoadResult r;
  if (all.empty()) return r;
  r.requests_per_s = static_cast<double>(all.size()) / static_cast<double>(duration.count());
  r.latency_p50_us = all[all.size() / 2];
  r.latency_p99_us = all[std::min(all.size() - 1, all.size() * 99 / 100)];
  r.fairness = most > 0 ? static_cast<double>(fewest) / static_cast<double>(most) : 0;
  return r;
}

/// Keeps the car travelling between the lowest and the top floor while the benchmark runs.
void dispatcher(const std::string& socket, std::atomic<bool>& stop, std::atomic<int>& travels) {
  Client client(socket);
  int floor = 5;
  while (!stop.load()) {
    const json status = client.call({{"cmd", "status"}});
    if (status.is_object() && status["ok"] == true &&
        status["result"]["travel"]["state"] == "idle" &&
        status["result"]["link"]["state"] == "up" &&
        !status["result"]["dcp"]["status"]["travel_active"].get<bool>()) {
      const json r = client.call({{"cmd", "travel"}, {"floor", floor}});
      if (r.is_object() && r["ok"] == true) {
        ++travels;
        floor = floor == 0 ? 5 : 0;
      }
    }
    std::this_thread::sleep_for(200ms);
  }
}

/// The DCP link's fault count (`stats` dcp.link_losses: DCP 7.3, ten missing replies in a row
/// or the port lost), or -1 when the daemon did not answer.
long long link_faults(const std::string& socket) {
  Client client(socket);
  const json s = client.call({{"cmd", "stats"}});
  if (!s.is_object() || s["ok"] != true) return -1;
  return s["result"]["dcp"]["link_losses"].get<long long>();
}

/// The reference: a bare absolute clock_nanosleep loop at the cycle's period and priority
/// (cyclictest's loop). Its lateness is what the platform gives any real-time thread; it counts
/// the cycles it would have skipped by the cycle's own rule (rt::decide_wake, DCP 7.2 window).
class ReferenceLoop {
 public:
  ReferenceLoop(std::chrono::nanoseconds period, std::chrono::nanoseconds window)
      : period_(period), window_(window) {}
  ~ReferenceLoop() { stop(); }
  int start(const rt::RtThreadOptions& options) {
    return thread_.start(options, [this] { loop(); });
  }
  void stop() {
    stop_ = true;
    thread_.join();
  }
  HistogramData lateness() const { return lateness_.copy(); }
  std::uint64_t skipped() const { return skipped_.load(std::memory_order_relaxed); }
  const rt::RtThreadStatus& status() const { return thread_.status(); }

 private:
  void loop() noexcept {
    MonoTime next = mono_now() + period_;
    while (!stop_.load(std::memory_order_relaxed)) {
      rt::sleep_until(next);
      const auto late = mono_now() - next;
      lateness_.record(late);
      const rt::WakeDecision d = rt::decide_wake(late, window_, period_);
      if (d.send) {
        next += period_;
      } else {
        skipped_.fetch_add(d.skipped, std::memory_order_relaxed);
        next += period_ * static_cast<std::int64_t>(d.skipped);
      }
    }
  }
  std::chrono::nanoseconds period_;
  std::chrono::nanoseconds window_;
  rt::Histogram<20000> lateness_{1us};  // 0..20 ms in 1 us bins, as the cycle's
  std::atomic<std::uint64_t> skipped_{0};
  std::atomic<bool> stop_{false};
  rt::RtThread thread_;
};

/// The unbound workqueue's CPU mask (sysfs; root only): where the kernel runs the tty's
/// flip-buffer work, which carries every received byte to the line discipline. Set for the run
/// and put back when this object goes.
class WorkqueueMask {
 public:
  static constexpr const char* kPath = "/sys/devices/virtual/workqueue/cpumask";
  WorkqueueMask() = default;
  WorkqueueMask(const WorkqueueMask&) = delete;
  WorkqueueMask& operator=(const WorkqueueMask&) = delete;
  ~WorkqueueMask() {
    if (!saved_.empty()) write(saved_);
  }
  static std::string read() {
    std::string mask;
    std::getline(std::ifstream(kPath), mask);
    return mask;
  }
  /// Only `cpu` (below 32: one 32-bit word of the kernel's hexadecimal mask). Returns false,
  /// with the mask unchanged, when it could not be written.
  bool set_only(int cpu) {
    const std::string before = read();
    char mask[16];
    std::snprintf(mask, sizeof mask, "%x", 1U << static_cast<unsigned>(cpu));
    if (before.empty() || !write(mask)) return false;
    saved_ = before;
    return true;
  }

 private:
  static bool write(const std::string& mask) {
    std::ofstream out(kPath);
    out << mask << "\n";
    out.flush();
    return static_cast<bool>(out);
  }
  std::string saved_;
};

/// Keeps one CPU from halting between the real-time threads' wake-ups: a SCHED_IDLE spin, which
/// any other thread on that CPU preempts at once (the kernel preempts an idle-policy task for
/// every waking task of another policy).
class IdlePoller {
 public:
  IdlePoller() = default;
  IdlePoller(const IdlePoller&) = delete;
  IdlePoller& operator=(const IdlePoller&) = delete;
  ~IdlePoller() { stop(); }
  /// 0, or an errno (the thread, its pinning or SCHED_IDLE refused).
  int start(int cpu) {
    stop_ = false;
    int error = 0;
    std::atomic<bool> ready{false};
    thread_ = std::thread([this, cpu, &error, &ready] {
      cpu_set_t set;
      CPU_ZERO(&set);
      CPU_SET(static_cast<std::size_t>(cpu), &set);
      sched_param idle{};
      if (::sched_setaffinity(0, sizeof set, &set) != 0 ||
          ::sched_setscheduler(0, SCHED_IDLE, &idle) != 0) {
        error = errno;
      }
      ready = true;
      if (error != 0) return;
      while (!stop_.load(std::memory_order_relaxed)) {
      }
    });
    while (!ready) std::this_thread::yield();
    if (error != 0) stop();
    return error;
  }
  void stop() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
  }

 private:
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

/// Everything one window measured.
struct Window {
  std::string name;
  int clients = 0;
  HistogramData cycle, reference, uss;
  rt::CycleCounters cycle_counters;  // deltas over the window
  UssBusCounters uss_counters;
  std::uint64_t reference_skipped = 0;
  std::uint64_t link_exchanges = 0;  // the reference link's
  std::uint64_t link_missing = 0;
  long long link_faults = 0;
  LoadResult load;
};

/// Counter deltas (`after` - `before`) of the fields the verdict reads.
rt::CycleCounters delta(const rt::CycleCounters& a, const rt::CycleCounters& b) {
  rt::CycleCounters d;
  d.cycles = b.cycles - a.cycles;
  d.skipped_cycles = b.skipped_cycles - a.skipped_cycles;
  d.missing_replies = b.missing_replies - a.missing_replies;
  d.late_replies = b.late_replies - a.late_replies;
  d.late_sends = b.late_sends - a.late_sends;
  d.bad_replies = b.bad_replies - a.bad_replies;
  return d;
}
UssBusCounters delta(const UssBusCounters& a, const UssBusCounters& b) {
  UssBusCounters d;
  d.exchanges = b.exchanges - a.exchanges;
  d.reply_timeouts = b.reply_timeouts - a.reply_timeouts;
  d.bad_replies = b.bad_replies - a.bad_replies;
  return d;
}

double ratio(const HistogramData& d, const HistogramData& ref) {
  const double r = ref.percentile_us(0.99);
  return r > 0 ? d.percentile_us(0.99) / r : 0;
}

/// The criterion for one loaded window: p99 at most 1.1 times the reference's.
constexpr double kMaxRatio = 1.1;

/// Whether the real-time criterion was met under 8 and 32 clients, and liftd's own share.
struct Verdict {
  bool all_ok = true;
  bool own_all_ok = true;
};

/// The lateness, missing-reply and API-load tables, one row per window.
void print_window_tables(const std::vector<Window>& windows, bool with_uss_bus) {
  std::printf(
      "\nwake-up lateness per window (us): the DCP cycle, the USS bus and the reference loop\n");
  std::printf("  %-11s %9s %9s %9s %6s %6s %9s %9s  %8s %8s %7s %6s  %8s %6s\n", "window",
              "cycle p99", "ref p99", "uss p99", "cyc/r", "uss/r", "cyc max", "ref max", "skipped",
              "ref skip", "missing", "faults", "uss tmo", "uss ex");
  for (const Window& w : windows) {
    std::printf(
        "  %-11s %9s %9s %9s %6.2f %6.2f %9.1f %9.1f  %8llu %8llu %7llu %6lld  %8llu %6llu\n",
        w.name.c_str(), w.cycle.percentile_text(0.99).c_str(),
        w.reference.percentile_text(0.99).c_str(),
        with_uss_bus ? w.uss.percentile_text(0.99).c_str() : "-", ratio(w.cycle, w.reference),
        with_uss_bus ? ratio(w.uss, w.reference) : 0.0, w.cycle.max_us(), w.reference.max_us(),
        static_cast<unsigned long long>(w.cycle_counters.skipped_cycles),
        static_cast<unsigned long long>(w.reference_skipped),
        static_cast<unsigned long long>(w.cycle_counters.missing_replies), w.link_faults,
        static_cast<unsigned long long>(w.uss_counters.reply_timeouts),
        static_cast<unsigned long long>(w.uss_counters.exchanges));
  }
  std::printf(
      "\nmissing replies per window: the DCP cycle, the reference link (same period and deadline, "
      "bare pty echo), the USS bus (reply timeouts)\n  %-11s %9s %9s %9s %9s %9s\n",
      "window", "cycle", "of", "ref link", "of", "uss");
  for (const Window& w : windows) {
    std::printf("  %-11s %9llu %9llu %9llu %9llu %9llu\n", w.name.c_str(),
                static_cast<unsigned long long>(w.cycle_counters.missing_replies),
                static_cast<unsigned long long>(w.cycle_counters.cycles),
                static_cast<unsigned long long>(w.link_missing),
                static_cast<unsigned long long>(w.link_exchanges),
                static_cast<unsigned long long>(w.uss_counters.reply_timeouts));
  }
  std::printf("\nAPI load per window\n  %-11s %9s %9s %9s %9s\n", "window", "req/s", "req p50",
              "req p99", "fairness");
  for (const Window& w : windows) {
    if (w.clients == 0) continue;
    std::printf("  %-11s %9.0f %9.1f %9.1f %9.2f\n", w.name.c_str(), w.load.requests_per_s,
                w.load.latency_p50_us, w.load.latency_p99_us, w.load.fairness);
  }
}

/// One verdict line per loaded window and link, for tools/bench.sh. The criterion
/// (p99 at most 1.1 x the reference loop's, no skipped cycle it does not also show, no missing
/// reply, no link fault), and beside it liftd's own share: misses the reference link also had
/// in the same window are the platform's (the tty's flip-buffer worker), as are the link faults
/// they cause.
/// Returns whether the criterion and liftd's own share were met under 8 and 32 clients.
Verdict print_verdicts(const std::vector<Window>& windows, bool with_uss_bus) {
  std::printf("\n");
  bool all_ok = true;
  bool own_all_ok = true;
  for (const Window& w : windows) {
    if (w.clients == 0) continue;
    const double rc = ratio(w.cycle, w.reference);
    const bool timing_ok =
        rc <= kMaxRatio && w.cycle_counters.skipped_cycles <= w.reference_skipped;
    const bool dcp_ok = timing_ok && w.cycle_counters.missing_replies == 0 && w.link_faults == 0;
    const bool dcp_own_ok = timing_ok && w.cycle_counters.missing_replies <= w.link_missing;
    std::printf(
        "verdict dcp %d clients: p99 %.2f x reference, skipped %llu (reference %llu), missing "
        "%llu (reference link %llu), link faults %lld: %s (own share %s)\n",
        w.clients, rc, static_cast<unsigned long long>(w.cycle_counters.skipped_cycles),
        static_cast<unsigned long long>(w.reference_skipped),
        static_cast<unsigned long long>(w.cycle_counters.missing_replies),
        static_cast<unsigned long long>(w.link_missing), w.link_faults, dcp_ok ? "ok" : "MISS",
        dcp_own_ok ? "ok" : "MISS");
    bool uss_ok = true;
    bool uss_own_ok = true;
    if (with_uss_bus) {
      const double ru = ratio(w.uss, w.reference);
      uss_ok = ru <= kMaxRatio && w.uss_counters.reply_timeouts == 0;
      uss_own_ok = ru <= kMaxRatio && w.uss_counters.reply_timeouts <= w.link_missing;
      std::printf(
          "verdict uss %d clients: p99 %.2f x reference, reply timeouts %llu (reference link "
          "%llu): %s (own share %s)\n",
          w.clients, ru, static_cast<unsigned long long>(w.uss_counters.reply_timeouts),
          static_cast<unsigned long long>(w.link_missing), uss_ok ? "ok" : "MISS",
          uss_own_ok ? "ok" : "MISS");
    }
    if (w.clients >= 8) {
      all_ok = all_ok && dcp_ok && uss_ok;
      own_all_ok = own_all_ok && dcp_own_ok && uss_own_ok;
    }
  }
  return {all_ok, own_all_ok};
}

}  // namespace

// Over 120 lines: one benchmark run read top to bottom: the daemon, the reference loop and
// link, the USS bus, the windows under load.
int main(int argc, char** argv) {
  std::chrono::seconds phase{20};
  bool with_uss = true;
  int board_cpu = -1;
  bool idle_poll = true;
  int api_limit = -1;  // -1: the configuration's default
  bool record = true;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--seconds") == 0 && i + 1 < argc) {
      phase = std::chrono::seconds(std::max(1, std::atoi(argv[++i])));
    } else if (std::strcmp(argv[i], "--no-uss") == 0) {
      with_uss = false;
    } else if (std::strcmp(argv[i], "--board") == 0 && i + 1 < argc) {
      board_cpu = std::atoi(argv[++i]);
    } else if (std::strcmp(argv[i], "--api-limit") == 0 && i + 1 < argc) {
      api_limit = std::max(0, std::atoi(argv[++i]));
    } else if (std::strcmp(argv[i], "--no-idle-poll") == 0) {
      idle_poll = false;
    } else if (std::strcmp(argv[i], "--no-record") == 0) {
      record = false;
    } else {
      std::fprintf(stderr,
                   "usage: api-load-bench [--seconds N] [--no-uss] [--api-limit R]\n"
                   "                      [--board CPU [--no-idle-poll]] [--no-record]\n"
                   "  N seconds per window (default 20): quiet, then 1, 8 and 32 clients\n"
                   "  --no-uss     without the USS bus beside the DCP cycle\n"
                   "  --api-limit R  api.max_requests_per_s (default: the configuration's\n"
                   "               default; 0 = no limit, as before it existed)\n"
                   "  --board CPU  a board's real-time settings (docs/operations.md): the\n"
                   "               real-time threads and the unbound workqueue on CPU (0..31),\n"
                   "               every other thread off it, a SCHED_IDLE spin keeping CPU\n"
                   "               from halting; root, two CPUs or more\n"
                   "  --no-idle-poll  --board without the spin\n"
                   "  --no-record  the lift keeps no record (record.enabled false): its\n"
                   "               travels' commits off the io thread, to compare\n");
      return 2;
    }
  }
  // Before any thread starts: the threads started from here on inherit it.
  WorkqueueMask workqueue;
  IdlePoller poller;
  std::string board_text =
      "none (every thread on any CPU; unbound workqueue mask " + WorkqueueMask::read() + ")";
  if (board_cpu >= 0) {
    const liftd::rt::CpuSplit split =
        board_cpu < 32 ? liftd::rt::keep_normal_threads_off(board_cpu) : liftd::rt::CpuSplit{};
    if (split.normal_cpus.empty()) {
      std::fprintf(stderr,
                   "api-load-bench: --board %d: not a CPU to give the real-time threads (this "
                   "process may use CPUs %s; it needs one of 0..31 and another beside it)\n",
                   board_cpu, liftd::cpu_list_text(liftd::current_cpus()).c_str());
      return 2;
    }
    const std::string before = WorkqueueMask::read();
    board_text = "real-time threads on CPU " + std::to_string(board_cpu) +
                 ", the others on CPU(s) " + liftd::cpu_list_text(split.normal_cpus) + ", " +
                 (workqueue.set_only(board_cpu)
                      ? "the unbound workqueue on CPU " + std::to_string(board_cpu) +
                            " for the run (mask " + WorkqueueMask::read() + ", was " + before + ")"
                      : "the unbound workqueue NOT moved (could not write " +
                            std::string(WorkqueueMask::kPath) + ": run as root), mask " + before);
    if (idle_poll) {
      const int error = poller.start(board_cpu);
      board_text += error == 0
                        ? ", kept from halting by a SCHED_IDLE spin"
                        : ", NOT kept from halting (" + std::string(std::strerror(error)) + ")";
    } else {
      board_text += ", left to halt when idle (--no-idle-poll)";
    }
  }
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("liftd-api-load-" + std::to_string(getpid()));
  fs::create_directories(dir);
  ::setenv("XDG_RUNTIME_DIR", dir.c_str(), 1);
  liftd::log::init({liftd::log::Level::warn, liftd::log::Backend::text, "api-load-bench"});

  ::signal(SIGPIPE, SIG_IGN);  // a refused or dropped client must not end the benchmark
  liftd::config::Config cfg = liftd::daemon::simulation_defaults();
  cfg.rt.lock_memory = true;  // as the service runs
  cfg.rt.cpu = board_cpu;
  if (api_limit >= 0) cfg.api.max_requests_per_s = api_limit;
  cfg.record.enabled = record;
  // 32 load clients plus the dispatcher and the `stats` look of each window.
  cfg.api.max_clients = 40;
  liftd::daemon::Daemon daemon(cfg, liftd::service::Notifier::from_environment(), std::nullopt);
  liftd::daemon::DcpLift app(daemon, cfg, true);
  std::thread daemon_thread([&] { daemon.run(); });

  // Wait for the link.
  bool up = false;
  for (int i = 0; i < 100 && !up; ++i) {
    std::this_thread::sleep_for(100ms);
    Client c(cfg.api.socket);
    if (!c.ok()) continue;
    const json s = c.call({{"cmd", "status"}});
    up = s.is_object() && s["result"]["link"]["state"] == "up";
  }
  if (!up) {
    std::fprintf(stderr, "api-load-bench: the simulated link did not come up\n");
    daemon.request_stop("benchmark failed");
    daemon_thread.join();
    return 1;
  }
  const rt::CycleConfig& cycle_config = app.cycle().config();
  rt::RtThreadOptions ref_options;
  ref_options.priority = cycle_config.thread.priority;
  ref_options.lock_memory = true;
  ref_options.cpu = board_cpu;
  ReferenceLoop reference(cycle_config.period, cycle_config.send_window);
  if (const int err = reference.start(ref_options); err != 0) {
    std::fprintf(stderr, "api-load-bench: reference loop: %s\n", std::strerror(err));
    return 1;
  }
  liftd::testing::ReferenceLink reference_link;
  if (const int err = reference_link.start(cycle_config.thread.priority, true, board_cpu);
      err != 0) {
    std::fprintf(stderr, "api-load-bench: reference link: %s\n", std::strerror(err));
    return 1;
  }
  std::unique_ptr<UssBus> uss_bus;
  if (with_uss) {
    try {
      uss_bus = std::make_unique<UssBus>(cycle_config.thread.priority, true, board_cpu);
      if (const int err = uss_bus->start(); err != 0) throw std::runtime_error(std::strerror(err));
    } catch (const std::exception& e) {
      std::fprintf(stderr, "api-load-bench: USS bus: %s (left out)\n", e.what());
      uss_bus.reset();
    }
  }
  std::atomic<bool> stop_dispatch{false};
  std::atomic<int> travels{0};
  std::thread dispatch([&] { dispatcher(cfg.api.socket, stop_dispatch, travels); });

  const auto rt_status = app.cycle().thread_status();
  std::printf(
      "api-load-bench: cycle thread %s priority %d, memory %s; reference loop %s at the same "
      "priority and period (%lld us); USS bus %s; %lld s per window; the car travels 0 <-> 5 "
      "throughout\nboard settings: %s\nAPI requests per second over all clients "
      "(api.max_requests_per_s): %s\n",
      rt_status.realtime ? "SCHED_FIFO" : "SCHED_OTHER (not real-time: run as root)",
      cycle_config.thread.priority, rt_status.memory_locked ? "locked" : "not locked",
      reference.status().realtime ? "SCHED_FIFO" : "SCHED_OTHER",
      static_cast<long long>(cycle_config.period.count() / 1000),
      uss_bus ? "at 38400 baud, 3 slaves, its thread at the same priority" : "left out",
      static_cast<long long>(phase.count()), board_text.c_str(),
      cfg.api.max_requests_per_s > 0 ? std::to_string(cfg.api.max_requests_per_s).c_str()
                                     : "no limit");
  std::this_thread::sleep_for(2s);  // the USS bus settles, the car starts

  std::vector<Window> windows;
  for (int clients : {0, 1, 8, 32}) {
    Window w;
    w.clients = clients;
    w.name =
        clients == 0 ? "quiet" : std::to_string(clients) + (clients == 1 ? " client" : " clients");
    const auto c0 = app.cycle().stats();
    const auto r0 = reference.lateness();
    const auto s0 = reference.skipped();
    const auto le0 = reference_link.exchanges();
    const auto lm0 = reference_link.missing();
    const UssBusStats u0 = uss_bus ? uss_bus->stats() : UssBusStats{};
    const long long f0 = link_faults(cfg.api.socket);
    if (clients == 0) {
      std::this_thread::sleep_for(phase);
    } else {
      w.load = hammer(cfg.api.socket, clients, phase);
    }
    const auto c1 = app.cycle().stats();
    w.reference = window(r0, reference.lateness());
    w.reference_skipped = reference.skipped() - s0;
    w.link_exchanges = reference_link.exchanges() - le0;
    w.link_missing = reference_link.missing() - lm0;
    w.cycle = window(c0.wake_lateness, c1.wake_lateness);
    w.cycle_counters = delta(c0.counters, c1.counters);
    if (uss_bus) {
      const UssBusStats u1 = uss_bus->stats();
      w.uss = window(u0.wake_lateness, u1.wake_lateness);
      w.uss_counters = delta(u0.counters, u1.counters);
    }
    const long long f1 = link_faults(cfg.api.socket);
    w.link_faults = f0 < 0 || f1 < 0 ? -1 : f1 - f0;
    windows.push_back(std::move(w));
  }
  stop_dispatch = true;
  dispatch.join();
  reference.stop();
  reference_link.stop();
  if (uss_bus) uss_bus->stop();
  const auto counters = app.cycle().stats().counters;

  print_window_tables(windows, uss_bus != nullptr);
  const auto [all_ok, own_all_ok] = print_verdicts(windows, uss_bus != nullptr);
  for (const Window& w : windows) {
    if (w.clients == 8) {
      // The older figure: how much 8 busy clients make the cycle later than quiet.
      std::printf("\nlateness ratio 8 clients / quiet: p99 %.2f, mean %.2f\n",
                  w.cycle.percentile_us(0.99) / windows.front().cycle.percentile_us(0.99),
                  w.cycle.mean_us() / windows.front().cycle.mean_us());
    }
  }
  std::printf(
      "travels started %d; cycles %llu, late sends %llu, overruns %llu, skipped %llu, missing "
      "replies %llu (late %llu)\n",
      travels.load(), static_cast<unsigned long long>(counters.cycles),
      static_cast<unsigned long long>(counters.late_sends),
      static_cast<unsigned long long>(counters.overruns),
      static_cast<unsigned long long>(counters.skipped_cycles),
      static_cast<unsigned long long>(counters.missing_replies),
      static_cast<unsigned long long>(counters.late_replies));
  std::printf("real-time criterion under 8 and 32 clients: %s; liftd's own share: %s\n",
              all_ok ? "met" : "MISSED", own_all_ok ? "met" : "MISSED");
  daemon.request_stop("benchmark done");
  daemon_thread.join();
  fs::remove_all(dir);
  return 0;
}
