#include "sch001/protocol.hpp"

#include <array>

namespace liftd::sch001 {
namespace {

constexpr bool bit(std::uint8_t byte, unsigned n) noexcept {
  return ((static_cast<unsigned>(byte) >> n) & 1U) != 0;
}
constexpr std::uint8_t set(bool value, unsigned n) noexcept {
  return static_cast<std::uint8_t>(value ? 1U << n : 0U);
}

}  // namespace

std::optional<Ids> ids_for(std::uint32_t p479, std::uint32_t p480, std::string* why) {
  const auto fail = [why](std::string text) -> std::optional<Ids> {
    if (why != nullptr) *why = std::move(text);
    return std::nullopt;
  };
  const std::uint32_t base = p479 == 0 ? kDefaultBase : p479;
  if (p480 == 0) return fail("P480 = 0 makes the card ignore every command (card document 2.2)");
  if (p480 < 2 || p480 >= kReservedIds) {
    return fail(
        "the controller node offset (P480) must be 2..95: inside the card's block of 96 "
        "identifiers and not base + 1, where the card receives (card document 1.6)");
  }
  if (base + kReservedIds - 1 > can::kMaxStandardId) {
    return fail("the card's base (P479) must leave its 96 identifiers within 0x7FF (11 bits)");
  }
  return Ids{base + 1, base + p480};
}

CardStatus CardStatus::from_byte(std::uint8_t b) noexcept {
  return {bit(b, 7), bit(b, 6), bit(b, 5), bit(b, 4), bit(b, 3), bit(b, 2), bit(b, 1), bit(b, 0)};
}

std::uint8_t CardStatus::to_byte() const noexcept {
  return static_cast<std::uint8_t>(set(err, 7) | set(pnp2, 6) | set(avv, 5) | set(t1, 4) |
                                   set(p1, 3) | set(p2, 2) | set(rdy, 1) | set(pnp1, 0));
}

CommandBits CommandBits::from_byte(std::uint8_t b) noexcept {
  return {bit(b, 7), bit(b, 6), bit(b, 5), bit(b, 4), bit(b, 3), bit(b, 2), bit(b, 1), bit(b, 0)};
}

std::uint8_t CommandBits::to_byte() const noexcept {
  return static_cast<std::uint8_t>(set(sp3, 7) | set(sp2, 6) | set(sp1, 5) | set(sfy, 4) |
                                   set(msp, 3) | set(hsp, 2) | set(dw, 1) | set(up, 0));
}

std::string_view to_string(Rejection rejection) noexcept {
  switch (rejection) {
    case Rejection::WrongLength:
      return "wrong length";
    case Rejection::UnknownFirstByte:
      return "unknown first byte";
  }
  return "unknown";
}

CardMessage decode_card_frame(const can::Frame& frame) noexcept {
  if (frame.length == 0) return Rejection::WrongLength;
  switch (frame.data[0]) {
    case kStatusFrame:
      if (frame.length != kStatusFrameLength) return Rejection::WrongLength;
      return StatusFrame{CardStatus::from_byte(frame.data[1])};
    case kEnableTimeout:
      return TimeoutCommand{true};
    case kDisableTimeout:
      return TimeoutCommand{false};
    default:
      return Rejection::UnknownFirstByte;
  }
}

can::Frame encode_command(const Ids& ids, const Command& command) noexcept {
  const std::array<std::uint8_t, kCommandFrameLength> bytes = {
      kCommandFrame, command.bits.to_byte(), command.current_floor, command.destination_floor};
  return can::make_frame(ids.to_card, bytes);
}

can::Frame encode_timeout_ack(const Ids& ids, bool enabled) noexcept {
  const std::array<std::uint8_t, 1> bytes = {enabled ? kTimeoutEnabledAck : kTimeoutDisabledAck};
  return can::make_frame(ids.to_card, bytes);
}

}  // namespace liftd::sch001
