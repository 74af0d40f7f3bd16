// The platform's share of missing replies: a bare link over a pty of its own, no protocol, for
// a benchmark or a live test to run beside the link it judges. One real-time thread writes 6
// bytes every 15 ms and looks (TIOCINQ, every character time, as the cycle does) whether 6 bytes
// came back by 13.625 ms (DCP 7.2); an echo thread one priority below sends back what it reads as
// late as the simulated drive answers. Both directions pass the tty's flip-buffer worker, a
// normal-priority kernel thread, as every byte of a real UART does: a reply this link misses was
// held up by the machine, whatever the reader does (docs/architecture.md, "What the cycle may
// wait for"). A period the thread wakes too late to send in (DCP 7.2 send window) is skipped and
// counted, as the cycle does: then the machine held up even a real-time thread. Header only: the
// benchmarks build without the tests.
#pragma once

#include <poll.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstdint>
#include <stdexcept>

#include "common/mono_time.hpp"
#include "io/pty.hpp"
#include "io/serial_port.hpp"
#include "rt/rt_thread.hpp"

namespace liftd::testing {

/// Periods in a row without a good exchange that witness a stall long enough for a drive to stop
/// the car on its own supervision (DCP 7.3: ten frames; the reference link, at another phase and
/// with fewer pty hops than the drive's link, may see two fewer).
inline constexpr std::uint64_t kDriveStallRun = 8;

class ReferenceLink {
 public:
  ReferenceLink() : pty_(make()) {}
  ReferenceLink(const ReferenceLink&) = delete;
  ReferenceLink& operator=(const ReferenceLink&) = delete;
  ~ReferenceLink() { stop(); }

  /// Starts both threads, the link's at `priority` (SCHED_FIFO where permitted, as RtThread
  /// falls back), both pinned to `cpu` when it is >= 0 (where the cycle runs); 0 or an errno.
  int start(int priority, bool lock_memory, int cpu = -1) {
    auto port = io::SerialPort::open(pty_.slave_path(), raw());
    if (!port.ok()) return EIO;
    port_ = std::move(port).value();
    rt::RtThreadOptions echo;
    echo.priority = std::max(1, priority - 1);
    echo.lock_memory = lock_memory;
    echo.cpu = cpu;
    if (const int err = echo_.start(echo, [this] { echo_loop(); }); err != 0) return err;
    rt::RtThreadOptions main;
    main.priority = priority;
    main.lock_memory = lock_memory;
    main.cpu = cpu;
    return thread_.start(main, [this] { loop(); });
  }
  void stop() {
    stop_ = true;
    thread_.join();
    echo_.join();
  }
  std::uint64_t exchanges() const { return exchanges_.load(std::memory_order_relaxed); }
  std::uint64_t missing() const { return missing_.load(std::memory_order_relaxed); }
  /// Periods skipped because the thread woke past the send window (not counted in missing()).
  std::uint64_t skipped() const { return skipped_.load(std::memory_order_relaxed); }
  /// The most periods in a row without a good exchange, a reply missed or the period skipped
  /// (DCP 7.3 faults a link at ten; a drive without frames for as long stops the car).
  std::uint64_t longest_miss_run() const {
    return longest_miss_run_.load(std::memory_order_relaxed);
  }
  /// The longest such run that overlapped [from, to]: a witness that the machine held up every
  /// pty, or every real-time thread, at that time (of the last kRuns runs of two or more).
  std::uint64_t longest_miss_run_during(MonoTime from, MonoTime to) const {
    const std::uint64_t count = runs_written_.load(std::memory_order_acquire);
    std::uint64_t longest = 0;
    for (std::uint64_t i = count > kRuns ? count - kRuns : 0; i < count; ++i) {
      const Run& r = runs_[i % kRuns];
      const MonoTime start{r.start_ns.load(std::memory_order_relaxed)};
      const MonoTime end{r.end_ns.load(std::memory_order_relaxed)};
      if (start <= to && end >= from) {
        longest = std::max(longest, r.length.load(std::memory_order_relaxed));
      }
    }
    return longest;
  }

