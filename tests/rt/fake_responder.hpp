// A stand-in for the drive on the far end of a pty: answers every 6-byte frame after a fixed
// delay with a reply derived from it, so the master can check the reply belongs to its frame.
// Used by the cycle tests and by tools/bench/cycle-bench (until the drive simulator plugs in).
#pragma once

#include <array>
#include <atomic>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <span>

#include "rt/rt_thread.hpp"

namespace liftd::rt::testing {

/// Bytes of a request and of a reply (DCP 2: 6).
inline constexpr std::size_t kEchoFrameSize = 6;
/// XOR mask the responder applies to bytes 0..4 of a request to make its reply.
inline constexpr std::uint8_t kEchoMask = 0xA5;

/// XOR of bytes 0..4 (DCP 3.4 checksum rule), the last byte of every echo frame.
std::uint8_t echo_checksum(std::span<const std::uint8_t> frame) noexcept;
/// The reply the responder gives to `request`: bytes 0..4 XOR kEchoMask, then the checksum.
std::array<std::uint8_t, kEchoFrameSize> echo_reply(std::span<const std::uint8_t> request) noexcept;

/// What the line between the master and the responder does with the master's bytes.
struct ResponderLine {
  /// The line echoes (a transceiver whose receiver stays on while it sends, an auto-direction
  /// USB adapter): every byte the master sends comes back to it as it is sent, before any
  /// reply.
  bool echo = false;
  /// Answer no frame (a drive that is off, behind an echoing line).
  bool silent = false;
};

/// Answers 6-byte frames read from `fd` (not owned) after `reply_delay`, on its own thread.
class FakeResponder {
 public:
  /// Bytes of a frame must arrive within this gap or the partial frame is dropped (resync).
  static constexpr auto kInterByteGap = std::chrono::milliseconds(5);

  /// What the line does with the master's bytes.
  using Line = ResponderLine;

  /// Talks over `fd` (a pty master or a serial port descriptor); thread starts in start().
  FakeResponder(int fd, std::chrono::microseconds reply_delay, int priority = 0,
                ResponderLine line = ResponderLine{});
  FakeResponder(const FakeResponder&) = delete;
  FakeResponder& operator=(const FakeResponder&) = delete;
  ~FakeResponder();

  /// Starts answering. Returns 0 or an errno.
  int start();
  /// Stops and joins (idempotent).
  void stop() noexcept;
  /// Frames answered so far.
  std::uint64_t answered() const noexcept { return answered_.load(std::memory_order_relaxed); }
  /// The next `frames` frames collide with another station's bits: the second byte of each is
  /// changed on the line, so the master reads back a changed echo and the responder reads the
  /// changed frame too (one line, one signal for every receiver on it).
  void collide(std::uint32_t frames) noexcept { collide_.fetch_add(frames); }
  /// Collisions made so far.
  std::uint64_t collisions() const noexcept { return collisions_.load(std::memory_order_relaxed); }

 private:
  void loop() noexcept;

  int fd_;
  std::chrono::microseconds reply_delay_;
  Line line_;
  std::atomic<std::uint32_t> collide_{0};
  std::atomic<std::uint64_t> collisions_{0};
  RtThreadOptions options_;
  RtThread thread_;
  std::atomic<bool> stop_{false};
  std::atomic<std::uint64_t> answered_{0};
};

}  // namespace liftd::rt::testing
