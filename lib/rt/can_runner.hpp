// The frame-driven runner for a CAN drive (the SCH001 card): a thread of its own (real-time
// where it may) that waits on the CAN endpoint, hands every frame to the engine and sends the
// engine's answer at once, ticks the engine between frames, records the traffic for `trace`,
// and reopens a failed endpoint with backoff. The card's 100 ms status frame is the clock; the
// tick only serves timeouts and the sequencing between frames.
#pragma once

#include <atomic>
#include <cstdint>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "can/frame.hpp"
#include "can/socket.hpp"
#include "common/mono_time.hpp"
#include "rt/flight_recorder.hpp"
#include "rt/rt_thread.hpp"

namespace liftd::rt {

/// What a CAN runner drives. Every method runs on the runner's thread and must not block,
/// lock or allocate.
class CanEngine {
 public:
  virtual ~CanEngine() = default;
  /// A data frame arrived; the frame to send at once, if any.
  virtual std::optional<can::Frame> on_frame(const can::Frame& frame, MonoTime now) noexcept = 0;
  /// An error frame arrived.
  virtual void on_bus_error(const can::ErrorReport& report, MonoTime now) noexcept = 0;
  /// The endpoint opened (true) or failed / closed (false).
  virtual void on_endpoint(bool up, MonoTime now) noexcept = 0;
  /// Called on every wake-up, at least every tick period.
  virtual void on_tick(MonoTime now) noexcept = 0;
  /// The answer on_frame() returned went out (`delivered`) or could not be sent (the socket's
  /// queue was full: nobody takes our frames).
  virtual void on_sent(bool /*delivered*/, MonoTime /*now*/) noexcept {}
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
  /// The last open or socket error ("" when none).
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
  void loop();
  bool open_endpoint(MonoTime now);
  void close_endpoint(MonoTime now, int error, const char* what);
  void schedule_reopen(MonoTime now) noexcept;
  void record(MonoTime now, Direction direction, std::uint8_t flags, const can::Frame& frame);
  void notify() noexcept;

  CanRunnerConfig config_;
  CanEngine& engine_;
  std::optional<can::CanSocket> socket_;
  bool adopted_ = false;
  RtThread thread_;
  FlightRecorder recorder_;
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
  std::uint64_t overflowed_before_socket_ = 0;  // by the sockets closed before this one
  mutable std::mutex error_mutex_;  ///< guards last_error_ (written off the hot path only)
  std::string last_error_;
};

}  // namespace liftd::rt
