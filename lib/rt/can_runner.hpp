// The runner of a CAN bus loop: a thread of its own (real-time where it may) that waits on the
// CAN endpoint, feeds the engine every frame and the time, sends whatever the engine queued
// right after each call, records the traffic for `trace`, and reopens a failed endpoint with
// backoff. An engine may send in answer to a frame (the SCH001 card's 100 ms status frame is
// answered at once) or on its own schedule from on_tick (a CANopen master's SYNC, PDOs,
// heartbeat), whichever its protocol says.
//
// The loop allocates nothing, takes no lock and never blocks but in poll(), reopening
// included: the endpoint's opener (can::EndpointOpener) and the CanSocket it attaches to are
// built before the thread starts, and the last error is published as numbers in one atomic
// that last_error() turns into words on the caller's thread.
//
// One seam for every bus loop. The three runners of lib/ differ in what clocks them, not in
// the shape of their engine: each is fed what arrived and the time, and sends when its
// protocol says.
// - CAN (here): frames and ticks in (on_frame, on_tick, on_bus_error, on_endpoint), frames out
//   through a CanOutbox from on_frame and on_tick, each frame's fate back (on_sent). Sending
//   unasked is the normal case.
// - The DCP cycle (rt::CycleEngine, cycle_runner.hpp): the protocol is master-slave with a
//   fixed 15 ms period (DCP 7.2), so "when the protocol says" is every period:
//   frame_to_send(now) is the engine's outbox of one frame per cycle (an empty span sends
//   nothing), on_reply / on_no_reply feed it what arrived by the deadline, after_cycle is the
//   tick, on_port_ready / on_port_lost the endpoint.
// - The USS bus (uss::UssHooks, lib/uss/runner/uss_runner.hpp): the master (uss::Master)
//   decides each telegram when the bus's timing allows (start pause A 5.1.2, reply delay
//   A 5.2.1.1, cycle time A 5.1.1) and is fed the reply's characters; the hooks'
//   after_exchange(now) is the tick and on_port the endpoint. What the lift sends goes into the
//   master's PZD and PKW requests, its outbox, which the next telegram carries.
// The CAN seam is the general one (any number of frames at any time); the serial two are its
// special case where the bus lets the master send only at its own turn.
#pragma once

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "can/frame.hpp"
#include "can/socket.hpp"
#include "common/mono_time.hpp"
#include "rt/flight_recorder.hpp"
#include "rt/rt_thread.hpp"

namespace liftd::rt {

/// The frames an engine asks its runner to send during one call of on_frame() or on_tick():
/// fixed slots, no allocation. The runner sends them in order as soon as the call returns and
/// tells the engine each one's fate through CanEngine::on_sent(). A frame beyond the slots is
/// refused (send() returns false) and counted (CanRunnerCounters::outbox_overflows).
class CanOutbox {
 public:
  /// Frames one call may queue. A CANopen master's SYNC, its four RPDOs to a node (CiA 301's
  /// default PDO set) and a heartbeat are six; 8 stays within one transmit queue of a SocketCAN
  /// interface (the kernel's CAN drivers default to txqueuelen 10).
  static constexpr std::size_t kCapacity = 8;

  /// Queues `frame`; false, and counted, when every slot is taken.
  bool send(const can::Frame& frame) noexcept {
    if (count_ == kCapacity) {
      ++overflows_;
      return false;
    }
    frames_[count_++] = frame;
    return true;
  }
  /// Slots still free in this call.
  std::size_t room() const noexcept { return kCapacity - count_; }
  /// What this call queued so far, oldest first.
  std::span<const can::Frame> queued() const noexcept { return {frames_.data(), count_}; }
  /// Frames refused since this outbox was made.
  std::uint64_t overflows() const noexcept { return overflows_; }
  /// Empties the slots (the runner, before each call; tests).
  void clear() noexcept { count_ = 0; }

