// The simulated drive (DriveSim) on a serial device or pty, on its own thread: frames are found
// by the inter-frame gap, answered after the engine's reply delay, and the car keeps moving
// between frames. Other threads read the encoder position lock-free, read a status summary,
// switch faults and drain the drive's events. This is the simulator, not the master's cycle:
// a mutex held for short copies is acceptable, except for the position (atomics only).
//
// Device loss: with `reconnect` (the default) a lost device is retried every
// `reconnect_interval` (a path is reopened, an adopted descriptor is polled again, e.g. a pty
// master whose slave was closed and will be reopened) and the state shows Reconnecting.
// Without it the loop ends and the state shows DeviceLost.
#pragma once

#include <atomic>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <mutex>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "common/mono_time.hpp"
#include "common/snapshot_box.hpp"
#include "dcp/sim/drive_sim.hpp"
#include "io/serial_port.hpp"

namespace liftd::dcp::sim {

/// Where and how the runner serves the drive.
struct RunnerOptions {
  /// Serial device or pty slave path, opened at 38400 8N1 (DCP 7.1) by start(). Ignored when
  /// `fd` is set.
  std::string device;
  /// An already-open, configured descriptor (e.g. a pty master); the runner takes ownership
  /// and closes it. -1 = open `device` instead.
  int fd = -1;
  /// Silence inside a frame after which the partial frame is dropped (resynchronisation).
  /// DCP 7.2: frames are sent back to back (6 bytes take 1.56 ms at 38400 baud), so 1 ms of
  /// silence means the frame was torn.
  std::chrono::microseconds gap{1000};
  /// Longest wait for input before the car model is advanced anyway.
  std::chrono::milliseconds idle_poll{5};
  /// Queue only fault events (Fault, FaultCleared) for drain_events().
  bool quiet = false;
  /// End the loop after this many master frames (0 = run until stop()).
  std::uint64_t max_frames = 0;
  /// Keep retrying a lost device (true) or end the loop with DeviceLost (false).
  bool reconnect = true;
  /// Pause between reconnection attempts.
  std::chrono::milliseconds reconnect_interval{100};
  /// Events kept for drain_events() before the oldest are dropped.
  std::size_t event_capacity = 1024;
  /// The line echoes: the simulator stands for the transceiver too, and writes every byte the
  /// master sent back to the master as it arrives, before the drive's reply (an RS485
  /// transceiver whose receiver stays on while it sends, an auto-direction USB adapter).
  bool echo = false;
  /// SCHED_FIFO priority of the runner's thread (0 = normal scheduling). The simulated drive
  /// stands for hardware that answers within DCP 7.2 whatever else the machine runs; where
  /// real-time scheduling is refused the runner runs with normal scheduling (status says so).
  int priority = 0;
};

/// DCP 7.1/7.2: six bytes of 10 bits at 38400 baud take 1.5625 ms on an RS485 wire.
inline constexpr std::chrono::microseconds kFrameWireTime{1563};

/// Extra delay a reply needs on `fd` so the master sees it when a real RS485 line would deliver
/// it: a pseudo-terminal passes bytes at once, so the master's frame (which on the wire ends
/// 1.5625 ms after it began) and our reply (which takes another 1.5625 ms) both arrive early by
/// one frame's wire time each. Zero for a real serial port, whose UART takes that time itself.
std::chrono::microseconds pty_wire_time(int fd) noexcept;

/// What the runner's loop is doing.
enum class RunnerState : std::uint8_t {
  Idle,          ///< not started
  Running,       ///< serving frames
  Reconnecting,  ///< the device was lost; retrying
  DeviceLost,    ///< the device was lost and `reconnect` is off: loop ended
  FrameLimit,    ///< max_frames reached: loop ended
  Stopped,       ///< stop() ended the loop
  Failed,        ///< start() could not open the device or start the thread
};
/// "idle", "running", ...
std::string_view to_string(RunnerState state) noexcept;

/// Counters of the serial side (the engine's own counters are in SimCounters).
struct RunnerCounters {
  std::uint64_t resyncs = 0;         ///< partial frames dropped after the gap
  std::uint64_t write_failures = 0;  ///< replies the port did not take completely
  std::uint64_t device_losses = 0;   ///< hang-ups / lost devices seen
  std::uint64_t reconnects = 0;      ///< successful reopenings after a loss
  std::uint64_t dropped_events = 0;  ///< events dropped because the queue was full
  std::uint64_t collisions = 0;      ///< master frames collide() changed on the line
  bool realtime = false;             ///< the thread runs with SCHED_FIFO (options.priority)
};

/// A consistent copy of the drive's state for status lines and the API.
struct RunnerStatus {
  RunnerState state = RunnerState::Idle;  ///< loop state
  Phase phase = Phase::Idle;              ///< drive phase
  TravelKind travel = TravelKind::None;   ///< travel sequence running
  std::uint8_t status_byte = 0;           ///< DCP 4.1 status byte as the next reply carries it
  bool initialised = false;               ///< a valid I0 exchange happened
  double position_mm = 0.0;               ///< car position
  double velocity_mps = 0.0;              ///< car speed, + up
  SimCounters sim{};                      ///< engine counters
  RunnerCounters runner{};                ///< serial-side counters
};

/// The car's motion as the drive loop last computed it, published as one consistent value.
struct EncoderSample {
  double position_mm = 0.0;   ///< car position at `at`
  double velocity_mps = 0.0;  ///< car speed at `at`, + up
  MonoTime at{};              ///< when the loop computed it
  Trajectory motion{};        ///< the drive's plan from `at` on
  /// The car's position at `now` on the drive's own plan: exactly where the drive's model puts
  /// the car then, however long ago the loop last ran, as long as it has not changed the plan
  /// since (and a change starts from where this plan has the car at that moment).
  double position_at_mm(MonoTime now) const noexcept { return motion.position_mm(now); }
};

/// One line of text for an event, time relative to `epoch`:
/// "[     1.234] phase magnetising".
std::string format_event(const SimEvent& event, MonoTime epoch);
/// One status line: "status 0x01 phase idle pos 0.0 mm v +0.000 m/s frames ...".
std::string format_status(const RunnerStatus& status);
/// Parses a reply fault name: badsum, s7, late, noreply, garbage. False when unknown.
bool parse_reply_fault(std::string_view name, ReplyFault& out) noexcept;
/// Parses a channel fault name: partial, garbage, silence. False when unknown.
bool parse_channel_fault(std::string_view name, ChannelFault& out) noexcept;

/// The simulated drive served on a serial device by its own thread.
class SerialDriveRunner {
 public:
  /// A runner for `config` on the device or descriptor in `options`; nothing opens yet.
  SerialDriveRunner(const DriveConfig& config, RunnerOptions options);
  /// Stops the thread (see stop()).
  ~SerialDriveRunner();
  SerialDriveRunner(const SerialDriveRunner&) = delete;
  SerialDriveRunner& operator=(const SerialDriveRunner&) = delete;

