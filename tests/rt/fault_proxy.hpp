// A fault-injecting relay between two pty pairs: the master's side (A) and the responder's
// side (B). It forwards each 6-byte request to B and damages B's reply on its way back to A
// according to a plan, counting what it did.
#pragma once

#include <array>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>

#include "rt/rt_thread.hpp"

namespace liftd::rt::testing {

/// What the proxy does to one reply.
enum class Fault : std::uint8_t {
  None,        ///< pass the reply unchanged
  FlipBit,     ///< flip one bit of byte 2 (checksum no longer matches)
  DropByte,    ///< leave out byte 2 (5 bytes arrive)
  Truncate,    ///< send only the first 3 bytes
  ExtraBytes,  ///< append 2 garbage bytes after the reply
  Stall,       ///< hold the reply for kStall, far past the reply deadline
  Silence,     ///< swallow the reply
};
/// Number of Fault values (for per-fault counters).
inline constexpr std::size_t kFaultKinds = 7;

/// Relays between `a_fd` (pty master whose slave the cycle opened) and `b_fd` (a descriptor on
/// the responder's pty). Descriptors are not owned.
class FaultProxy {
 public:
  /// How long a stalled reply is held: with a 1 ms responder it reaches the master ~37 ms after
  /// the request, inside the reply window of the cycle after next (30..43.6 ms).
  static constexpr auto kStall = std::chrono::milliseconds(36);

  /// `plan(request_index)` picks the fault for each request's reply.
  FaultProxy(int a_fd, int b_fd, std::function<Fault(std::uint64_t)> plan, int priority = 0);
  FaultProxy(const FaultProxy&) = delete;
  FaultProxy& operator=(const FaultProxy&) = delete;
  ~FaultProxy();

  /// Starts relaying. Returns 0 or an errno.
  int start();
  /// Stops and joins (idempotent).
  void stop() noexcept;
  /// Replies that got `fault` (None counts clean relays).
  std::uint64_t applied(Fault fault) const noexcept {
    return applied_[static_cast<std::size_t>(fault)].load(std::memory_order_relaxed);
  }
  /// Requests relayed so far.
  std::uint64_t requests() const noexcept { return requests_.load(std::memory_order_relaxed); }
  /// Stops fault injection from now on (every later reply passes unchanged).
  void heal() noexcept { healed_.store(true, std::memory_order_relaxed); }

 private:
  void loop() noexcept;

  int a_fd_;
  int b_fd_;
  std::function<Fault(std::uint64_t)> plan_;
  RtThreadOptions options_;
  RtThread thread_;
  std::atomic<bool> stop_{false};
  std::atomic<bool> healed_{false};
  std::atomic<std::uint64_t> requests_{0};
  std::array<std::atomic<std::uint64_t>, kFaultKinds> applied_{};
};

}  // namespace liftd::rt::testing