 private:
  std::array<can::Frame, kCapacity> frames_{};
  std::size_t count_ = 0;
  std::uint64_t overflows_ = 0;
};

/// What a CAN runner drives: fed frames, bus errors, the endpoint's state and the time; sends
/// through the CanOutbox it is handed whenever its protocol says. Every method runs on the
/// runner's thread and must not block, lock or allocate.
class CanEngine {
 public:
  virtual ~CanEngine() = default;
  /// A data frame arrived; queue in `out` what to send now (an answer, or nothing).
  virtual void on_frame(const can::Frame& frame, MonoTime now, CanOutbox& out) noexcept = 0;
  /// An error frame arrived.
  virtual void on_bus_error(const can::ErrorReport& report, MonoTime now) noexcept = 0;
  /// The endpoint opened (true) or failed / closed (false). An engine that sends on opening
  /// (a CANopen NMT start) does so in its next on_tick(), at most one tick period later.
  virtual void on_endpoint(bool up, MonoTime now) noexcept = 0;
  /// Called on every loop pass, at least every tick period (CanRunnerConfig::tick), after the
  /// frames of that pass: timeouts, sequencing, and what the engine sends on its own schedule.
  virtual void on_tick(MonoTime now, CanOutbox& out) noexcept = 0;
  /// A frame this engine queued went out (`delivered`) or could not be sent (the socket's
  /// queue was full: nobody takes our frames; or the endpoint failed or was closed). Called
  /// once per queued frame, in order, right after the call that queued it.
  virtual void on_sent(const can::Frame& /*frame*/, bool /*delivered*/, MonoTime /*now*/) noexcept {
  }
};

struct CanRunnerConfig {
  std::string endpoint;            ///< "can0" or "unix:PATH" (config can.interface)
  std::vector<std::uint32_t> ids;  ///< identifiers to receive
  MonoTime tick = std::chrono::milliseconds(10);
  MonoTime reopen_first = std::chrono::milliseconds(100);  ///< first retry after a failure
  MonoTime reopen_max = std::chrono::seconds(5);           ///< retries back off up to this
  RtThreadOptions rt{};
  std::size_t recorder_records = 2048;  ///< about 100 s of a card's 10 frames/s both ways
};

/// Counters for `stats` (read from any thread).
struct CanRunnerCounters {
  std::uint64_t frames_received = 0;
  std::uint64_t frames_sent = 0;
  std::uint64_t send_errors = 0;
  std::uint64_t error_frames = 0;
  std::uint64_t reopens = 0;     ///< endpoint (re)opened after the first time
  std::uint64_t dropped = 0;     ///< records the endpoint dropped (filtered, malformed, 29-bit)
  std::uint64_t overflowed = 0;  ///< frames the kernel dropped on our full receive queue
  std::uint64_t outbox_overflows = 0;  ///< frames the engine queued beyond CanOutbox::kCapacity
};

class CanRunner {
 public:
  CanRunner(const CanRunnerConfig& config, CanEngine& engine);
  ~CanRunner();
  CanRunner(const CanRunner&) = delete;
  CanRunner& operator=(const CanRunner&) = delete;

  /// Use this connected endpoint (one end of a socketpair under --simulate) instead of opening
  /// config.endpoint; a failure of it is final (there is nothing to reopen).
  void adopt(can::CanSocket socket);
  /// Starts the thread (the first open happens on it). 0 or an errno.
  int start();
  /// Ends the loop and joins (within one tick). Idempotent.
  void stop() noexcept;

  const RtThreadStatus& thread_status() const noexcept { return thread_.status(); }
  const CanRunnerConfig& config() const noexcept { return config_; }
  CanRunnerCounters counters() const noexcept;
  /// The last open or socket error ("" when none), in words made on the caller's thread.
  std::string last_error() const;
  /// Advances on every loop pass: the daemon's watchdog sees the thread alive.
  std::uint64_t progress() const noexcept { return progress_.load(std::memory_order_relaxed); }
  /// Frames sent and received; each record is the 11-bit identifier (2 bytes, big-endian)
  /// followed by the data bytes.
  const FlightRecorder& recorder() const noexcept { return recorder_; }
  /// An eventfd (or -1) bumped after every loop pass (frames answered, or a tick), so the io
  /// thread wakes at once for what the engine queued.
  void set_notify_fd(int fd) noexcept { notify_fd_ = fd; }

 private:
  /// What failed last, published by the loop as numbers (publish_error()).
  enum class ErrorWhat : std::uint8_t {
    None,
    Open,         ///< opening failed: the step in the packed word
    PeerClosed,   ///< the CAN peer closed the connection
    ReadFailed,   ///< reading the CAN endpoint failed
    WriteFailed,  ///< writing to the CAN endpoint failed
  };

  void loop();
  bool open_endpoint(MonoTime now) noexcept;
  void close_endpoint(MonoTime now, int error, ErrorWhat what) noexcept;
  void schedule_reopen(MonoTime now) noexcept;
  /// Sends what the engine queued in outbox_, tells it each frame's fate, empties the outbox.
  /// False when a write failed the endpoint (it is closed then).
  bool send_queued(MonoTime now) noexcept;
  void record(MonoTime now, Direction direction, std::uint8_t flags,
              const can::Frame& frame) noexcept;
  void notify() noexcept;
  void publish_error(int error, ErrorWhat what, can::OpenStep step = {}) noexcept;

  CanRunnerConfig config_;
  CanEngine& engine_;
  can::EndpointOpener opener_;  ///< built with the runner: the loop opens without allocating
  can::CanSocket socket_;       ///< one endpoint for the runner's life; descriptors come and go
  bool adopted_ = false;
  RtThread thread_;
  FlightRecorder recorder_;
  CanOutbox outbox_;
  std::atomic<bool> stop_{false};
  std::atomic<std::uint64_t> progress_{0};
  int wake_fd_ = -1;    ///< eventfd that ends the wait on stop()
  int notify_fd_ = -1;  ///< eventfd for the io thread
  MonoTime reopen_at_{};
  MonoTime reopen_delay_{};
  bool ever_opened_ = false;
  std::atomic<std::uint64_t> frames_received_{0};
  std::atomic<std::uint64_t> frames_sent_{0};
  std::atomic<std::uint64_t> send_errors_{0};
  std::atomic<std::uint64_t> error_frames_{0};
  std::atomic<std::uint64_t> reopens_{0};
  std::atomic<std::uint64_t> dropped_{0};
  std::atomic<std::uint64_t> overflowed_{0};
  std::atomic<std::uint64_t> outbox_overflows_{0};
  /// The last error: errno in the low 32 bits, ErrorWhat and OpenStep above (publish_error()), in
  /// one word so that a reader never sees one error's number with another's words. Written by
  /// the loop, read by last_error() on any thread; no lock is shared with the loop.
  std::atomic<std::uint64_t> last_error_{0};
};

}  // namespace liftd::rt
