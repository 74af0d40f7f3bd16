// The command gate's rules that belong to the machine, not to the drive: every drive kind's
// gate asks them in the same order after its own link and drive checks (DCP: lib/dcp/travel/gate,
// SCH001: lib/sch001/hydraulic_travel, USS: lib/uss/drive/lift_travel). No travel signal while the
// inputs are stale, the safety chain is open, the doors are not locked (or, where a relevelling
// allows it, bridged in the door zone), or a travel that needs the position lacks it.
#pragma once

#include <cstdint>

#include "lift/cause.hpp"
#include "lift/inputs.hpp"

namespace liftd::lift {

/// What a kind of travel needs of the machine.
struct MachineNeeds {
  bool doors_locked = true;          ///< false for inspection / recall and a fast start's hold
  bool door_bridge_allowed = false;  ///< relevelling: a bridged door zone stands for locked doors
  bool position = false;             ///< the travel steers by the absolute position
};

/// The first machine condition that forbids motion.
enum class MachineRefusal : std::uint8_t {
  None,
  InputsLost,       ///< the input provider is silent (inputs.timeout_ms)
  SafetyChainOpen,  ///< the safety chain is open
  DoorsNotLocked,   ///< doors neither locked nor (where allowed) bridged
  PositionLost,     ///< the position source is invalid or stale
};

/// The machine's verdict for a travel with `needs`.
constexpr MachineRefusal machine_refusal(const Inputs& in, bool position_known,
                                         const MachineNeeds& needs) noexcept {
  if (!in.valid) return MachineRefusal::InputsLost;
  if (!in.safety_chain_closed) return MachineRefusal::SafetyChainOpen;
  if (needs.doors_locked && !in.doors_locked &&
      !(needs.door_bridge_allowed && in.door_zone_bridge)) {
    return MachineRefusal::DoorsNotLocked;
  }
  if (needs.position && !position_known) return MachineRefusal::PositionLost;
  return MachineRefusal::None;
}

/// What a run of the SCH001 and USS travel sequencers needs of the machine, by its `kind` (their
/// TravelKind: Travel, Relevel, Inspection): a travel or relevelling locked doors (a relevelling
/// also a bridged door zone where `relevel_doors_open`) and, when the travel steers by
/// position, the position; an inspection run neither (the safety chain holds the door contacts).
template <typename Kind>
constexpr MachineNeeds run_needs(Kind kind, bool relevel_doors_open,
                                 bool steers_by_position) noexcept {
  MachineNeeds needs;
  needs.doors_locked = kind == Kind::Travel || kind == Kind::Relevel;
  needs.door_bridge_allowed = kind == Kind::Relevel && relevel_doors_open;
  needs.position = needs.doors_locked && steers_by_position;
  return needs;
}

/// A machine refusal as the Cause a travel reports.
constexpr Cause refusal_cause(MachineRefusal refusal) noexcept {
  switch (refusal) {
    case MachineRefusal::InputsLost:
      return Cause::InputsLost;
    case MachineRefusal::SafetyChainOpen:
      return Cause::SafetyChainOpen;
    case MachineRefusal::DoorsNotLocked:
      return Cause::DoorsNotLocked;
    case MachineRefusal::PositionLost:
      return Cause::PositionLost;
    case MachineRefusal::None:
      break;
  }
  return Cause::None;
}

}  // namespace liftd::lift
