// Signals from the machine that the travel logic looks at once per cycle (system.md "Inputs from
// the machine"). Plain data: the input provider fills it, the sequencers only read it.
#pragma once

#include <cstdint>

namespace liftd::lift {

/// Direction of travel of the car.
enum class Direction : std::uint8_t {
  None,  ///< stationary or unknown
  Up,    ///< towards higher levels (DCP B4 = 0)
  Down,  ///< towards lower levels (DCP B4 = 1)
};

/// The machine's inputs as the input provider last reported them.
struct Inputs {
  bool valid = false;                ///< the input provider is alive and these values are current
  bool safety_chain_closed = false;  ///< safety circuit closed end to end
  bool doors_closed = false;         ///< car and landing doors closed
  bool doors_locked = false;         ///< landing doors locked
  bool door_reversal = false;        ///< doors reopening (light curtain, door-open button)
  bool door_zone_bridge = false;     ///< door contacts bridged in the door zone (relevelling)
  bool inspection = false;           ///< inspection switch on the car roof in inspection
  bool recall = false;               ///< test control (recall) switch on
  bool button_up = false;            ///< inspection / recall "up" button pressed
  bool button_down = false;          ///< inspection / recall "down" button pressed
  bool end_zone_top = false;         ///< car inside the top end zone (inspection limited to V0)
  bool end_zone_bottom = false;      ///< car inside the bottom end zone
  bool dcp3_decel_point = false;     ///< shaft signal: fixed deceleration point of the target met
  bool dcp3_at_level = false;        ///< shaft signal: car level with the target floor
  bool operator==(const Inputs&) const = default;
};

}  // namespace liftd::lift
