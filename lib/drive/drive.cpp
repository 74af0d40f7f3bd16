#include "drive/drive.hpp"

#include <algorithm>

namespace liftd::drive {

std::string_view to_string(Kind kind) noexcept {
  return kKindNames[static_cast<std::size_t>(kind)];
}

std::optional<Kind> parse_kind(std::string_view name) noexcept {
  const auto it = std::find(kKindNames.begin(), kKindNames.end(), name);
  if (it == kKindNames.end()) return std::nullopt;
  return static_cast<Kind>(it - kKindNames.begin());
}

std::string_view to_string(State state) noexcept {
  switch (state) {
    case State::Offline:
      return "offline";
    case State::Ready:
      return "ready";
    case State::Travelling:
      return "travelling";
    case State::Fault:
      return "fault";
    case State::NotReady:
      return "not_ready";
  }
  return "offline";
}

std::string_view to_string(Capability capability) noexcept {
  switch (capability) {
    case Capability::Keypad:
      return "keypad";
    case Capability::Display:
      return "display";
    case Capability::Power:
      return "power";
    case Capability::Load:
      return "load";
    case Capability::DriveReset:
      return "drive_reset";
    case Capability::FastStart:
      return "fast_start";
    case Capability::FastStop:
      return "fast_stop";
    case Capability::Parameters:
      return "parameters";
    case Capability::kCount:
      break;
  }
  return "unknown";
}

}  // namespace liftd::drive