  /// Opens the device (or adopts the descriptor) and starts the thread. False, with
  /// last_error(), when the device cannot be opened or the runner was started before.
  bool start();
  /// Ends the loop and joins the thread (returns within a few ms: the loop waits at most
  /// `idle_poll` or one reply delay). Idempotent.
  void stop() noexcept;
  /// True while the loop thread runs (false after stop(), DeviceLost or FrameLimit).
  bool running() const noexcept { return running_.load(std::memory_order_acquire); }
  /// Why start() failed, or the last open/reconnect error.
  std::string last_error() const;
  /// Loop state.
  RunnerState state() const noexcept { return state_.load(std::memory_order_acquire); }
  /// What RS485 / low-latency settings took effect when the device was (re)opened.
  io::PortFeatures port_features() const;
  /// Monotonic time the drive was powered on (the epoch for event lines).
  MonoTime epoch() const noexcept { return epoch_; }

  // --- the simulated encoder (lock-free, wait-free: safe in a real-time cycle) ---
  /// Car position in mm, updated by the loop on every frame and every idle wake-up.
  double position_mm() const noexcept { return position_mm_.load(std::memory_order_relaxed); }
  /// Car speed in m/s (+ up), updated with the position.
  double velocity_mps() const noexcept { return velocity_mps_.load(std::memory_order_relaxed); }
  /// Position, speed, acceleration and time of the last update as one consistent sample (a
  /// stale time means the loop has stalled). Only one thread may call it (the cycle's, where
  /// the sample stands for an absolute encoder): it takes the newest sample from a triple
  /// buffer, so the three values never come from two different updates.
  EncoderSample encoder_sample() const noexcept { return encoder_.read(); }

