// What every drive kind shares with the lift core and the API: which kind of drive the lift
// has, the drive state a dispatcher reads, and the drive-specific commands a kind may offer (each
// kind says which in its row of the registry, lib/kinds). Knows no protocol: each kind maps its
// own states onto these.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string_view>

#include "drive/kinds.inc"

namespace liftd::drive {

/// The drive kinds of this build (config `drive.kind`): one per folder of LIFTD_DRIVE_KINDS in the
/// top CMakeLists.txt, in its order (drive/kinds.inc is made from that list). What each kind is
/// and offers is the kind's own (lib/<kind>/, its row in the registry lib/kinds).
enum class Kind : std::uint8_t {
#define LIFTD_DRIVE_KIND_ENUMERATOR(name, wire) name,
  LIFTD_FOR_EACH_DRIVE_KIND(LIFTD_DRIVE_KIND_ENUMERATOR)
#undef LIFTD_DRIVE_KIND_ENUMERATOR
};
/// Wire names of Kind, in enum order (config `drive.kind`, status `drive.kind`).
inline constexpr std::array kKindNames = {
#define LIFTD_DRIVE_KIND_WIRE_NAME(name, wire) std::string_view(wire),
    LIFTD_FOR_EACH_DRIVE_KIND(LIFTD_DRIVE_KIND_WIRE_NAME)
#undef LIFTD_DRIVE_KIND_WIRE_NAME
};
/// The wire name of `kind` ("dcp", ...).
std::string_view to_string(Kind kind) noexcept;
/// The kind of a wire name, nullopt for an unknown one.
std::optional<Kind> parse_kind(std::string_view name) noexcept;

/// The travelling speeds a travel may ask for, by name, fastest first. It is the order in which
/// a DCP3 installation adds speeds (DCP 3.5.3.7: one speed V4, two V4 V3, ... seven V4 V3 V2 V1
/// V7 V6 V5); DCP4 drives have V4 and V3, the hydraulic unit V4, V3 and V1 (its fast speed).
inline constexpr std::array<std::string_view, 7> kTravelSpeedNames = {"V4", "V3", "V2", "V1",
                                                                      "V7", "V6", "V5"};

/// The drive as a dispatcher sees it, whatever the kind (status `drive.state`).
enum class State : std::uint8_t {
  Offline,     ///< no working link to the drive yet (or any more): nothing can move
  Ready,       ///< link up, no active fault, no travel, the drive allows one: a travel may start
  Travelling,  ///< a travel (of any kind) is running
  Fault,       ///< link up, but an active fault forbids new travels
  NotReady,    ///< link up, no fault, but the drive itself does not let a travel start now
               ///< (DCP S0 = 0, SCH001 RDY = 0, USS in local control or not ready to switch on)
};
/// "offline", "ready", "travelling", "fault", "not_ready".
std::string_view to_string(State state) noexcept;

/// The drive state from the facts every kind has. A running travel counts before a fault (a
/// fault ends a travel within the cycle, and a warning that only forbids new travels lets the
/// running one finish); a link that is not up counts before everything. `drive_allows_travel` is
/// the drive's own verdict on a travel starting now: what its controller refuses a travel for on
/// the drive's side (DCP: travel::CommandGate::drive_forbidding, SCH001:
/// HydraulicTravel::drive_forbidding, USS: LiftTravel::drive_forbidding), so that `ready` holds
/// exactly when the drive would let a travel start.
constexpr State state_of(bool link_up, bool travelling, bool any_fault,
                         bool drive_allows_travel) noexcept {
  if (!link_up) return State::Offline;
  if (travelling) return State::Travelling;
  if (any_fault) return State::Fault;
  return drive_allows_travel ? State::Ready : State::NotReady;
}

/// Commands that only some drive kinds have. The common ones (travel, stop, relevel,
/// inspection, calls, inputs) every kind offers.
enum class Capability : std::uint8_t {
  Keypad,      ///< `key`: the drive's remote keypad (DCP 5.8)
  Display,     ///< `display`: the drive's remote display (DCP 5.7)
  Power,       ///< `power`: mains / emergency power mode (DCP I6)
  Load,        ///< `load`: car load for the next travel (DCP I8)
  DriveReset,  ///< `drive_reset`: fault reset asked of the drive (DCP I2 'R')
  FastStart,   ///< `fast_start`: start while the doors close (DCP 12)
  FastStop,    ///< `fast_stop`: fast stop of a travel (DCP 13)
  Parameters,  ///< `uss_read`, `uss_write`, `uss_mirror`: the drive's parameters (USS C 4)
  kCount,
};
/// "keypad", "display", ...
std::string_view to_string(Capability capability) noexcept;

/// A set of capabilities.
class Capabilities {
 public:
  constexpr Capabilities() noexcept = default;
  /// Every capability there is.
  static constexpr Capabilities all() noexcept {
    Capabilities c;
    c.bits_ = (1U << static_cast<unsigned>(Capability::kCount)) - 1U;
    return c;
  }
  constexpr Capabilities& add(Capability capability) noexcept {
    bits_ |= 1U << static_cast<unsigned>(capability);
    return *this;
  }
  constexpr bool has(Capability capability) const noexcept {
    return (bits_ & (1U << static_cast<unsigned>(capability))) != 0;
  }
  constexpr bool operator==(const Capabilities&) const noexcept = default;

 private:
  std::uint32_t bits_ = 0;
};

}  // namespace liftd::drive
