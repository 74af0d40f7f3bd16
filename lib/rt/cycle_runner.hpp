// The real-time cycle of one serial link: every period send the engine's frame, wait for the
// reply until a deadline, feed the engine. Protocol independent; the engine decides the bytes.
#pragma once

#include <array>
#include <atomic>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>

#include "common/mono_time.hpp"
#include "common/spsc_queue.hpp"
#include "io/line_echo.hpp"
#include "io/serial_port.hpp"
#include "rt/cycle_event.hpp"
#include "rt/flight_recorder.hpp"
#include "rt/histogram.hpp"
#include "rt/port_keeper.hpp"
#include "rt/reply_watch.hpp"
#include "rt/rt_thread.hpp"

namespace liftd::rt {

/// The protocol side of a cycle (a DCP or USS master). Called only from the cycle thread;
/// every method must be allocation free, lock free and non-blocking.
class CycleEngine {
 public:
  virtual ~CycleEngine() = default;
  /// The frame to send now (6 bytes for DCP). An empty span sends nothing this cycle.
  /// The bytes must stay valid until the next call.
  virtual std::span<const std::uint8_t> frame_to_send(MonoTime now) noexcept = 0;
  /// Bytes of a complete reply (DCP 2: 6).
  virtual std::size_t reply_size() const noexcept = 0;
  /// A complete reply arrived in time. Return false if it is unusable (e.g. bad checksum):
  /// the cycle counts it as a bad reply.
  virtual bool on_reply(std::span<const std::uint8_t> reply, MonoTime now) noexcept = 0;
  /// No complete reply by the deadline (late, short or missing).
  virtual void on_no_reply(MonoTime now) noexcept = 0;
  /// The exchange is unusable although bytes came in time: the line read back a frame that
  /// differs from the one sent (a collision on an echoing line, drive.echo). The drive cannot
  /// have received our frame intact. Default: as a missing reply.
  virtual void on_bad_reply(MonoTime now) noexcept { on_no_reply(now); }
  /// The device went away (or is not there); nothing is sent until it is back.
  virtual void on_port_lost(MonoTime now) noexcept = 0;
  /// The device is (back) open; the next cycle sends again. Start re-initialising here.
  virtual void on_port_ready(MonoTime /*now*/) noexcept {}
  /// End of every cycle, also without a port: publish snapshots, drain requests.
  virtual void after_cycle(MonoTime /*now*/) noexcept {}
};

/// Parameters of one link's cycle.
struct CycleConfig {
  std::string device_path;    ///< serial device, e.g. /dev/ttyS1 or a pty slave
  io::SerialSettings serial;  ///< line settings (DCP 7.1: 38400 8N1)
  /// DCP 7.2: one transfer cycle every 15 ms.
  std::chrono::nanoseconds period = std::chrono::milliseconds(15);
  /// DCP 7.2: the drive's reply must be complete (its driver off) by 13.625 ms after our start.
  std::chrono::nanoseconds reply_deadline = std::chrono::microseconds(13625);
  /// DCP 7.2: the drive may start its reply 2.0624 ms after our frame began (our driver off,
  /// "Frühester Sendebeginn der Regelung") and starts it by 11.5625 ms ("Spätester
  /// Sendebeginn"). With the reply's length on the line they bound when the cycle first looks
  /// for a reply (rt/reply_watch.hpp).
  std::chrono::nanoseconds reply_earliest_start = std::chrono::nanoseconds(2'062'400);
  std::chrono::nanoseconds reply_latest_start = std::chrono::nanoseconds(11'562'500);
  /// Latest wake-up lateness at which we still send (a "late send" past kOnTimeBudget). DCP
  /// 7.2: the drive's reply ends by 13.625 ms and the next master frame starts at 15 ms, so a
  /// frame up to 15 - 13.625 = 1.375 ms late still cannot collide with the reply to it (its
  /// reply deadline moves with it and still ends by the next planned start). Never above
  /// max_send_window(); the constructor refuses more.
  std::chrono::nanoseconds send_window = std::chrono::microseconds(1375);
  /// How often the cycle looks (TIOCINQ) whether the reply has reached the line discipline
  /// while it waits for it; 0 = one character time of `serial` (DCP 7.1: 10 bits at 38400 baud
  /// = 260 us). The cycle never blocks in read(2) or poll(2) on the tty (docs/architecture.md).
  std::chrono::nanoseconds input_check_interval{0};
  RtThreadOptions thread;  ///< SCHED_FIFO priority, memory locking, affinity
  std::chrono::nanoseconds reopen_backoff_min =
      std::chrono::milliseconds(100);  ///< first retry after a loss
  std::chrono::nanoseconds reopen_backoff_max =
      std::chrono::seconds(2);  ///< retry interval cap (doubling)
  /// Whether the line gives our own frame back ahead of the reply (io/line_echo.hpp). With an
  /// echo the reply follows the frame's copy: both must be complete by the reply deadline,
  /// which counts from the start of our frame, so the copy (read while we send) takes nothing
  /// from the drive's time (DCP 7.2).
  io::EchoMode echo = io::EchoMode::Off;
  /// How much traffic the flight recorder keeps (default 30 s = 2000 cycles of 15 ms).
  std::chrono::nanoseconds recorder_span = std::chrono::seconds(30);
  /// Bytes the flight recorder keeps per frame: the link's longest frame (kDcpRecordBytes for
  /// DCP, kUssRecordBytes for USS).
  std::size_t recorder_bytes = kDcpRecordBytes;
};

/// DCP 7.2: our driver must be off by 2.0624 ms and 6 bytes at 38400 baud take 1.5625 ms, so a
/// frame that starts within 0.5 ms of its planned time is on time; later ones count as late.
inline constexpr std::chrono::nanoseconds kOnTimeBudget = std::chrono::microseconds(500);

/// The largest send window the spec's timing allows: period minus reply deadline (DCP 7.2:
/// 15 - 13.625 = 1.375 ms), so a late frame's reply still ends before the next planned frame.
constexpr std::chrono::nanoseconds max_send_window(std::chrono::nanoseconds period,
                                                   std::chrono::nanoseconds reply_deadline) {
  return period > reply_deadline ? period - reply_deadline : std::chrono::nanoseconds{0};
}

/// What the cycle does with one wake-up, decided from its lateness alone.
struct WakeDecision {
  bool send = false;          ///< run the cycle now
  bool late = false;          ///< sent, but later than kOnTimeBudget
  std::uint64_t skipped = 0;  ///< cycles skipped (0 when sending)
};

/// The rule: send when `lateness` is within `window` (late past kOnTimeBudget), otherwise skip
/// this cycle and every further period that has already begun. Absolute schedule: the caller
/// plans the next wake-up `skipped` (or 1) periods after the missed one.
constexpr WakeDecision decide_wake(std::chrono::nanoseconds lateness,
                                   std::chrono::nanoseconds window,
                                   std::chrono::nanoseconds period) {
  if (lateness <= window) return WakeDecision{true, lateness > kOnTimeBudget, 0};
  const auto p = period.count() > 0 ? period.count() : 1;
  return WakeDecision{false, false, static_cast<std::uint64_t>(lateness.count() / p) + 1};
}

/// Counters of the cycle, copied out by stats().
struct CycleCounters {
  std::uint64_t cycles = 0;           ///< cycles completed (sent or not)
  std::uint64_t frames_sent = 0;      ///< frames written completely
  std::uint64_t good_replies = 0;     ///< complete, in time, accepted by the engine
  std::uint64_t bad_replies = 0;      ///< complete, in time, rejected by the engine
  std::uint64_t missing_replies = 0;  ///< not complete by the deadline (incl. partial)
  std::uint64_t partial_replies = 0;  ///< of the missing ones: some bytes came
  std::uint64_t late_sends = 0;       ///< frames sent later than kOnTimeBudget, within the window
  std::uint64_t overruns = 0;         ///< wake-ups too late to send (beyond the send window)
  std::uint64_t skipped_cycles = 0;   ///< cycles not run because of overruns
  std::uint64_t late_replies = 0;   ///< of the missing ones: complete, but seen after the deadline
  std::uint64_t port_losses = 0;    ///< device losses
  std::uint64_t port_opens = 0;     ///< successful opens (first one included)
  std::uint64_t send_failures = 0;  ///< frames the port refused
  std::uint64_t stray_bytes = 0;    ///< bytes flushed before sending
  /// Exchanges whose frame came back changed on an echoing line (a bus collision); each is
  /// also one of the bad replies.
  std::uint64_t echo_collisions = 0;
  /// Looks at the line for replies (SerialPort::looks()): each a wake-up of the cycle thread
  /// besides the one a period.
  std::uint64_t reply_looks = 0;
};

/// A copy of the cycle's statistics, taken on any thread.
struct CycleStats {
  CycleCounters counters;       ///< counters
  HistogramData wake_lateness;  ///< wake-up minus planned time, 1 us bins up to 20 ms
  HistogramData reply_latency;  ///< send start to complete reply, 10 us bins up to 15 ms
  HistogramData work_time;      ///< wake-up to end of cycle work, 1 us bins up to 20 ms
};

/// Runs the cycle on its own real-time thread and a helper thread that (re)opens the device.
class CycleRunner {
 public:
  /// Everything is allocated here; `engine` must outlive the runner. Throws
  /// std::invalid_argument if the send window is negative or above max_send_window().
  CycleRunner(CycleConfig config, CycleEngine& engine);
  CycleRunner(const CycleRunner&) = delete;
  CycleRunner& operator=(const CycleRunner&) = delete;
  /// Stops and joins both threads.
  ~CycleRunner();

