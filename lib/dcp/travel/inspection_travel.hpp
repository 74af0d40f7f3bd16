// Inspection and test control (recall) travels, DCP 9.2.1 and 9.2.2: button driven, VI with
// B1+B2, crawl in the end zone, V0 (B2 only) from inside an end zone, B0 off on release.
#pragma once

#include <cstdint>

#include "dcp/travel/step_context.hpp"

namespace liftd::travel {

/// State machine of inspection / recall travels (same on DCP3 and DCP4).
class InspectionTravel {
 public:
  /// States in the order of DCP figures 9-3 and 9-4.
  enum class State : std::uint8_t {
    Idle,          ///< 0000: stationary, B0 off (DCP 9.1.1)
    SpeedMessage,  ///< 1001 + VI, B4 = direction: button pressed (step 1)
    Vi,            ///< 0111: B1 + B2 + B0 at inspection speed (step 2)
    Crawl,         ///< 0101: B2 + B0 only: end zone reached (step 3) or started inside it (V0)
    Released,      ///< 0000: button released, B0 off at once (step 4); waiting for S1 = 0
  };

  /// One cycle; call every cycle while the inspection or recall switch is on, or while active().
  Demand step(StepContext& ctx) noexcept;
  /// Gate refused: forget the travel, wait for the drive to stop.
  void abort_immediate() noexcept;
  /// Whether a button travel is in progress (including waiting for S1 = 0 after release).
  bool active() const noexcept { return state_ != State::Idle; }
  /// Current state.
  State state() const noexcept { return state_; }
  /// Inspection or Recall.
  TravelKind kind() const noexcept { return kind_; }
  /// Direction of the current button travel.
  Direction direction() const noexcept { return direction_; }

 private:
  Demand demand(std::uint8_t message, std::uint16_t data_word) const noexcept;
  bool in_end_zone(const lift::Inputs& inputs) const noexcept;

  State state_ = State::Idle;
  TravelKind kind_ = TravelKind::Inspection;
  Direction direction_ = Direction::None;
  std::uint32_t cycles_in_state_ = 0;
  bool travel_seen_ = false;
  bool aborted_ = false;
  bool need_release_ = false;
};

}  // namespace liftd::travel
