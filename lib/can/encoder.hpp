// A generic absolute position encoder on CAN (position.source "can"), sans-I/O: which frame
// carries the position, where in it, in which byte order and sign, and how counts become
// millimetres. CanEncoder is the position source the real-time side reads; it goes stale (no
// position, so any travel ends) when no frame came within the timeout.
#pragma once

#include <atomic>
#include <cstdint>
#include <optional>
#include <string>

#include "can/frame.hpp"
#include "common/mono_time.hpp"
#include "common/position_source.hpp"

namespace liftd::can {

/// Where the position is in the encoder's frame.
struct EncoderFormat {
  std::uint32_t id = 0x190;          ///< 11-bit identifier of the encoder's frame
  std::uint8_t offset = 0;           ///< first byte of the value in the data
  std::uint8_t length = 4;           ///< 2 to 4 bytes
  bool big_endian = false;           ///< byte order of the value (CANopen encoders: little)
  bool is_signed = false;            ///< two's complement value
  std::int64_t um_per_count = 1000;  ///< micrometres per count (1000: 1 mm per count)
  std::int64_t offset_mm = 0;        ///< added after scaling: the car position at count 0
};

/// What is wrong with `format`, or nullopt.
std::optional<std::string> validate(const EncoderFormat& format);

/// The car position in `frame`, or nullopt when the frame is not the encoder's or too short.
std::optional<std::int64_t> decode_position(const EncoderFormat& format, const Frame& frame);

/// The encoder as a position source: fed on the CAN thread, read on the real-time thread.
class CanEncoder final : public PositionSource {
 public:
  CanEncoder(const EncoderFormat& format, MonoTime timeout) noexcept
      : format_(format), feed_(timeout) {}
  /// A frame from the bus at `now`; true when it was the encoder's.
  bool on_frame(const Frame& frame, MonoTime now) noexcept;
  std::optional<std::int64_t> position_mm(MonoTime now) const noexcept override {
    return feed_.position_mm(now);
  }
  const EncoderFormat& format() const noexcept { return format_; }
  /// Frames with the encoder's identifier that were too short to carry the value.
  std::uint64_t short_frames() const noexcept {
    return short_frames_.load(std::memory_order_relaxed);
  }

 private:
  EncoderFormat format_;
  PositionFeed feed_;
  std::atomic<std::uint64_t> short_frames_{0};
};

}  // namespace liftd::can
