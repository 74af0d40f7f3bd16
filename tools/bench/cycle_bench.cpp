// cycle-bench: runs the real cycle (CycleRunner over a pty, against the fake responder or any
// responder on --device) and, in the same run, a bare reference loop that only sleeps with
// clock_nanosleep(TIMER_ABSTIME) at the same period and priority. Prints wake-up lateness of
// both, their ratio, send-to-reply latency, cycle work time and CPU time per cycle.
#include <sys/resource.h>

#include <atomic>
#include <charconv>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <thread>

#include "echo_engine.hpp"
#include "fake_responder.hpp"
#include "io/pty.hpp"
#include "rt/cycle_runner.hpp"
#include "rt/histogram.hpp"
#include "rt/rt_thread.hpp"

namespace {

using liftd::mono_now;
using liftd::MonoTime;
namespace rt = liftd::rt;
namespace testing = liftd::rt::testing;

struct Options {
  std::uint64_t cycles = 20000;
  int priority = 80;
  bool lock_memory = true;
  long reply_delay_us = 2000;  // fake responder: well inside DCP 7.2's 11.5625 ms start limit
  std::string device;          // empty: built-in pty + fake responder
  std::string check = "echo";  // echo | checksum | none
  std::string recorder_file;   // flight recorder dump at the end
  int cpu = -1;
};

void usage() {
  std::puts(
      "usage: cycle-bench [--cycles N] [--priority P] [--no-mlock] [--cpu N]\n"
      "                   [--reply-delay-us US] [--device PATH --check echo|checksum|none]\n"
      "                   [--recorder FILE]\n"
      "  --cycles N          cycles to run (default 20000 = 5 minutes at 15 ms)\n"
      "  --priority P        SCHED_FIFO priority of both loops, 0 = normal (default 80)\n"
      "  --device PATH       talk to a responder on PATH (e.g. a drive simulator's pty) instead\n"
      "                      of the built-in fake responder\n"
      "  --check MODE        how replies are judged: echo (fake responder), checksum (DCP XOR\n"
      "                      rule, for a simulator), none\n"
      "  --recorder FILE     write the flight recorder (last 30 s) to FILE at the end");
}

template <class T>
bool parse_number(std::string_view text, T& out) {
  const auto r = std::from_chars(text.data(), text.data() + text.size(), out);
  return r.ec == std::errc() && r.ptr == text.data() + text.size();
}

std::optional<Options> parse(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string_view arg = argv[i];
    const bool has_value = i + 1 < argc;
    const std::string_view value = has_value ? argv[i + 1] : "";
    bool ok = true;
    if (arg == "--cycles" && has_value) {
      ok = parse_number(value, o.cycles) && o.cycles > 0;
      ++i;
    } else if (arg == "--priority" && has_value) {
      ok = parse_number(value, o.priority);
      ++i;
    } else if (arg == "--cpu" && has_value) {
      ok = parse_number(value, o.cpu);
      ++i;
    } else if (arg == "--reply-delay-us" && has_value) {
      ok = parse_number(value, o.reply_delay_us) && o.reply_delay_us >= 0;
      ++i;
    } else if (arg == "--device" && has_value) {
      o.device = value;
      ++i;
    } else if (arg == "--check" && has_value) {
      o.check = value;
      ok = o.check == "echo" || o.check == "checksum" || o.check == "none";
      ++i;
    } else if (arg == "--recorder" && has_value) {
      o.recorder_file = value;
      ++i;
    } else if (arg == "--no-mlock") {
      o.lock_memory = false;
    } else {
      ok = false;
    }
    if (!ok) {
      std::fprintf(stderr, "cycle-bench: bad argument '%s'\n", argv[i]);
      usage();
      return std::nullopt;
    }
  }
  return o;
}

