#include "lift/faults.hpp"

namespace liftd::lift {

std::string_view fault_code_name(FaultCode code) noexcept {
  switch (code) {
    case FaultCode::LinkFault:
      return "link_fault";
    case FaultCode::DriveFault:
      return "drive_fault";
    case FaultCode::SafetyChain:
      return "safety_chain_open";
    case FaultCode::InputsLost:
      return "inputs_lost";
    case FaultCode::PositionLost:
      return "position_lost";
    case FaultCode::AdvanceWarning:
      return "advance_warning";
    case FaultCode::kCount:
      break;
  }
  return "internal";
}

}  // namespace liftd::lift
