// The real-time thread of a USS bus (spec chapter A 5): sleeps until the master's next start
// (start pause, fixed cycle time), writes its telegram, reads the reply character by character
// (PARMRK-marked line errors decoded) until the master has what it needs or its deadline
// passes, then lets the user side run. A keeper thread (re)opens the device with backoff
// (rt::PortKeeper, as for CycleRunner). The protocol decisions are all in uss::Master; this
// file only does I/O and keeps time.
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
#include "rt/cycle_runner.hpp"
#include "rt/flight_recorder.hpp"
#include "rt/histogram.hpp"
#include "rt/port_keeper.hpp"
#include "rt/rt_thread.hpp"
#include "uss/line.hpp"
#include "uss/master/master.hpp"

namespace liftd::uss {

/// The user side of a USS bus (e.g. the lift's USS controller). Called only from the runner's
/// thread; must not allocate, lock or block.
class UssHooks {
 public:
  virtual ~UssHooks() = default;
  /// After every exchange (request and reply, timeout or broadcast), and about every 5 ms
  /// while there is no port: read the master's results, set PZD, submit PKW requests.
  virtual void after_exchange(MonoTime now) noexcept = 0;
  /// The port opened (true) or was lost (false).
  virtual void on_port(bool up, MonoTime now) noexcept = 0;
};

/// The USS line settings: 8E1 (B: 11-bit character, A 6.1) with parity and framing errors
/// delivered marked (USS A 5.2.2 counts them), at `baud`.
io::SerialSettings uss_serial_settings(std::uint32_t baud);

/// Parameters of one USS bus.
struct UssRunnerConfig {
  std::string device_path;  ///< serial device, e.g. /dev/ttyS1 or a pty slave
  /// Line settings; the baud rate must equal the master's. Default: 38400 8E1, mark_errors.
  io::SerialSettings serial = uss_serial_settings(38400);
  rt::RtThreadOptions thread;  ///< SCHED_FIFO priority, memory locking, affinity
  std::chrono::nanoseconds reopen_backoff_min = std::chrono::milliseconds(100);  ///< first retry
  std::chrono::nanoseconds reopen_backoff_max = std::chrono::seconds(2);         ///< retry cap
  /// How much traffic the flight recorder keeps (estimated from the expected cycle time, at
  /// most kMaxRecords records).
  std::chrono::nanoseconds recorder_span = std::chrono::seconds(30);
  /// Bytes kept per record: the longest telegram (A 4.2: 256).
  std::size_t recorder_bytes = rt::kUssRecordBytes;
  /// Whether the bus gives our own telegram back ahead of the reply (io/line_echo.hpp). The
  /// copy arrives while we send, before the telegram's end that the reply delay counts from
  /// (A 5.2.1.1), so it takes nothing from the slave's time.
  io::EchoMode echo = io::EchoMode::Off;
};

/// Counters of the runner, copied out by stats().
struct UssRunnerCounters {
  std::uint64_t exchanges = 0;          ///< telegrams sent and finished (with or without reply)
  std::uint64_t good_replies = 0;       ///< replies the master accepted
  std::uint64_t bad_replies = 0;        ///< replies the master rejected
  std::uint64_t reply_timeouts = 0;     ///< no reply by the master's deadline (A 5.2.1.1)
  std::uint64_t no_reply_expected = 0;  ///< broadcasts (A 3)
  std::uint64_t cycles = 0;             ///< passes of the polling list (master.cycles())
  std::uint64_t port_losses = 0;        ///< device losses
  std::uint64_t port_opens = 0;         ///< successful opens
  std::uint64_t send_failures = 0;      ///< telegrams the port refused (not a loss)
  std::uint64_t stray_bytes = 0;        ///< bytes flushed before sending
  std::uint64_t chars_received = 0;     ///< characters fed to the master
  std::uint64_t line_errors = 0;        ///< characters that arrived marked (parity/framing/break)
  /// Telegrams that came back changed on an echoing bus (a collision); each is also one of the
  /// bad replies.
  std::uint64_t echo_collisions = 0;
};

/// A copy of the runner's statistics, taken on any thread.
struct UssRunnerStats {
  UssRunnerCounters counters;
  rt::HistogramData cycle_time;  ///< master.last_cycle_time() per pass, 50 us bins up to 1 s
  /// Wake-up minus send_at() of each sleep until send_at(), 1 us bins up to 20 ms (none when
  /// send_at() had already passed, as after a reply timeout).
  rt::HistogramData wake_lateness;
  rt::HistogramData reply_time;  ///< end of our request to the end of the reply, 10 us bins
};

/// Runs a uss::Master on its own real-time thread, plus a helper thread that (re)opens the
/// device.
class UssRunner {
 public:
  /// Records in the flight recorder at most.
  static constexpr std::size_t kMaxRecords = 8192;

  /// Everything is allocated here; `master` and `hooks` must outlive the runner. Throws
  /// std::invalid_argument if the line's baud rate differs from the master's.
  UssRunner(UssRunnerConfig config, uss::Master& master, UssHooks& hooks);
  UssRunner(const UssRunner&) = delete;
  UssRunner& operator=(const UssRunner&) = delete;
  /// Stops and joins both threads.
  ~UssRunner();

  /// Starts the threads. Returns 0 or the errno of a failed thread start. A missing device is
  /// retried with backoff.
  int start();
  /// Stops the bus and closes the port (idempotent).
  void stop() noexcept;

