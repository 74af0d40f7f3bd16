// The faults a lift can stand in, whatever its drive: each ends any travel in the safe state
// (no travel command, drive enable off) and is reported once when it comes and once when it
// goes. The names are the API's fault codes (docs/api.md "Fault codes"); each drive kind words
// the technician's explanation in its own terms (fault_text in its controller).
#pragma once

#include <cstdint>
#include <string_view>

namespace liftd::lift {

enum class FaultCode : std::uint8_t {
  LinkFault,       ///< the link to the drive is lost (DCP 7.3, the SCH001 card silent, a bus)
  DriveFault,      ///< the drive reports a general fault (DCP S3, SCH001 ERR)
  SafetyChain,     ///< safety chain open
  InputsLost,      ///< input provider silent longer than inputs.timeout_ms
  PositionLost,    ///< the position source is invalid or stale
  AdvanceWarning,  ///< the drive warns of a coming fault (DCP S2): no new travel until it clears
  kCount,
};

/// snake_case code for the API and the journal ("link_fault", ...); "internal" for kCount.
std::string_view fault_code_name(FaultCode code) noexcept;

}  // namespace liftd::lift
