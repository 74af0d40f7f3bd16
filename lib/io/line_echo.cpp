#include "io/line_echo.hpp"

namespace liftd::io {

std::string_view to_string(EchoMode mode) noexcept {
  switch (mode) {
    case EchoMode::Auto:
      return "auto";
    case EchoMode::On:
      return "on";
    case EchoMode::Off:
      return "off";
  }
  return "auto";
}

std::string_view to_string(EchoState state) noexcept {
  switch (state) {
    case EchoState::Unknown:
      return "unknown";
    case EchoState::Present:
      return "present";
    case EchoState::Absent:
      return "absent";
  }
  return "unknown";
}

}  // namespace liftd::io