  // --- status (short lock) ---
  /// A consistent copy of the drive's state and counters.
  RunnerStatus status() const;
  /// Appends the events since the last call to `out` and returns how many.
  std::size_t drain_events(std::vector<SimEvent>& out);
  /// Appends the events since the last call as text lines (format_event) and returns how many.
  std::size_t drain_event_lines(std::vector<std::string>& out);

  // --- fault injection and set-up (short lock; take effect on the next frame) ---
  /// DCP 4.1 S3: general fault on/off.
  void set_general_fault(bool on);
  /// DCP 4.1 S2: advance warning on/off.
  void set_advance_warning(bool on);
  /// DCP 4.1 S0 forced off.
  void set_not_ready(bool on);
  /// Applies `fault` to the next `frames` replies.
  void inject(ReplyFault fault, std::uint32_t frames);
  /// The drive refuses the next target change with S5 (DCP 4.1).
  void refuse_next_target();
  /// Injects a communication-channel fault (DCP 5) now.
  void inject_channel(ChannelFault fault);
  /// The next `frames` master frames collide with another station's bits on the line: their
  /// second byte changes for every receiver, the master's echo (options.echo) and the drive
  /// alike, which then finds a bad checksum (DCP 6.2 a).
  void collide(std::uint32_t frames) noexcept { collide_.fetch_add(frames); }
  /// Applies `fault` to each reply with `probability` (0..1).
  void set_fault_rate(ReplyFault fault, double probability);
  /// Clears every reply fault and rate.
  void clear_reply_faults();
  /// Extended status flags (emergency power, temperature) to report.
  void set_extended_flags(const dcp::ExtendedStatus& flags);
  /// Moves the car (only while the drive is idle; ignored otherwise).
  void set_position_mm(double position_mm);

 private:
  void run() noexcept;
  bool reopen() noexcept;
  void publish(MonoTime now) noexcept;
  void collect_events() noexcept;
  void finish(RunnerState state) noexcept;
  void wake() noexcept;
  bool wait_for_stop(MonoTime until) noexcept;

  DriveConfig config_;
  RunnerOptions options_;
  MonoTime epoch_{};
  io::SerialPort port_;
  int wake_fd_ = -1;                       // eventfd: stop() wakes the loop's wait at once
  int epoll_fd_ = -1;                      // the loop's wait: wake_fd_ and the port's input
  std::chrono::microseconds wire_time_{};  // pty_wire_time() of the port (0 on a real line)
  std::thread thread_;
  std::atomic<bool> stop_requested_{false};
  std::atomic<bool> running_{false};
  std::atomic<RunnerState> state_{RunnerState::Idle};
  std::atomic<std::uint32_t> collide_{0};  // frames still to collide (collide())

  std::atomic<double> position_mm_{0.0};
  std::atomic<double> velocity_mps_{0.0};
  static_assert(std::atomic<double>::is_always_lock_free, "the encoder must be lock-free");
  mutable SnapshotBox<EncoderSample> encoder_;  // written under mutex_, read by one thread

  mutable std::mutex mutex_;  // guards everything below
  DriveSim sim_;
  RunnerCounters counters_{};
  std::deque<SimEvent> events_;
  std::string last_error_;
  io::PortFeatures features_{};
};

}  // namespace liftd::dcp::sim
