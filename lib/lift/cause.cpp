#include "lift/cause.hpp"

namespace liftd::lift {

std::string_view to_string(Cause cause) noexcept {
  switch (cause) {
    case Cause::None:
      return "none";
    case Cause::LinkDown:
      return "link_down";
    case Cause::NoHandshake:
      return "no_handshake";
    case Cause::DriveNotReady:
      return "drive_not_ready";
    case Cause::AdvanceWarning:
      return "advance_warning";
    case Cause::DriveFault:
      return "drive_fault";
    case Cause::SafetyChainOpen:
      return "safety_chain_open";
    case Cause::DoorsNotLocked:
      return "doors_not_locked";
    case Cause::PositionLost:
      return "position_lost";
    case Cause::InputsLost:
      return "inputs_lost";
    case Cause::DoorReversal:
      return "door_reversal";
    case Cause::FastStartTimeout:
      return "fast_start_timeout";
    case Cause::StopRequested:
      return "stop_requested";
    case Cause::DriveDidNotStart:
      return "drive_did_not_start";
    case Cause::DriveDidNotStop:
      return "drive_did_not_stop";
    case Cause::ModeChanged:
      return "mode_changed";
    case Cause::StoppedOffLevel:
      return "stopped_off_level";
    case Cause::LevelNotReached:
      return "level_not_reached";
    case Cause::TargetRefused:
      return "target_refused";
    case Cause::ShuttingDown:
      return "shutting_down";
    case Cause::CardSilent:
      return "card_silent";
    case Cause::BusFault:
      return "bus_fault";
    case Cause::TravelTimeout:
      return "travel_timeout";
    case Cause::SpeedNotConfigured:
      return "speed_not_configured";
  }
  return "none";
}

}  // namespace liftd::lift
