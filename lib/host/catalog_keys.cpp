// The switches name every enumerator without a default, so a new fault code or cause does not
// build (-Werror=switch) until it has its catalog decision here.
#include "host/catalog_keys.hpp"

namespace liftd::daemon {

std::optional<log::Catalogued> fault_catalog_key(lift::FaultCode code, bool raised) noexcept {
  using log::Catalogued;
  if (!raised) {
    if (code == lift::FaultCode::LinkFault) return Catalogued::LinkRestored;
    return std::nullopt;
  }
  switch (code) {
    case lift::FaultCode::LinkFault:
      return Catalogued::LinkLost;
    case lift::FaultCode::DriveFault:
      return Catalogued::DriveFault;
    case lift::FaultCode::SafetyChain:
      return Catalogued::SafetyChainOpen;
    case lift::FaultCode::InputsLost:
      return Catalogued::InputsLost;
    case lift::FaultCode::PositionLost:
      return Catalogued::PositionLost;
    case lift::FaultCode::AdvanceWarning:
      return Catalogued::DriveAdvanceWarning;
    case lift::FaultCode::kCount:
      break;
  }
  return std::nullopt;
}

log::Catalogued abort_catalog_key(lift::Cause cause) noexcept {
  using lift::Cause;
  switch (cause) {
    case Cause::SafetyChainOpen:
      return log::Catalogued::SafetyChainOpenedMidTravel;
    case Cause::None:
    case Cause::LinkDown:
    case Cause::NoHandshake:
    case Cause::DriveNotReady:
    case Cause::AdvanceWarning:
    case Cause::DriveFault:
    case Cause::DoorsNotLocked:
    case Cause::PositionLost:
    case Cause::InputsLost:
    case Cause::DoorReversal:
    case Cause::FastStartTimeout:
    case Cause::StopRequested:
    case Cause::DriveDidNotStart:
    case Cause::DriveDidNotStop:
    case Cause::ModeChanged:
    case Cause::StoppedOffLevel:
    case Cause::LevelNotReached:
    case Cause::TargetRefused:
    case Cause::ShuttingDown:
    case Cause::CardSilent:
    case Cause::BusFault:
    case Cause::TravelTimeout:
    case Cause::SpeedNotConfigured:
      break;
  }
  return log::Catalogued::TravelAborted;
}

}  // namespace liftd::daemon
