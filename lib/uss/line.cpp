#include "uss/line.hpp"

namespace liftd::uss {
namespace {

constexpr std::uint8_t kMark = 0xFF;  // termios PARMRK: escape introducer \377
constexpr std::uint8_t kZero = 0x00;  // \377 \0 c: c with an error; \377 \0 \0: break

}  // namespace

std::string_view to_string(LineError error) noexcept {
  switch (error) {
    case LineError::None:
      return "none";
    case LineError::Parity:
      return "parity";
    case LineError::Framing:
      return "framing";
    case LineError::Overrun:
      return "overrun";
    case LineError::Break:
      return "break";
  }
  return "?";
}

std::size_t ParmrkDecoder::decode(std::span<const std::uint8_t> raw,
                                  std::span<RxChar> out) noexcept {
  std::size_t n = 0;
  for (std::uint8_t b : raw) {
    if (n >= out.size()) break;  // cannot happen with out.size() >= raw.size()
    switch (state_) {
      case State::Data:
        if (b == kMark) {
          state_ = State::SawFf;
        } else {
          out[n++] = RxChar{b, LineError::None};
        }
        break;
      case State::SawFf:
        if (b == kMark) {
          out[n++] = RxChar{kMark, LineError::None};
          state_ = State::Data;
        } else if (b == kZero) {
          state_ = State::SawFf00;
        } else {
          out[n++] = RxChar{b, LineError::Parity};  // malformed escape: unreliable data
          state_ = State::Data;
        }
        break;
      case State::SawFf00:
        out[n++] = b == kZero ? RxChar{0, LineError::Break} : RxChar{b, LineError::Parity};
        state_ = State::Data;
        break;
    }
  }
  return n;
}

}  // namespace liftd::uss
