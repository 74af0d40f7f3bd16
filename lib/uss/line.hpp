// Serial line characters as the receiver sees them, and the decoder for a termios line opened
// with PARMRK (parity and framing errors marked in the byte stream). No I/O, no allocation.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>

namespace liftd::uss {

/// What the UART said about one character (A 5.2.2: parity and framing errors are receive
/// errors; A 5.2.3 also counts overruns).
enum class LineError : std::uint8_t { None, Parity, Framing, Overrun, Break };

std::string_view to_string(LineError error) noexcept;

/// One received character.
struct RxChar {
  std::uint8_t byte = 0;
  LineError error = LineError::None;
  bool operator==(const RxChar&) const = default;
};

/// Decodes the byte stream of a tty opened with INPCK | PARMRK and without IGNPAR / ISTRIP /
/// IGNBRK / BRKINT:
///  - 0xFF 0xFF       = data byte 0xFF,
///  - 0xFF 0x00 c     = byte c received with a parity or framing error (Linux marks both the
///                      same way, so it is reported as Parity),
///  - 0xFF 0x00 0x00  = a break (reported as Break; a parity error on a 0x00 byte looks the
///                      same and is reported as Break too),
///  - any other byte  = itself.
/// A lone 0xFF followed by any other byte cannot come from such a tty; the pair is reported as
/// that byte with LineError::Parity so the telegram it belongs to is rejected. Overruns are not
/// marked in the stream by Linux (they show in TIOCGICOUNT only).
/// Keeps state across calls (an escape may straddle reads). Never writes more characters than
/// raw.size(): out.size() >= raw.size() is enough.
class ParmrkDecoder {
 public:
  /// Decodes raw into out; returns the number of characters written.
  std::size_t decode(std::span<const std::uint8_t> raw, std::span<RxChar> out) noexcept;
  /// Forgets a half-received escape (e.g. after the port was reopened).
  void reset() noexcept { state_ = State::Data; }
  /// True while an escape sequence is incomplete.
  bool mid_escape() const noexcept { return state_ != State::Data; }

 private:
  enum class State : std::uint8_t { Data, SawFf, SawFf00 };
  State state_ = State::Data;
};

}  // namespace liftd::uss
