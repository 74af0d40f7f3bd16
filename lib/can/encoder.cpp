#include "can/encoder.hpp"

namespace liftd::can {

std::optional<std::string> validate(const EncoderFormat& f) {
  if (f.id > kMaxStandardId) return "the encoder's identifier must be 11 bits (0..0x7FF)";
  if (f.length < 2 || f.length > 4) return "the value is 2 to 4 bytes long";
  if (f.offset + f.length > kMaxData) {
    return "offset + length must stay within the 8 data bytes of a CAN frame";
  }
  if (f.um_per_count == 0) return "the scale (micrometres per count) must not be 0";
  return std::nullopt;
}

std::optional<std::int64_t> decode_position(const EncoderFormat& f, const Frame& frame) {
  if (frame.id != f.id || frame.length < f.offset + f.length) return std::nullopt;
  std::uint32_t raw = 0;
  for (std::size_t i = 0; i < f.length; ++i) {
    const std::size_t at = f.offset + (f.big_endian ? i : f.length - 1U - i);
    raw = (raw << 8) | frame.data[at];
  }
  std::int64_t counts = raw;
  if (f.is_signed) {
    const unsigned bits = 8U * f.length;
    const std::int64_t sign = std::int64_t{1} << (bits - 1);
    counts = (counts ^ sign) - sign;  // sign-extend the top bit of the value
  }
  // Round to the nearest millimetre (half away from zero).
  const std::int64_t um = counts * f.um_per_count;
  const std::int64_t mm = um >= 0 ? (um + 500) / 1000 : -((-um + 500) / 1000);
  return mm + f.offset_mm;
}

bool CanEncoder::on_frame(const Frame& frame, MonoTime now) noexcept {
  if (frame.id != format_.id) return false;
  if (const auto mm = decode_position(format_, frame)) {
    feed_.set(*mm, now);
  } else {
    short_frames_.fetch_add(1, std::memory_order_relaxed);
  }
  return true;
}

}  // namespace liftd::can
