// api-load-bench: what API load does to the real-time cycle. Runs the real daemon wiring in
// process (Daemon + LiftApp with the simulated lift on a pty, the cycle thread at its configured
// priority, the API server), keeps the car travelling between the lowest and the top floor, and
// measures the cycle's wake-up lateness in a quiet window and then in windows where 1, 8 and 32
// clients hammer `status` as fast as they can. The same run, the same machine: the ratios are
// the figures to read. Also prints requests per second and request latency per load.
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "common/mono_time.hpp"
#include "daemon/daemon.hpp"
#include "daemon/lift_app.hpp"
#include "log/log.hpp"
#include "rt/histogram.hpp"
#include "service/notify.hpp"
#include "support/api_client.hpp"

namespace {

using namespace std::chrono_literals;
using liftd::rt::HistogramData;
using nlohmann::json;

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
  for (const auto& l : latencies) all.insert(all.end(), l.begin(), l.end());
  std::sort(all.begin(), all.end());
  LoadResult r;
  if (all.empty()) return r;
  r.requests_per_s = static_cast<double>(all.size()) / static_cast<double>(duration.count());
  r.latency_p50_us = all[all.size() / 2];
  r.latency_p99_us = all[std::min(all.size() - 1, all.size() * 99 / 100)];
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

void print_row(const char* name, const HistogramData& d, const HistogramData& quiet,
               const LoadResult* load) {
  std::printf("  %-12s %8s %9s %9s %9.1f %9.1f  %6.2f %6.2f", name, d.percentile_text(0.5).c_str(),
              d.percentile_text(0.99).c_str(), d.percentile_text(0.999).c_str(), d.max_us(),
              static_cast<double>(d.count), d.percentile_us(0.99) / quiet.percentile_us(0.99),
              d.max_us() / quiet.max_us());
  if (load != nullptr) {
    std::printf("  %9.0f %9.1f %9.1f", load->requests_per_s, load->latency_p50_us,
                load->latency_p99_us);
  }
  std::printf("\n");
}

}  // namespace

int main(int argc, char** argv) {
  std::chrono::seconds phase{20};
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--seconds") == 0 && i + 1 < argc) {
      phase = std::chrono::seconds(std::max(1, std::atoi(argv[++i])));
    } else {
      std::fprintf(stderr,
                   "usage: api-load-bench [--seconds N]\n"
                   "  N seconds per window (default 20): quiet, then 1, 8 and 32 clients\n");
      return 2;
    }
  }
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("liftd-api-load-" + std::to_string(getpid()));
  fs::create_directories(dir);
  ::setenv("XDG_RUNTIME_DIR", dir.c_str(), 1);
  liftd::log::init({liftd::log::Level::warn, liftd::log::Backend::text, "api-load-bench"});

  liftd::config::Config cfg = liftd::daemon::simulation_defaults();
  cfg.rt.lock_memory = true;  // as the service runs
  liftd::daemon::Daemon daemon(cfg, liftd::service::Notifier::from_environment(), std::nullopt);
  liftd::daemon::LiftApp app(daemon, cfg, true);
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
  std::atomic<bool> stop_dispatch{false};
  std::atomic<int> travels{0};
  std::thread dispatch([&] { dispatcher(cfg.api.socket, stop_dispatch, travels); });

  const auto rt_status = app.cycle().thread_status();
  std::printf(
      "api-load-bench: cycle thread %s, memory %s; %lld s per window; the car travels "
      "0 <-> 5 throughout\n",
      rt_status.realtime ? "SCHED_FIFO" : "SCHED_OTHER (not real-time: run as root)",
      rt_status.memory_locked ? "locked" : "not locked", static_cast<long long>(phase.count()));

  HistogramData before = app.cycle().stats().wake_lateness;
  std::this_thread::sleep_for(phase);
  HistogramData after = app.cycle().stats().wake_lateness;
  const HistogramData quiet = window(before, after);

  struct Row {
    int clients;
    HistogramData lateness;
    LoadResult load;
  };
  std::vector<Row> rows;
  for (int clients : {1, 8, 32}) {
    before = app.cycle().stats().wake_lateness;
    const LoadResult load = hammer(cfg.api.socket, clients, phase);
    after = app.cycle().stats().wake_lateness;
    rows.push_back({clients, window(before, after), load});
  }
  stop_dispatch = true;
  dispatch.join();
  const auto counters = app.cycle().stats().counters;

  std::printf("\ncycle wake-up lateness per window (us), and the API load in it\n");
  std::printf("  %-12s %8s %9s %9s %9s %9s  %6s %6s  %9s %9s %9s\n", "window", "p50", "p99",
              "p99.9", "max", "cycles", "p99/q", "max/q", "req/s", "req p50", "req p99");
  print_row("quiet", quiet, quiet, nullptr);
  for (const Row& r : rows) {
    char name[32];
    std::snprintf(name, sizeof name, "%d client%s", r.clients, r.clients == 1 ? "" : "s");
    print_row(name, r.lateness, quiet, &r.load);
  }
  for (const Row& r : rows) {
    if (r.clients == 8) {
      // The figure to read: how much 8 busy clients make the cycle later (1.00 = not at all).
      std::printf("\nlateness ratio 8 clients / quiet: p99 %.2f, mean %.2f\n",
                  r.lateness.percentile_us(0.99) / quiet.percentile_us(0.99),
                  r.lateness.mean_us() / quiet.mean_us());
    }
  }
  std::printf(
      "travels started %d; cycles %llu, late sends %llu, overruns %llu, skipped %llu, missing "
      "replies %llu\n",
      travels.load(), static_cast<unsigned long long>(counters.cycles),
      static_cast<unsigned long long>(counters.late_sends),
      static_cast<unsigned long long>(counters.overruns),
      static_cast<unsigned long long>(counters.skipped_cycles),
      static_cast<unsigned long long>(counters.missing_replies));
  daemon.request_stop("benchmark done");
  daemon_thread.join();
  fs::remove_all(dir);
  return 0;
}
