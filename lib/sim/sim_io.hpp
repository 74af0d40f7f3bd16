// The machine's inputs as a simulated lift provides them (docs/architecture.md "Machine inputs"):
// safety chain, a simple door model, inspection/recall switches and buttons and end zones
// (not the shaft signals: the API adds those). Pure: time comes in as an argument, no thread,
// clock or I/O.
//
// Door model: the doors move between closed (0) and fully open (1) at a configurable speed.
// Closed means fully closed; the landing doors lock `lock_ms` after they closed and unlock as
// soon as they start to open. Doors never open while the car moves: an open request made then
// is held and carried out on arrival (when the car stops).
#pragma once

#include <cstdint>

#include "common/mono_time.hpp"
#include "lift/inputs.hpp"

namespace liftd::sim {

/// Timings and options of the simulated machine.
struct SimIoConfig {
  std::uint32_t close_ms = 2000;     ///< fully open to closed
  std::uint32_t open_ms = 2000;      ///< closed to fully open
  std::uint32_t lock_ms = 300;       ///< closed to locked
  std::uint32_t reversal_ms = 500;   ///< how long an injected reversal signal stays on
  bool doors_open_at_start = false;  ///< false: closed and locked at power-on
  bool open_on_arrival = false;      ///< open the doors whenever the car stops after moving
  /// Shaft limits for the end zones (mm); end zones are off while top <= bottom.
  double shaft_bottom_mm = 0.0;
  double shaft_top_mm = 0.0;   ///< position of the top level
  double end_zone_mm = 300.0;  ///< length of each end zone from its limit
};

/// What the doors are doing.
enum class DoorState : std::uint8_t {
  Locked,   ///< closed and locked (ready to travel)
  Closed,   ///< closed, lock not yet engaged
  Opening,  ///< moving open (unlocked)
  Open,     ///< fully open
  Closing,  ///< moving closed
};
/// "locked", "closed", ...
const char* to_string(DoorState state) noexcept;

/// The simulated I/O board.
class SimulatedIo {
 public:
  /// The machine at power-on at `now`: safety chain closed, doors per config, switches off.
  explicit SimulatedIo(const SimIoConfig& config = {}, MonoTime now = MonoTime{}) noexcept;

  /// Moves the doors and ends timed signals up to `now` (call every few ms; idempotent).
  void advance(MonoTime now) noexcept;
  /// The inputs as of the last advance(), ready for the travel controller.
  lift::Inputs inputs() const noexcept;
  /// advance(now), then inputs().
  lift::Inputs inputs(MonoTime now) noexcept {
    advance(now);
    return inputs();
  }

  // --- doors ---
  /// Starts closing the doors (ignored while the door reversal is held).
  void close_doors(MonoTime now) noexcept;
  /// Starts opening the doors; while the car moves the request waits for arrival.
  void open_doors(MonoTime now) noexcept;
  /// Door state.
  DoorState door_state() const noexcept { return door_state_; }
  /// How far open the doors are, 0 (closed) .. 1 (fully open).
  double door_opening() const noexcept { return opening_; }
  /// True while an open request waits for the car to stop.
  bool open_pending() const noexcept { return open_pending_; }

  // --- the car (from the drive simulator) ---
  /// Tells the model whether the car moves and where it is. On the moving -> stopped edge a
  /// pending (or, with open_on_arrival, automatic) door opening starts.
  void set_car(bool moving, double position_mm, MonoTime now) noexcept;

  // --- injection and switches ---
  /// A door reversal (light curtain, door-open button): closing doors reopen and the reversal
  /// input shows for reversal_ms.
  void inject_door_reversal(MonoTime now) noexcept;
  /// Holds the door reversal on (obstruction) or releases it; closing is refused while held.
  void set_door_obstructed(bool on, MonoTime now) noexcept;
  /// Opens (true) or closes the safety chain.
  void set_safety_chain_open(bool open) noexcept { chain_open_ = open; }
  /// Inspection switch on the car roof.
  void set_inspection(bool on) noexcept { inputs_.inspection = on; }
  /// Test control (recall) switch.
  void set_recall(bool on) noexcept { inputs_.recall = on; }
  /// Inspection / recall direction buttons.
  void set_buttons(bool up, bool down) noexcept {
    inputs_.button_up = up;
    inputs_.button_down = down;
  }
  /// Door contacts bridged in the door zone (relevelling with open doors).
  void set_door_zone_bridge(bool on) noexcept { inputs_.door_zone_bridge = on; }
  /// The input provider alive (true) or failed (inputs().valid = false).
  void set_valid(bool valid) noexcept { inputs_.valid = valid; }

 private:
  void set_door_state(DoorState state, MonoTime now) noexcept;
  void start_opening(MonoTime now) noexcept;

  SimIoConfig config_;
  MonoTime now_{};
  lift::Inputs inputs_{};
  DoorState door_state_ = DoorState::Locked;
  MonoTime door_since_{};  // when door_state_ was entered
  double opening_ = 0.0;
  bool open_pending_ = false;
  bool obstructed_ = false;
  bool chain_open_ = false;
  bool car_moving_ = false;
  double car_position_mm_ = 0.0;
  bool car_moved_ = false;  // moved since the doors last opened (for open_on_arrival)
  MonoTime reversal_until_{};
};

}  // namespace liftd::sim
