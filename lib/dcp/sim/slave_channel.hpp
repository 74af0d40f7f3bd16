// The drive's sending end of the DCP communication channel (DCP 5): whole messages are queued
// (I-message replies, error messages, display lines) and leave two bytes per reply.
// Receiving uses the shared dcp::ChannelParser. Pure code: no I/O, fixed buffers.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

namespace liftd::dcp::sim {

/// The drive's outgoing channel bytes: unlike dcp::ChannelTransmitter it queues several
/// messages, because a drive may add an error message or display lines at any time and sends
/// them after the message in progress (DCP 5.11).
class ChannelOutput {
 public:
  /// Room for the four display lines (4 x 25 bytes), an error message and an I-message reply.
  static constexpr std::size_t kCapacity = 512;

  /// Queues STX mode body ETX, or nothing if it does not fit. Returns whether it was queued.
  bool push_message(std::uint8_t mode, std::span<const std::uint8_t> body) noexcept;
  /// Queues raw bytes as they are (fault injection), or nothing if they do not fit.
  bool push_raw(std::span<const std::uint8_t> bytes) noexcept;
  /// The next channel byte, 0x00 (idle) when nothing is queued.
  std::uint8_t pop() noexcept;
  /// Bytes waiting.
  std::size_t size() const noexcept { return size_; }
  /// Drops everything queued.
  void clear() noexcept { head_ = size_ = 0; }

 private:
  std::array<std::uint8_t, kCapacity> ring_{};
  std::size_t head_ = 0;
  std::size_t size_ = 0;
};

}  // namespace liftd::dcp::sim