  /// Non-real-time side: pops the next port/thread event (rt::CycleEvent, rt::describe()).
  bool poll_event(rt::CycleEvent& out) noexcept;

  /// What the thread got (SCHED_FIFO, memory lock, affinity); valid after start().
  const rt::RtThreadStatus& thread_status() const noexcept { return port_keeper_.thread_status(); }
  /// Any thread: counters and histograms.
  UssRunnerStats stats() const;
  /// Any thread: sent telegrams and received characters (copy(), write_text()).
  const rt::FlightRecorder& recorder() const noexcept { return recorder_; }
  /// Any thread: goes up after every exchange and every idle tick (systemd watchdog).
  std::uint64_t progress() const noexcept { return progress_.load(std::memory_order_relaxed); }
  /// An eventfd bumped after every exchange (one write(2), never blocks). Set before start().
  void set_notify_fd(int fd) noexcept { notify_fd_ = fd; }
  /// Any thread: true while a port is open on the bus thread.
  bool port_ready() const noexcept { return port_keeper_.port_ready(); }
  /// The configuration in use.
  const UssRunnerConfig& config() const noexcept { return config_; }
  /// Any thread: what the bus knows about its line's echo (config echo; Auto: found out at
  /// each port open, reported once as an rt::CycleEventKind::LineEcho event).
  io::EchoState echo_state() const noexcept { return echo_state_.load(std::memory_order_relaxed); }

 private:
  static constexpr std::size_t kEventSlots = 64;
  // A read takes at most this many bytes; with PARMRK a character may take 3.
  static constexpr std::size_t kReadBytes = 3 * uss::kMaxTelegramBytes;

  void loop() noexcept;
  void run_exchange(MonoTime wake) noexcept;
  void receive(MonoTime sent_at) noexcept;
  void feed(std::size_t raw_bytes, MonoTime now) noexcept;
  void to_master(const uss::RxChar& c, MonoTime at) noexcept;
  bool take_echo(const uss::RxChar& c, MonoTime at) noexcept;
  void release_held() noexcept;
  void after_reply_window() noexcept;
  void note_echo_decided(MonoTime now) noexcept;
  void adopt_offered_port() noexcept;
  void lose_port(MonoTime now, int error_number) noexcept;
  void notify() noexcept;
  static void bump(std::atomic<std::uint64_t>& a, std::uint64_t by = 1) noexcept {
    a.store(a.load(std::memory_order_relaxed) + by, std::memory_order_relaxed);
  }

  UssRunnerConfig config_;
  uss::Master& master_;
  UssHooks& hooks_;
  // How often the bus thread looks (TIOCINQ) for reply characters: one character time.
  std::chrono::nanoseconds input_check_;

  // Bus thread state.
  uss::ParmrkDecoder decoder_;
  std::array<std::uint8_t, kReadBytes> raw_{};
  std::array<uss::RxChar, kReadBytes> chars_{};
  std::array<std::uint8_t, uss::kMaxTelegramBytes> rx_record_{};  // reply bytes for the recorder
  std::size_t rx_record_size_ = 0;
  MonoTime sent_end_{};
  // The echo of the telegram being answered (echo on, or auto while finding out).
  io::EchoDetector echo_;
  std::span<const std::uint8_t> echo_sent_;  // the telegram sent (valid until the next one)
  std::size_t echo_pos_ = 0;                 // characters of it read back so far
  bool echo_done_ = false;                   // the echo is over (read back, or none this time)
  // Auto, undecided: characters that match the telegram so far are held back from the master
  // until they prove to be the echo (all of it came back) or not (one differs: they were the
  // reply's, and go to the master with their own times).
  std::array<MonoTime, uss::kMaxTelegramBytes> held_at_{};
  std::size_t held_ = 0;         // characters held back now
  bool echo_candidate_ = false;  // all of the telegram came back and is held as its echo
  bool echo_ambiguous_ = false;  // a mirror telegram's copy alone: echo or the mirror reply
  bool stray_possible_ = false;  // the last reply timed out or was bad: flush before sending
  std::uint64_t last_cycles_ = 0;
  int notify_fd_ = -1;

  std::atomic<std::uint64_t> progress_{0};

  struct Counters {
    std::atomic<std::uint64_t> exchanges{0}, good_replies{0}, bad_replies{0}, reply_timeouts{0},
        no_reply_expected{0}, cycles{0}, send_failures{0}, stray_bytes{0}, chars_received{0},
        line_errors{0}, echo_collisions{0};
  } counters_;
  std::atomic<io::EchoState> echo_state_{io::EchoState::Unknown};
  rt::Histogram<20000> cycle_time_{std::chrono::microseconds(50)};    // 0..1 s
  rt::Histogram<20000> wake_lateness_{std::chrono::microseconds(1)};  // 0..20 ms
  rt::Histogram<10000> reply_time_{std::chrono::microseconds(10)};    // 0..100 ms
  rt::FlightRecorder recorder_;

  // Events of the bus thread; poll_event() drains them, then the keeper's.
  SpscQueue<rt::CycleEvent, kEventSlots> bus_events_;
  rt::HeldEvent held_loss_;  // a port loss the full queue could not take yet

  // The bus thread (loop), its port and the keeper thread that (re)opens the port.
  rt::PortKeeper port_keeper_;
};

}  // namespace liftd::uss