  /// Starts the threads. Returns 0 or the errno of a failed thread start. A missing device is
  /// not an error: it is retried with backoff.
  int start();
  /// Stops the cycle and closes the port (idempotent).
  void stop() noexcept;

  /// Non-real-time side: pops the next event. Call from one thread only.
  bool poll_event(CycleEvent& out) noexcept;

  /// What the cycle thread got (SCHED_FIFO, memory lock, affinity); valid after start().
  const RtThreadStatus& thread_status() const noexcept { return port_keeper_.thread_status(); }
  /// Any thread: counters and histograms.
  CycleStats stats() const;
  /// Any thread: the flight recorder (copy() it, then write_text()).
  const FlightRecorder& recorder() const noexcept { return recorder_; }
  /// Any thread: goes up every period while the cycle thread is alive (systemd watchdog).
  std::uint64_t progress() const noexcept { return progress_.load(std::memory_order_relaxed); }
  /// Wakes another thread after every cycle: the cycle thread adds 1 to this eventfd (created
  /// non-blocking; one write(2), no allocation, never blocks). -1 (default) = none. Set before
  /// start(); the caller owns the descriptor and keeps it open until stop().
  void set_notify_fd(int fd) noexcept { notify_fd_ = fd; }
  /// Any thread: true while a port is open on the cycle thread.
  bool port_ready() const noexcept { return port_keeper_.port_ready(); }
  /// The configuration in use.
  const CycleConfig& config() const noexcept { return config_; }
  /// Any thread: what the cycle knows about the line's echo (config echo; Auto: found out at
  /// each port open, reported once as a LineEcho event).
  io::EchoState echo_state() const noexcept { return echo_state_.load(std::memory_order_relaxed); }