 private:
  static constexpr auto kPeriod = std::chrono::milliseconds(15);  // DCP 7.2
  static io::SerialSettings raw() {
    io::SerialSettings s;  // DCP 7.1: 38400 8N1
    s.rs485 = io::Rs485Mode::Off;
    return s;
  }
  static io::PtyPair make() {
    auto created = io::PtyPair::create(raw());
    if (!created.ok()) throw std::runtime_error(created.error().message());
    return std::move(created).value();
  }
  void loop() noexcept {
    constexpr auto kDeadline = std::chrono::microseconds(13625);   // DCP 7.2
    constexpr auto kSendWindow = std::chrono::microseconds(1375);  // DCP 7.2, as the cycle's
    const auto step = io::character_time(raw());
    std::array<std::uint8_t, 6> frame{1, 2, 3, 4, 5, 6};
    std::array<std::uint8_t, 6> reply{};
    MonoTime next = mono_now() + kPeriod;
    std::uint64_t run = 0;
    const auto miss = [&](MonoTime at) {
      ++run;
      if (run > longest_miss_run_.load(std::memory_order_relaxed)) {
        longest_miss_run_.store(run, std::memory_order_relaxed);
      }
      note_run(run, at);
    };
    while (!stop_.load(std::memory_order_relaxed)) {
      // A period whose send window the thread woke too late for is skipped, as the cycle skips
      // it: the machine held up the thread itself, not only the pty.
      rt::sleep_until(next);
      while (mono_now() - next > kSendWindow) {
        skipped_.fetch_add(1, std::memory_order_relaxed);
        miss(next);
        next += kPeriod;
        if (next > mono_now()) rt::sleep_until(next);
      }
      (void)port_.drain_queued();
      const MonoTime sent = mono_now();
      if (port_.write_frame(frame).status == io::IoStatus::Ok) {
        const auto got = port_.read_queued_until(reply, sent + kDeadline, step);
        exchanges_.fetch_add(1, std::memory_order_relaxed);
        if (got.status != io::IoStatus::Ok) {
          missing_.fetch_add(1, std::memory_order_relaxed);
          miss(sent);
        } else {
          run = 0;
        }
      }
      next += kPeriod;
    }
  }
  // Runs of two misses or more, oldest overwritten; the run in progress is updated in place.
  static constexpr std::uint64_t kRuns = 64;
  struct Run {
    std::atomic<std::int64_t> start_ns{0};
    std::atomic<std::int64_t> end_ns{0};
    std::atomic<std::uint64_t> length{0};
  };
  void note_run(std::uint64_t run, MonoTime sent) noexcept {
    if (run < 2) return;
    const std::int64_t at = sent.count();
    std::uint64_t index = runs_written_.load(std::memory_order_relaxed);
    if (run == 2) {
      Run& r = runs_[index % kRuns];
      // The first miss of the run was one period before this one.
      r.start_ns.store(at - MonoTime(kPeriod).count(), std::memory_order_relaxed);
      r.end_ns.store(at, std::memory_order_relaxed);
      r.length.store(run, std::memory_order_relaxed);
      runs_written_.store(++index, std::memory_order_release);
      return;
    }
    Run& r = runs_[(index - 1) % kRuns];
    r.end_ns.store(at, std::memory_order_relaxed);
    r.length.store(run, std::memory_order_relaxed);
  }

  void echo_loop() noexcept {
    std::array<std::uint8_t, 64> buf{};
    const int fd = pty_.master_fd();
    while (!stop_.load(std::memory_order_relaxed)) {
      pollfd pfd{fd, POLLIN, 0};
      if (::poll(&pfd, 1, 20) <= 0) continue;
      const ssize_t n = ::read(fd, buf.data(), buf.size());
      if (n <= 0) continue;
      // As the simulated drive does on a pty (dcp::sim::pty_wire_time): answer when a real RS485
      // line would deliver the answer, after our frame's and the reply's wire time (DCP 7.1/7.2:
      // 6 bytes of 10 bits at 38400 baud, 1.5625 ms each).
      rt::sleep_until(mono_now() + 2 * std::chrono::microseconds(1563));
      (void)!::write(fd, buf.data(), static_cast<std::size_t>(n));
    }
  }
  io::PtyPair pty_;
  io::SerialPort port_;
  rt::RtThread thread_;
  rt::RtThread echo_;
  std::atomic<bool> stop_{false};
  std::atomic<std::uint64_t> exchanges_{0};
  std::atomic<std::uint64_t> missing_{0};
  std::atomic<std::uint64_t> skipped_{0};
  std::atomic<std::uint64_t> longest_miss_run_{0};
  std::array<Run, kRuns> runs_{};
  std::atomic<std::uint64_t> runs_written_{0};
};

}  // namespace liftd::testing
