// The one place every command byte passes through before it goes on the wire (DCP 9.1).
#pragma once

#include <cstdint>

#include "dcp/travel/types.hpp"

namespace liftd::travel {

/// What a travel state needs besides the common conditions.
struct GateProfile {
  bool doors_locked_required = true;  ///< false for inspection / recall and the fast start hold
  bool door_bridge_allowed = false;   ///< relevelling: bridged door zone replaces doors locked
  bool position_required = false;     ///< DCP4 travels on remaining distance
};

/// A sequencer's wish for the next frame.
struct Demand {
  std::uint8_t command = 0;     ///< B0..B6
  std::uint16_t data_word = 0;  ///< speed bits or remaining distance
  GateProfile profile{};        ///< conditions of the state that asked
};

/// The gate's verdict for one cycle.
struct GateResult {
  CycleOutput output{};                       ///< what may go on the wire
  lift::Cause violation = lift::Cause::None;  ///< set when a demand for B0/B1/B2 was refused
};

/// Refuses B0/B1/B2 unless every condition holds: link up, handshake done, inputs valid, S3 = 0,
/// safety chain closed, doors locked (profile exceptions), position valid (profile), and at the
/// rising edge of B0 also S0 = 1 and S2 = 0 (DCP 9.1.3, 9.1.5, 9.1.6). A refused frame goes out
/// as an all-clear command byte with a zero data word. The brake output follows S6 (DCP 9.1.7).
class CommandGate {
 public:
  /// Filters one demand.
  GateResult apply(const Demand& demand, const CycleInput& in) noexcept;
  /// The first condition that forbids B0/B1/B2 now, or None. `starting` adds S0 and S2.
  static lift::Cause forbidding(const CycleInput& in, const GateProfile& profile,
                                bool starting) noexcept;
  /// The drive's side of forbidding(): link up, handshake done, S3 = 0 and, when `starting`,
  /// S0 = 1 and S2 = 0 (DCP 7.3, 5.12.2, 9.1.6, 9.1.3, 9.1.5). With `starting` it is the drive's
  /// verdict on a new travel that status `drive.state` reports (`ready` only when None).
  static lift::Cause drive_forbidding(const CycleInput& in, bool starting) noexcept;
  /// Whether the last frame let out had B0 set.
  bool enable_on() const noexcept { return enable_on_; }

 private:
  bool enable_on_ = false;
};

}  // namespace liftd::travel