 private:
  static constexpr std::size_t kMaxReply = 256;  // USS A: a telegram is at most 256 bytes

  // What one exchange's read brought (read_reply()).
  struct Exchange {
    io::IoResult got;                     // the read's status, bytes read in all (echo included)
    std::span<const std::uint8_t> reply;  // the reply's bytes (complete or not)
    MonoTime complete_by{};               // start of the look that completed the reply
    bool collision = false;               // the echo came back changed
    bool echoed = false;                  // the reply stood behind a faithful echo
  };
  static constexpr std::size_t kEventSlots = 64;
  static constexpr std::size_t kSlotsKeptForLosses = 8;  // see push_skip_event()

  void cycle_loop() noexcept;
  void run_one_cycle(MonoTime wake, MonoTime planned) noexcept;
  Exchange read_reply(io::SerialPort& port, std::span<const std::uint8_t> frame, MonoTime sent_at,
                      MonoTime deadline) noexcept;
  void note_echo_decided(MonoTime now) noexcept;
  void lose_port(MonoTime now, int error_number) noexcept;
  void note_skip(MonoTime now, std::chrono::nanoseconds lateness, std::uint64_t skipped) noexcept;
  void end_skip_run(MonoTime now) noexcept;
  void notify() noexcept;
  bool push_skip_event(const CycleEvent& e) noexcept;
  static void bump(std::atomic<std::uint64_t>& a, std::uint64_t by = 1) noexcept {
    a.store(a.load(std::memory_order_relaxed) + by, std::memory_order_relaxed);
  }

  CycleConfig config_;
  CycleEngine& engine_;
  std::chrono::nanoseconds input_check_;  // config_.input_check_interval, resolved

  // Cycle thread state.
  std::array<std::uint8_t, 2 * kMaxReply> reply_{};  // the frame's echo, then the reply
  io::EchoDetector echo_;
  ReplyWatch reply_watch_;       // when to look first for a reply
  bool stray_possible_ = false;  // the last reply was missing or bad: flush before sending
  // The current run of skipped cycles (between two sent cycles).
  bool in_skip_run_ = false;
  bool skip_start_pending_ = false;  // its start event did not fit in the queue yet
  std::uint64_t run_skipped_ = 0;
  std::chrono::nanoseconds run_worst_{0};
  MonoTime run_started_{};
  bool skip_end_pending_ = false;  // a finished run's summary still to push
  CycleEvent pending_end_{};
  int notify_fd_ = -1;

  std::atomic<std::uint64_t> progress_{0};

  // Statistics (written by the cycle thread only).
  struct Counters {
    std::atomic<std::uint64_t> cycles{0}, frames_sent{0}, good_replies{0}, bad_replies{0},
        missing_replies{0}, partial_replies{0}, late_sends{0}, overruns{0}, skipped_cycles{0},
        late_replies{0}, send_failures{0}, stray_bytes{0}, echo_collisions{0}, reply_looks{0};
  } counters_;
  std::atomic<io::EchoState> echo_state_{io::EchoState::Unknown};
  // Lateness and work beyond a period are what matter most: 0..20 ms in 1 us bins (a period of
  // DCP 7.2 plus margin); anything beyond lands in the last bin and prints as "> 20000".
  Histogram<20000> wake_lateness_{std::chrono::microseconds(1)};
  Histogram<1500> reply_latency_{std::chrono::microseconds(10)};  // 0..15 ms in 10 us bins
  Histogram<20000> work_time_{std::chrono::microseconds(1)};
  FlightRecorder recorder_;

  // Events of the cycle thread; poll_event() drains them, then the keeper's.
  SpscQueue<CycleEvent, kEventSlots> cycle_events_;
  HeldEvent held_loss_;  // a port loss the full queue could not take yet

  // The cycle thread (cycle_loop), its port and the keeper thread that (re)opens the port.
  PortKeeper port_keeper_;
};

}  // namespace liftd::rt
