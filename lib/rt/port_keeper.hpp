// The serial port of a real-time thread (the DCP cycle, the USS bus), kept open by a helper
// "keeper" thread. Opening a device and closing a tty may block (a closing UART waits for its
// output to drain), so neither happens on the real-time thread: the keeper opens the device,
// retrying with a doubling backoff, and offers the descriptor through an atomic; the real-time
// thread adopts it, and on an I/O error hands the dead descriptor back for the keeper to close
// and to open the device again. The real-time side is lock free and allocation free. Both
// threads start and stop together, so the keeper starts and stops the real-time thread too.
#pragma once

#include <atomic>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <thread>

#include "common/mono_time.hpp"
#include "common/spsc_queue.hpp"
#include "io/serial_port.hpp"
#include "rt/cycle_event.hpp"
#include "rt/rt_thread.hpp"

namespace liftd::rt {

/// How a port keeper opens its device.
struct PortKeeperConfig {
  std::string device_path;                        ///< serial device, e.g. /dev/ttyS1 or a pty slave
  io::SerialSettings serial;                      ///< line settings of the link
  std::chrono::nanoseconds reopen_backoff_min{};  ///< first retry after a loss or failed open
  std::chrono::nanoseconds reopen_backoff_max{};  ///< retry interval cap (doubling)
  /// Adds the link's own notes to the text of a PortOpened event (after the RS485 and
  /// low-latency notes); may be empty. Runs on the keeper thread.
  std::function<void(const io::SerialPort& opened, std::string& text)> add_open_notes;
};

/// The PortLost event a runner queues from its real-time thread when it lost the port.
inline CycleEvent port_lost_event(MonoTime now, int error_number) noexcept {
  CycleEvent e;
  e.kind = CycleEventKind::PortLost;
  e.time = now;
  e.error_number = error_number;
  e.count = 1;  // losses in this event (more when it was held back behind a full queue)
  return e;
}

/// A real-time thread, the keeper thread beside it and the port the keeper keeps for it.
class PortKeeper {
 public:
  explicit PortKeeper(PortKeeperConfig config);
  PortKeeper(const PortKeeper&) = delete;
  PortKeeper& operator=(const PortKeeper&) = delete;
  /// Stops and joins both threads.
  ~PortKeeper();

  /// Starts the real-time thread running `rt_loop` (which returns once stop_requested()),
  /// reports what that thread got (a ThreadStatus event when a wish was refused), then starts
  /// the keeper thread, which opens the device at once. Returns 0, or EBUSY when running, or
  /// the errno of a failed thread start.
  int start(const RtThreadOptions& options, std::function<void()> rt_loop);
  /// Ends and joins both threads, then closes the port and any descriptor in hand-over
  /// (idempotent).
  void stop() noexcept;
  /// Real-time thread: true once stop() has begun; its loop returns then.
  bool stop_requested() const noexcept { return stop_.load(std::memory_order_relaxed); }
  /// What the real-time thread got (SCHED_FIFO, memory lock, affinity); valid after start().
  const RtThreadStatus& thread_status() const noexcept { return rt_thread_.status(); }

  /// Non-real-time side: pops the next event of the keeper (ThreadStatus, PortOpened,
  /// PortOpenFailed). Call from one thread only.
  bool poll_event(CycleEvent& out) noexcept { return keeper_events_.try_pop(out); }

  /// Real-time thread: the port it uses; closed until adopt_offered_port() took one.
  io::SerialPort& port() noexcept { return port_; }
  /// Real-time thread: takes the descriptor the keeper offers, if any. True when it did: the
  /// port is then open and ready.
  bool adopt_offered_port() noexcept;
  /// Real-time thread: the port failed; hands its descriptor back to the keeper to close and
  /// asks for the device again. The port is closed afterwards.
  void hand_back_port() noexcept;

  /// Any thread: true while the real-time thread has an open port.
  bool port_ready() const noexcept { return port_ready_.load(std::memory_order_relaxed); }
  /// Any thread: ports the real-time thread adopted (the first one included).
  std::uint64_t port_opens() const noexcept { return port_opens_.load(std::memory_order_relaxed); }
  /// Any thread: ports the real-time thread lost.
  std::uint64_t port_losses() const noexcept {
    return port_losses_.load(std::memory_order_relaxed);
  }

 private:
  static constexpr std::size_t kEventSlots = 64;

  void keeper_loop();
  std::string describe_opened(const io::SerialPort& opened) const;

  PortKeeperConfig config_;

  // Real-time thread state.
  io::SerialPort port_;

  // Shared between the two threads: a freshly opened descriptor, a dead one to close, and
  // whether the real-time thread wants a port.
  std::atomic<int> offered_fd_{-1};
  std::atomic<int> dead_fd_{-1};
  std::atomic<bool> port_wanted_{true};
  std::atomic<bool> stop_{false};
  std::atomic<bool> port_ready_{false};
  // Written by the real-time thread only.
  std::atomic<std::uint64_t> port_opens_{0};
  std::atomic<std::uint64_t> port_losses_{0};

  SpscQueue<CycleEvent, kEventSlots> keeper_events_;
  RtThread rt_thread_;
  std::thread keeper_;
  bool started_ = false;
};

}  // namespace liftd::rt