std::int64_t thread_cpu_ns() noexcept {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

std::int64_t process_cpu_ns() noexcept {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

// The frames of the fake responder's echo protocol (valid DCP checksums), with a selectable
// reply check so a DCP drive simulator can stand in for the fake responder.
class BenchEngine : public rt::CycleEngine {
 public:
  explicit BenchEngine(std::string_view check) : check_(check) {}
  std::span<const std::uint8_t> frame_to_send(MonoTime now) noexcept override {
    if (first_cpu_ns_ < 0) first_cpu_ns_ = thread_cpu_ns();
    return echo_.frame_to_send(now);
  }
  std::size_t reply_size() const noexcept override { return testing::kEchoFrameSize; }
  bool on_reply(std::span<const std::uint8_t> reply, MonoTime now) noexcept override {
    const bool echo_ok = echo_.on_reply(reply, now);
    if (check_ == "echo") return echo_ok;
    if (check_ == "checksum") return testing::echo_checksum(reply) == reply[5];
    return true;
  }
  void on_no_reply(MonoTime now) noexcept override { echo_.on_no_reply(now); }
  void on_port_lost(MonoTime now) noexcept override { echo_.on_port_lost(now); }
  void after_cycle(MonoTime /*now*/) noexcept override {
    cpu_ns_.store(thread_cpu_ns() - (first_cpu_ns_ < 0 ? thread_cpu_ns() : first_cpu_ns_),
                  std::memory_order_relaxed);
  }
  /// CPU time the cycle thread used since its first frame.
  std::int64_t cpu_ns() const noexcept { return cpu_ns_.load(std::memory_order_relaxed); }

 private:
  std::string_view check_;
  testing::EchoEngine echo_;
  std::int64_t first_cpu_ns_ = -1;
  std::atomic<std::int64_t> cpu_ns_{0};
};

struct Reference {
  rt::Histogram<5000> lateness{std::chrono::microseconds(1)};  // same bins as the cycle's
  std::atomic<std::uint64_t> done{0};
  std::atomic<std::int64_t> cpu_ns{0};
};

void reference_loop(Reference& ref, std::chrono::nanoseconds period, std::uint64_t cycles) {
  const std::int64_t cpu_start = thread_cpu_ns();
  MonoTime next = mono_now() + period;
  for (std::uint64_t i = 0; i < cycles; ++i) {
    const auto ns = next.count();
    const timespec ts{static_cast<time_t>(ns / 1'000'000'000),
                      static_cast<long>(ns % 1'000'000'000)};
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
    }
    ref.lateness.record(mono_now() - next);
    ref.done.store(i + 1, std::memory_order_relaxed);
    next += period;
  }
  ref.cpu_ns.store(thread_cpu_ns() - cpu_start);
}

void print_row(const char* name, const rt::HistogramData& d) {
  std::printf("  %-24s %9.1f %9.1f %9.1f %9.1f %9.1f\n", name, d.percentile_us(0.5),
              d.percentile_us(0.99), d.percentile_us(0.999), d.max_us(), d.mean_us());
}

double ratio(double a, double b) {
  return b > 0 ? a / b : 0.0;
}

}  // namespace

int main(int argc, char** argv) {
  const std::optional<Options> parsed = parse(argc, argv);
  if (!parsed) return 2;
  const Options& o = *parsed;

  std::unique_ptr<liftd::io::PtyPair> pty;
  std::unique_ptr<testing::FakeResponder> responder;
  rt::CycleConfig config;
  config.thread.priority = o.priority;
  config.thread.lock_memory = o.lock_memory;
  config.thread.cpu = o.cpu;
  if (o.device.empty()) {
    auto created = liftd::io::PtyPair::create();
    if (!created.ok()) {
      std::fprintf(stderr, "cycle-bench: %s\n", created.error().message().c_str());
      return 1;
    }
    pty = std::make_unique<liftd::io::PtyPair>(std::move(created).value());
    // The responder runs just below the cycle, like a drive that always answers in time.
    responder = std::make_unique<testing::FakeResponder>(
        pty->master_fd(), std::chrono::microseconds(o.reply_delay_us),
        o.priority > 1 ? o.priority - 1 : 0);
    if (responder->start() != 0) {
      std::fprintf(stderr, "cycle-bench: cannot start the fake responder\n");
      return 1;
    }
    config.device_path = pty->slave_path();
  } else {
    config.device_path = o.device;
  }

  BenchEngine engine(o.check);
  rt::CycleRunner runner(config, engine);
  Reference ref;
  rt::RtThread ref_thread;
  rt::RtThreadOptions ref_options = config.thread;
  ref_options.lock_memory = false;  // already locked for the whole process by the runner
  const std::int64_t process_cpu_start = process_cpu_ns();
  if (const int err = runner.start(); err != 0) {
    std::fprintf(stderr, "cycle-bench: cannot start the cycle: %s\n", std::strerror(err));
    return 1;
  }
  if (const int err =
          ref_thread.start(ref_options, [&] { reference_loop(ref, config.period, o.cycles); });
      err != 0) {
    std::fprintf(stderr, "cycle-bench: cannot start the reference loop: %s\n", std::strerror(err));
    return 1;
  }

  std::printf(
      "cycle-bench: %llu cycles of %.1f ms on %s, liftd cycle and reference loop in "
      "parallel\n",
      static_cast<unsigned long long>(o.cycles),
      std::chrono::duration<double, std::milli>(config.period).count(), config.device_path.c_str());
  std::fflush(stdout);
  rt::CycleEvent event;
  while (runner.stats().counters.cycles + runner.stats().counters.skipped_cycles < o.cycles ||
         ref.done.load() < o.cycles) {
    while (runner.poll_event(event)) std::printf("event: %s\n", rt::describe(event).c_str());
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
  }
  runner.stop();
  ref_thread.join();
  const std::int64_t process_cpu = process_cpu_ns() - process_cpu_start;
  if (responder) responder->stop();
  while (runner.poll_event(event)) std::printf("event: %s\n", rt::describe(event).c_str());

  const rt::CycleStats s = runner.stats();
  const rt::HistogramData ref_late = ref.lateness.copy();
  const auto& st = ref_thread.status();
  std::printf("scheduling: %s, priority %d; memory locked: %s; reference loop same priority\n",
              runner.thread_status().realtime ? "SCHED_FIFO" : "normal (SCHED_FIFO refused)",
              o.priority, runner.thread_status().memory_locked ? "yes" : "no");
  if (!st.realtime && o.priority > 0) std::printf("reference loop: %s\n", st.describe().c_str());
  std::printf("responder: %s\n", o.device.empty()
                                     ? ("built-in fake over a pty, reply after " +
                                        std::to_string(o.reply_delay_us) + " us")
                                           .c_str()
                                     : ("external on " + o.device + ", check " + o.check).c_str());
  std::printf("\n%-26s %9s %9s %9s %9s %9s\n", "microseconds", "p50", "p99", "p99.9", "max",
              "mean");
  std::printf("wake-up lateness\n");
  print_row("liftd cycle", s.wake_lateness);
  print_row("reference loop", ref_late);
  std::printf("  %-24s %9.2f %9.2f %9.2f %9.2f %9.2f\n", "ratio liftd/reference",
              ratio(s.wake_lateness.percentile_us(0.5), ref_late.percentile_us(0.5)),
              ratio(s.wake_lateness.percentile_us(0.99), ref_late.percentile_us(0.99)),
              ratio(s.wake_lateness.percentile_us(0.999), ref_late.percentile_us(0.999)),
              ratio(s.wake_lateness.max_us(), ref_late.max_us()),
              ratio(s.wake_lateness.mean_us(), ref_late.mean_us()));
  std::printf("send-to-reply latency\n");
  print_row("liftd cycle", s.reply_latency);
  std::printf("cycle work time (wake-up to end of cycle, includes waiting for the reply)\n");
  print_row("liftd cycle", s.work_time);

  const auto per_cycle_us = [](std::int64_t ns, std::uint64_t n) {
    return n > 0 ? static_cast<double>(ns) / static_cast<double>(n) / 1000.0 : 0.0;
  };
  std::printf(
      "\nCPU time per cycle: liftd cycle thread %.1f us, reference loop %.1f us, whole "
      "process %.1f us (all threads, responder included)\n",
      per_cycle_us(engine.cpu_ns(), s.counters.cycles), per_cycle_us(ref.cpu_ns.load(), o.cycles),
      per_cycle_us(process_cpu, o.cycles));
  const auto& c = s.counters;
  std::printf(
      "counters: cycles %llu, sent %llu, good %llu, bad %llu, missing %llu (partial %llu), "
      "overruns %llu, skipped %llu, port losses %llu, stray bytes %llu\n",
      static_cast<unsigned long long>(c.cycles), static_cast<unsigned long long>(c.frames_sent),
      static_cast<unsigned long long>(c.good_replies),
      static_cast<unsigned long long>(c.bad_replies),
      static_cast<unsigned long long>(c.missing_replies),
      static_cast<unsigned long long>(c.partial_replies),
      static_cast<unsigned long long>(c.overruns),
      static_cast<unsigned long long>(c.skipped_cycles),
      static_cast<unsigned long long>(c.port_losses),
      static_cast<unsigned long long>(c.stray_bytes));
  if (!o.recorder_file.empty()) {
    if (const int err = rt::write_text_file(o.recorder_file, runner.recorder().copy()); err != 0) {
      std::fprintf(stderr, "cycle-bench: cannot write %s: %s\n", o.recorder_file.c_str(),
                   std::strerror(err));
      return 1;
    }
    std::printf("flight recorder written to %s\n", o.recorder_file.c_str());
  }
  return 0;
}
