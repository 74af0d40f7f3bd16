// Signals from the machine that the travel logic looks at once per cycle (docs/architecture.md
// "Machine inputs"). Plain data: the input provider fills it, the sequencers only read it.
#pragma once

#include <array>
#include <cstddef>
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
  bool level_zone = false;           ///< shaft signal: car inside the stopping zone of a level
  bool relevel_up = false;  ///< shaft signal: car below its level beyond the relevelling tolerance
  bool relevel_down =
      false;  ///< shaft signal: car above its level beyond the relevelling tolerance
  /// Shaft signals: the fixed deceleration point of speed Vn met (index n - 1 for V1..V7), one
  /// set for a car travelling up and one for down. A travel at Vn looks at its own point only.
  std::array<bool, 7> decel_up{};
  std::array<bool, 7> decel_down{};

  /// The deceleration point of speed V`speed_number` (1..7) for `direction`; false for any
  /// other speed or no direction.
  bool decel_point(int speed_number, Direction direction) const noexcept {
    if (speed_number < 1 || speed_number > static_cast<int>(decel_up.size())) return false;
    const auto i = static_cast<std::size_t>(speed_number - 1);
    if (direction == Direction::Up) return decel_up[i];
    if (direction == Direction::Down) return decel_down[i];
    return false;
  }
  /// The relevelling signal that asks for `direction` (relevel_up for Up, relevel_down for Down).
  bool relevel_towards(Direction direction) const noexcept {
    return direction == Direction::Up ? relevel_up : direction == Direction::Down && relevel_down;
  }
  /// The inspection or the recall (test control) switch is on: the car moves only while a
  /// button is held, and no normal travel runs (DCP 9.1.1, 9.2.1, 9.2.2; every drive kind).
  bool button_mode() const noexcept { return inspection || recall; }
  bool operator==(const Inputs&) const = default;
};

}  // namespace liftd::lift
