// cycle-bench: runs the real stack (CycleRunner + DcpController over a pty, the drive simulator
// on the far end, travels going up and down) and, in the same run, a bare reference loop that
// only sleeps with clock_nanosleep(TIMER_ABSTIME) at the same period and priority. Prints
// wake-up lateness of both, their ratio, send-to-reply latency, cycle work time and CPU time
// per cycle. `--engine echo` runs the protocol-free echo engine against the fake responder
// instead (the cycle alone, without the DCP engine).
#include <sys/resource.h>

#include <atomic>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <thread>

#include <unistd.h>

#include "dcp/control/dcp_controller.hpp"
#include "dcp/sim/serial_runner.hpp"
#include "dcp/trace.hpp"
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
  std::string engine = "dcp";  // dcp: DcpController + drive simulator; echo: fake responder
  bool travel = true;          // dcp: keep the car travelling between the end floors
  std::uint64_t cycles = 20000;
  int priority = 80;
  bool lock_memory = true;
  long reply_delay_us = -1;    // -1: the responder's default (simulator 1000, fake 2000)
  std::string device;          // empty: built-in pty + simulator or fake responder
  std::string check = "echo";  // echo | checksum | none
  std::string recorder_file;   // flight recorder dump at the end
  int cpu = -1;
};

void usage() {
  std::puts(
      "usage: cycle-bench [--engine dcp|echo] [--no-travel] [--cycles N] [--priority P]\n"
      "                   [--no-mlock] [--cpu N] [--reply-delay-us US]\n"
      "                   [--device PATH [--check echo|checksum|none]] [--recorder FILE]\n"
      "  --engine dcp        the real stack (default): DcpController against the drive\n"
      "                      simulator (lib/dcp/sim) over a pty, travelling floor 0 <-> top\n"
      "  --engine echo       the cycle alone: echo engine against the fake responder\n"
      "  --no-travel         dcp: keep the car parked (link traffic only)\n"
      "  --cycles N          cycles to run (default 20000 = 5 minutes at 15 ms)\n"
      "  --priority P        SCHED_FIFO priority of both loops, 0 = normal (default 80)\n"
      "  --reply-delay-us US responder's reply delay (simulator 1000, fake 2000 by default)\n"
      "  --device PATH       talk to a responder on PATH (e.g. dcp-drive-sim on a pty) instead\n"
      "                      of the built-in one; dcp: no travels (no encoder to read)\n"
      "  --check MODE        echo engine: how replies are judged: echo (fake responder),\n"
      "                      checksum (DCP XOR rule, for a simulator), none\n"
      "  --recorder FILE     write the flight recorder (last 30 s, DCP decoded) to FILE");
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
    if (arg == "--engine" && has_value) {
      o.engine = value;
      ok = o.engine == "dcp" || o.engine == "echo";
      ++i;
    } else if (arg == "--no-travel") {
      o.travel = false;
    } else if (arg == "--cycles" && has_value) {
      ok = parse_number(value, o.cycles) && o.cycles > 0;
      ++i;
    } else if (arg == "--priority" && has_value) {
      ok = parse_number(value, o.priority);
      ++i;
    } else if (arg == "--cpu" && has_value) {
      ok = parse_number(value, o.cpu);
      ++i;
    } else if (arg == "--reply-delay-us" && has_value) {
      ok = parse_number(value, o.reply_delay_us) && o.reply_delay_us >= 0 &&
           o.reply_delay_us < 11000;  // DCP 7.2: the reply must start by 11.5625 ms
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

// The fake responder's echo protocol (valid DCP checksums), with a selectable reply check so
// a DCP drive simulator on --device can stand in for the fake responder.
class CheckedEcho : public rt::CycleEngine {
 public:
  explicit CheckedEcho(std::string_view check) : check_(check) {}
  std::span<const std::uint8_t> frame_to_send(MonoTime now) noexcept override {
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

 private:
  std::string_view check_;
  testing::EchoEngine echo_;
};

// Forwards to the engine under test and measures the cycle thread's CPU time, and the time spent
// inside the engine's own calls (the protocol work; the rest of the cycle is serial I/O that
// every engine shares).
class TimedEngine final : public rt::CycleEngine {
 public:
  explicit TimedEngine(rt::CycleEngine& inner) : inner_(inner) {}
  std::span<const std::uint8_t> frame_to_send(MonoTime now) noexcept override {
    if (first_cpu_ns_ < 0) first_cpu_ns_ = thread_cpu_ns();
    const MonoTime t0 = mono_now();
    const auto frame = inner_.frame_to_send(now);
    inside_ += mono_now() - t0;
    return frame;
  }
  std::size_t reply_size() const noexcept override { return inner_.reply_size(); }
  bool on_reply(std::span<const std::uint8_t> reply, MonoTime now) noexcept override {
    const MonoTime t0 = mono_now();
    const bool good = inner_.on_reply(reply, now);
    inside_ += mono_now() - t0;
    return good;
  }
  void on_no_reply(MonoTime now) noexcept override {
    const MonoTime t0 = mono_now();
    inner_.on_no_reply(now);
    inside_ += mono_now() - t0;
  }
  void on_port_lost(MonoTime now) noexcept override { inner_.on_port_lost(now); }
  void on_port_ready(MonoTime now) noexcept override { inner_.on_port_ready(now); }
  void after_cycle(MonoTime now) noexcept override {
    const MonoTime t0 = mono_now();
    inner_.after_cycle(now);
    inside_ += mono_now() - t0;
    engine_ns_.store(inside_.count(), std::memory_order_relaxed);
    if (first_cpu_ns_ >= 0) {
      cpu_ns_.store(thread_cpu_ns() - first_cpu_ns_, std::memory_order_relaxed);
    }
  }
  /// CPU time the cycle thread used since its first frame.
  std::int64_t cpu_ns() const noexcept { return cpu_ns_.load(std::memory_order_relaxed); }
  /// Time spent inside the engine's calls (frame, reply, no reply, after the cycle).
  std::int64_t engine_ns() const noexcept { return engine_ns_.load(std::memory_order_relaxed); }

 private:
  rt::CycleEngine& inner_;
  std::int64_t first_cpu_ns_ = -1;
  std::chrono::nanoseconds inside_{0};
  std::atomic<std::int64_t> cpu_ns_{0};
  std::atomic<std::int64_t> engine_ns_{0};
};

// The simulated encoder, read lock-free by the cycle (DCP4 travels need the position).
class SimEncoder final : public liftd::control::PositionSource {
 public:
  explicit SimEncoder(const liftd::dcp::sim::SerialDriveRunner* runner) : runner_(runner) {}
  std::optional<std::int64_t> position_mm(MonoTime) const noexcept override {
    if (runner_ == nullptr) return std::nullopt;
    return std::llround(runner_->position_mm());
  }

 private:
  const liftd::dcp::sim::SerialDriveRunner* runner_;
};

// The installation of the benchmark: six floors 3 m apart, DCP4, extended I9 reply.
liftd::control::ControllerConfig bench_controller_config() {
  liftd::control::ControllerConfig c;
  c.floors_mm = {0, 3000, 6000, 9000, 12000, 15000};
  c.link.extended_position = true;
  return c;
}

// The io thread's side of the DCP stack during the run: inputs, travels, events.
struct DcpDriver {
  liftd::control::DcpController& controller;
  bool travel = true;
  MonoTime last_inputs{};
  std::uint32_t tag = 0;
  std::size_t next_floor = 5;
  bool travel_pending = false;
  std::uint64_t travels_started = 0;
  std::uint64_t travels_finished = 0;
  std::uint64_t travels_aborted = 0;
  std::uint64_t refused = 0;
  std::uint64_t link_faults = 0;

  void pump() {
    namespace control = liftd::control;
    const MonoTime now = mono_now();
    if (now - last_inputs >= std::chrono::milliseconds(100)) {  // config inputs.timeout_ms 500
      liftd::lift::Inputs in;
      in.valid = in.safety_chain_closed = in.doors_closed = in.doors_locked = true;
      controller.post(control::Command{0, control::InputsCommand{in}});
      last_inputs = now;
    }
    control::ControllerEvent e;
    while (controller.poll_event(e)) {
      if (e.kind == control::ControllerEvent::Kind::Travel) {
        if (e.travel.type == liftd::travel::Event::Type::Finished) ++travels_finished;
        if (e.travel.type == liftd::travel::Event::Type::Aborted) ++travels_aborted;
      } else if (e.kind == control::ControllerEvent::Kind::FaultRaised &&
                 e.fault == control::FaultCode::LinkFault) {
        ++link_faults;
      }
    }
    control::CommandReply r;
    while (controller.poll_reply(r)) {
      if (r.tag != tag) continue;
      travel_pending = false;
      if (r.code == control::ReplyCode::Ok) {
        ++travels_started;
        next_floor = next_floor == 0 ? 5 : 0;
      } else {
        ++refused;
      }
    }
    if (!travel || travel_pending) return;
    const control::ControllerSnapshot s = controller.snapshot();
    const bool idle = s.link == liftd::dcp::LinkState::Up &&
                      s.travel_kind == liftd::travel::TravelKind::None && s.status_byte &&
                      (*s.status_byte & liftd::dcp::status_bit::kTravelActive) == 0 &&
                      (*s.status_byte & liftd::dcp::status_bit::kReady) != 0;
    if (!idle) return;
    controller.post(control::Command{
        ++tag, control::TravelCommand{next_floor, liftd::dcp::Speed::V4, std::nullopt, false}});
    travel_pending = true;
  }
};

struct Reference {
  rt::Histogram<20000> lateness{std::chrono::microseconds(1)};  // same bins as the cycle's
  std::atomic<std::uint64_t> done{0};
  std::atomic<std::int64_t> cpu_ns{0};
  std::atomic<std::uint64_t> beyond_window{0};  // wake-ups later than the cycle's send window
  std::atomic<long long> wake_ups{0};           // voluntary context switches over its run
};

long long thread_voluntary_switches() noexcept {
  rusage u{};
  return getrusage(RUSAGE_THREAD, &u) == 0 ? u.ru_nvcsw : 0;
}

void reference_loop(Reference& ref, std::chrono::nanoseconds period,
                    std::chrono::nanoseconds send_window, std::uint64_t cycles) {
  const std::int64_t cpu_start = thread_cpu_ns();
  const long long switches_start = thread_voluntary_switches();
  MonoTime next = mono_now() + period;
  for (std::uint64_t i = 0; i < cycles; ++i) {
    const auto ns = next.count();
    const timespec ts{static_cast<time_t>(ns / 1'000'000'000),
                      static_cast<long>(ns % 1'000'000'000)};
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
    }
    const auto late = mono_now() - next;
    ref.lateness.record(late);
    if (late > send_window) ref.beyond_window.fetch_add(1, std::memory_order_relaxed);
    ref.done.store(i + 1, std::memory_order_relaxed);
    next += period;
  }
  ref.cpu_ns.store(thread_cpu_ns() - cpu_start);
  ref.wake_ups.store(thread_voluntary_switches() - switches_start);
}

// Percentiles beyond the bins' range print as "> 20000": the bins cannot tell more.
// Voluntary context switches of this process's thread named `name` (/proc/self/task/*/status):
// each is a sleep the thread woke from. -1 if there is no such thread.
long long voluntary_switches(const std::string& name) {
  std::error_code ec;
  for (const auto& task : std::filesystem::directory_iterator("/proc/self/task", ec)) {
    std::ifstream comm(task.path() / "comm");
    std::string comm_name;
    if (!std::getline(comm, comm_name) || comm_name != name) continue;
    std::ifstream status(task.path() / "status");
    for (std::string line; std::getline(status, line);) {
      if (line.rfind("voluntary_ctxt_switches:", 0) == 0) {
        return std::atoll(line.c_str() + std::strlen("voluntary_ctxt_switches:"));
      }
    }
  }
  return -1;
}

void print_row(const char* name, const rt::HistogramData& d) {
  std::printf("  %-24s %9s %9s %9s %9.1f %9.1f\n", name, d.percentile_text(0.5).c_str(),
              d.percentile_text(0.99).c_str(), d.percentile_text(0.999).c_str(), d.max_us(),
              d.mean_us());
}

double ratio(double a, double b) {
  return b > 0 ? a / b : 0.0;
}

}  // namespace

// Over 120 lines: one benchmark run read top to bottom: set up, run both loops, report.
int main(int argc, char** argv) {
  const std::optional<Options> parsed = parse(argc, argv);
  if (!parsed) return 2;
  const Options& o = *parsed;
  const bool dcp = o.engine == "dcp";

  std::unique_ptr<liftd::io::PtyPair> pty;
  std::unique_ptr<testing::FakeResponder> responder;
  std::unique_ptr<liftd::dcp::sim::SerialDriveRunner> drive;
  rt::CycleConfig config;
  config.thread.priority = o.priority;
  config.thread.lock_memory = o.lock_memory;
  config.thread.cpu = o.cpu;
  std::string responder_text;
  if (o.device.empty()) {
    liftd::io::SerialSettings raw;
    raw.rs485 = liftd::io::Rs485Mode::Off;  // a pty has no RS485 mode
    auto created = liftd::io::PtyPair::create(raw);
    if (!created.ok()) {
      std::fprintf(stderr, "cycle-bench: %s\n", created.error().message().c_str());
      return 1;
    }
    pty = std::make_unique<liftd::io::PtyPair>(std::move(created).value());
    if (dcp) {
      liftd::dcp::sim::DriveConfig drive_config;  // DCP4, the simulator's default installation
      if (o.reply_delay_us >= 0)
        drive_config.reply_delay = std::chrono::microseconds(o.reply_delay_us);
      liftd::dcp::sim::RunnerOptions runner_options;
      runner_options.fd = ::dup(pty->master_fd());
      runner_options.quiet = true;
      runner_options.reconnect = false;
      drive = std::make_unique<liftd::dcp::sim::SerialDriveRunner>(drive_config, runner_options);
      if (!drive->start()) {
        std::fprintf(stderr, "cycle-bench: cannot start the drive simulator: %s\n",
                     drive->last_error().c_str());
        return 1;
      }
      responder_text = "drive simulator (lib/dcp/sim, normal priority) over a pty, reply after " +
                       std::to_string(drive_config.reply_delay.count()) + " us";
    } else {
      const long delay_us = o.reply_delay_us >= 0 ? o.reply_delay_us : 2000;
      // The responder runs just below the cycle, like a drive that always answers in time.
      responder = std::make_unique<testing::FakeResponder>(pty->master_fd(),
                                                           std::chrono::microseconds(delay_us),
                                                           o.priority > 1 ? o.priority - 1 : 0);
      if (responder->start() != 0) {
        std::fprintf(stderr, "cycle-bench: cannot start the fake responder\n");
        return 1;
      }
      responder_text = "built-in fake over a pty, reply after " + std::to_string(delay_us) + " us";
    }
    config.device_path = pty->slave_path();
  } else {
    config.device_path = o.device;
    responder_text = "external on " + o.device + (dcp ? "" : ", check " + o.check);
  }

  SimEncoder encoder(drive.get());
  std::unique_ptr<liftd::control::DcpController> controller;
  std::unique_ptr<CheckedEcho> echo;
  std::optional<DcpDriver> driver;
  if (dcp) {
    controller =
        std::make_unique<liftd::control::DcpController>(bench_controller_config(), encoder);
    driver.emplace(DcpDriver{*controller});
    driver->travel = o.travel && drive != nullptr;
  } else {
    echo = std::make_unique<CheckedEcho>(o.check);
  }
  TimedEngine engine(dcp ? static_cast<rt::CycleEngine&>(*controller)
                         : static_cast<rt::CycleEngine&>(*echo));
  rt::CycleRunner runner(config, engine);
  Reference ref;
  rt::RtThread ref_thread;
  rt::RtThreadOptions ref_options = config.thread;
  ref_options.lock_memory = false;  // already locked for the whole process by the runner
  ref_options.name = "bench-ref";   // as ps -L shows it
  const std::int64_t process_cpu_start = process_cpu_ns();
  if (const int err = runner.start(); err != 0) {
    std::fprintf(stderr, "cycle-bench: cannot start the cycle: %s\n", std::strerror(err));
    return 1;
  }
  if (const int err = ref_thread.start(
          ref_options, [&] { reference_loop(ref, config.period, config.send_window, o.cycles); });
      err != 0) {
    std::fprintf(stderr, "cycle-bench: cannot start the reference loop: %s\n", std::strerror(err));
    return 1;
  }

  // The cycle thread is named before start() returns (RtThread).
  const long long cycle_switches_start = voluntary_switches("liftd-cycle");
  const std::uint64_t cycles_start = runner.stats().counters.cycles;
  std::printf(
      "cycle-bench: %llu cycles of %.1f ms on %s, %s, liftd cycle and reference loop in "
      "parallel\n",
      static_cast<unsigned long long>(o.cycles),
      std::chrono::duration<double, std::milli>(config.period).count(), config.device_path.c_str(),
      dcp ? (driver->travel ? "DcpController, travelling" : "DcpController, parked")
          : "echo engine");
  std::fflush(stdout);
  rt::CycleEvent event;
  while (runner.stats().counters.cycles + runner.stats().counters.skipped_cycles < o.cycles ||
         ref.done.load() < o.cycles) {
    while (runner.poll_event(event)) std::printf("event: %s\n", rt::describe(event).c_str());
    if (driver) driver->pump();
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  const long long cycle_switches = voluntary_switches("liftd-cycle") - cycle_switches_start;
  const std::uint64_t cycles_counted = runner.stats().counters.cycles - cycles_start;
  runner.stop();
  ref_thread.join();
  const std::int64_t process_cpu = process_cpu_ns() - process_cpu_start;
  if (driver) driver->pump();
  if (responder) responder->stop();
  if (drive) drive->stop();
  while (runner.poll_event(event)) std::printf("event: %s\n", rt::describe(event).c_str());

  const rt::CycleStats s = runner.stats();
  const rt::HistogramData ref_late = ref.lateness.copy();
  const auto& st = ref_thread.status();
  std::printf("scheduling: %s, priority %d; memory locked: %s; reference loop same priority\n",
              runner.thread_status().realtime ? "SCHED_FIFO" : "normal (SCHED_FIFO refused)",
              o.priority, runner.thread_status().memory_locked ? "yes" : "no");
  if (!st.realtime && o.priority > 0) std::printf("reference loop: %s\n", st.describe().c_str());
  std::printf("responder: %s\n", responder_text.c_str());
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
  std::printf("engine calls per cycle: %.2f us (the protocol work inside the cycle thread)\n",
              per_cycle_us(engine.engine_ns(), s.counters.cycles));
  std::printf(
      "wake-ups beyond the send window (%lld us): liftd cycle %llu (all skipped: %llu), reference "
      "loop %llu\n",
      static_cast<long long>(config.send_window.count() / 1000),
      static_cast<unsigned long long>(s.counters.overruns),
      static_cast<unsigned long long>(s.counters.skipped_cycles),
      static_cast<unsigned long long>(ref.beyond_window.load()));
  // Issue #43: each wake-up costs a small board's CPU. The reference loop wakes once a period.
  const auto per_cycle = [](long long n, std::uint64_t cycles) {
    return cycles > 0 ? static_cast<double>(n) / static_cast<double>(cycles) : 0.0;
  };
  std::printf(
      "wake-ups per cycle (voluntary context switches): liftd cycle %.2f (looks for the reply "
      "%.2f), reference loop %.2f\n",
      per_cycle(cycle_switches, cycles_counted),
      per_cycle(static_cast<long long>(s.counters.reply_looks), s.counters.cycles),
      per_cycle(ref.wake_ups.load(), o.cycles));
  const auto& c = s.counters;
  std::printf(
      "counters: cycles %llu, sent %llu (late %llu), good %llu, bad %llu, missing %llu (partial "
      "%llu, seen after the deadline %llu), overruns %llu, skipped %llu, port losses %llu, stray "
      "bytes %llu\n",
      static_cast<unsigned long long>(c.cycles), static_cast<unsigned long long>(c.frames_sent),
      static_cast<unsigned long long>(c.late_sends),
      static_cast<unsigned long long>(c.good_replies),
      static_cast<unsigned long long>(c.bad_replies),
      static_cast<unsigned long long>(c.missing_replies),
      static_cast<unsigned long long>(c.partial_replies),
      static_cast<unsigned long long>(c.late_replies), static_cast<unsigned long long>(c.overruns),
      static_cast<unsigned long long>(c.skipped_cycles),
      static_cast<unsigned long long>(c.port_losses),
      static_cast<unsigned long long>(c.stray_bytes));
  if (driver) {
    const liftd::control::ControllerSnapshot snap = controller->snapshot();
    const liftd::dcp::LinkCounters& lc = snap.link_counters;
    std::printf(
        "dcp: link %s; bad checksum %llu, missing %llu, S7 %llu, B7 sent %llu, longest error run "
        "%u, link faults %llu; travels started %llu, finished %llu, aborted %llu, refused %llu\n",
        std::string(liftd::dcp::to_string(snap.link)).c_str(),
        static_cast<unsigned long long>(lc.bad_checksum),
        static_cast<unsigned long long>(lc.missing_replies),
        static_cast<unsigned long long>(lc.s7_seen), static_cast<unsigned long long>(lc.b7_sent),
        lc.longest_error_run, static_cast<unsigned long long>(lc.link_faults),
        static_cast<unsigned long long>(driver->travels_started),
        static_cast<unsigned long long>(driver->travels_finished),
        static_cast<unsigned long long>(driver->travels_aborted),
        static_cast<unsigned long long>(driver->refused));
  }
  if (drive) {
    const liftd::dcp::sim::RunnerStatus ds = drive->status();
    std::printf("drive simulator: %s\n", liftd::dcp::sim::format_status(ds).c_str());
  }
  if (!o.recorder_file.empty()) {
    const liftd::rt::FrameDecoder decoder = dcp ? liftd::dcp::trace_decoder() : rt::FrameDecoder{};
    if (const int err = rt::write_text_file(o.recorder_file, runner.recorder().copy(), decoder);
        err != 0) {
      std::fprintf(stderr, "cycle-bench: cannot write %s: %s\n", o.recorder_file.c_str(),
                   std::strerror(err));
      return 1;
    }
    std::printf("flight recorder written to %s\n", o.recorder_file.c_str());
  }
  return 0;
}
