// Relevelling without remaining distance (DCP 9.2.3): VN speed message, B1 without B2, and at the
// level either B1 and B0 off together (9.2.3.1) or B1 off with B0 held until S6 = 0 and S1 = 0
// (9.2.3.2, "electric stop").
#pragma once

#include <cstdint>

#include "dcp/travel/step_context.hpp"

namespace liftd::travel {

/// State machine of one relevelling travel without remaining distance.
class RelevelTravel {
 public:
  /// States in the order of DCP figures 9-5 and 9-6.
  enum class State : std::uint8_t {
    Idle,             ///< 0000: no travel
    SpeedMessage,     ///< 1001 + VN, B4 = direction (step 1)
    Relevel,          ///< 0011: B1 + B0, no stop switch (step 2)
    ElectricStop,     ///< 0001: B1 off, B0 held until S6 = 0 and S1 = 0 (9.2.3.2 steps 3, 4)
    Coast,            ///< 0000: B1 and B0 off together (9.2.3.1 step 3); waiting for S1 = 0
    ControlledAbort,  ///< 0001: stop message, wait for S6 = 0 and S1 = 0
  };

  /// Starts a relevelling travel towards `target_mm` (used with a valid position) in `direction`.
  void begin(const TravelRequest& request, Direction direction, const CycleInput& in) noexcept;
  /// One cycle: the demand for the next frame.
  Demand step(StepContext& ctx) noexcept;
  /// Gate refused: forget the travel.
  void abort_immediate() noexcept { state_ = State::Idle; }
  /// Controlled stop.
  void request_stop(lift::Cause cause) noexcept;
  /// Whether a travel is in progress.
  bool active() const noexcept { return state_ != State::Idle; }
  /// Current state.
  State state() const noexcept { return state_; }
  /// Direction, constant for the whole travel.
  Direction direction() const noexcept { return direction_; }

  /// The level it relevels to (with a valid position).
  std::int64_t target_mm() const noexcept { return target_mm_; }

 private:
  void enter(State state, MonoTime now) noexcept;
  Demand demand(std::uint8_t message, std::uint16_t data_word) const noexcept;
  bool at_level(const StepContext& ctx) const noexcept;
  void finish(StepContext& ctx) noexcept;

  State state_ = State::Idle;
  Direction direction_ = Direction::None;
  std::int64_t target_mm_ = 0;
  MonoTime entered_{};
  MonoTime now_{};
  std::uint32_t cycles_in_state_ = 0;
  bool brake_seen_open_ = false;
  bool travel_seen_ = false;
  lift::Cause end_cause_ = lift::Cause::None;
};

}  // namespace liftd::travel
