// A classic CAN frame as the protocol code sees it: identifier, length and data, no kernel
// types. lib/can/socket.* converts to and from struct can_frame; lib/sch001 and the position
// encoder decode these.
#pragma once

#include <array>
#include <cstdint>
#include <span>

namespace liftd::can {

/// CAN 2.0A: identifiers are 11 bits.
inline constexpr std::uint32_t kMaxStandardId = 0x7FF;
/// A classic CAN frame carries at most 8 data bytes.
inline constexpr std::size_t kMaxData = 8;

/// One classic CAN data frame with an 11-bit identifier.
struct Frame {
  std::uint32_t id = 0;                       ///< 11-bit identifier
  std::uint8_t length = 0;                    ///< data length code, 0..8
  std::array<std::uint8_t, kMaxData> data{};  ///< bytes beyond `length` are 0
  /// The `length` bytes of data.
  std::span<const std::uint8_t> bytes() const noexcept { return {data.data(), length}; }
  bool operator==(const Frame&) const = default;
};

/// A frame with `id` and the given bytes (at most 8; more are cut off).
Frame make_frame(std::uint32_t id, std::span<const std::uint8_t> bytes) noexcept;

}  // namespace liftd::can
