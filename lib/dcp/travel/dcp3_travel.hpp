// DCP3 travels: speed travels with a fixed deceleration distance SVx (DCP 10.1, 10.2), crawl
// travel with V0 (10.3), both optionally after a fast start (DCP 12), and fast stop (DCP 13).
// Also used in DCP4 for travels without remaining distance (DCP 11 introduction).
#pragma once

#include <cstdint>

#include "dcp/travel/step_context.hpp"

namespace liftd::travel {

/// State machine of one DCP3 speed or crawl travel.
class Dcp3Travel {
 public:
  /// States in the order of DCP figures 10-1 to 10-3 and the fast start figures of chapter 12.
  enum class State : std::uint8_t {
    Idle,             ///< 0000: no travel
    FastStartHold,    ///< 1001 + VF every cycle: car held with open brake, doors closing
    FastStartGo,      ///< 1111 + speed: speed after fast start once the doors are locked
    SpeedMessage,     ///< 1001 + speed, B4 = direction (step 1)
    Travel,           ///< 0111: B1 + B2 + B0 (step 2; B2 set with B1, DCP 8.2 "(2b)")
    Creep,            ///< 0101: B1 cleared at the deceleration point, B2 positions at crawl (3, 4)
    TravelEnd,        ///< 0001: B2 cleared at the level, B0 until S6 = 0 and S1 = 0 (step 5)
    FastStop,         ///< 1111 + VF: fast stop ramp (DCP 13) until S6 = 0
    ControlledAbort,  ///< 0001: stop message, wait for S6 = 0 and S1 = 0 (DCP 12.2.2)
  };

  /// Starts a travel (the caller validated the request and resolved the direction).
  void begin(const TravelRequest& request, Direction direction, const CycleInput& in) noexcept;
  /// One cycle: the demand for the next frame.
  Demand step(StepContext& ctx) noexcept;
  /// Gate refused: forget the travel.
  void abort_immediate() noexcept { state_ = State::Idle; }
  /// Controlled stop (stop message).
  void request_stop(lift::Cause cause) noexcept;
  /// DCP 13: fast stop during the travel.
  void request_fast_stop() noexcept;
  /// A user stop with a known position: crawl from `target_mm`'s deceleration point SVx on
  /// (DCP 10.1.1 step 3). False when the car is already past its deceleration point.
  bool stop_at(std::int64_t target_mm) noexcept;
  /// A crawl travel (V0) by position ends at `target_mm` instead: B1 and B2 withdrawn once the
  /// car is the stop lead before it (DCP 10.3 step 3). False for any other travel or state.
  bool end_crawl_at(std::int64_t target_mm) noexcept;
  /// Destination level.
  std::int64_t target_mm() const noexcept { return target_mm_; }
  /// The speed of the running travel.
  dcp::Speed speed() const noexcept { return speed_; }

  /// Whether a travel is in progress.
  bool active() const noexcept { return state_ != State::Idle; }
  /// Current state.
  State state() const noexcept { return state_; }
  /// Dcp3Speed or Dcp3Crawl.
  TravelKind kind() const noexcept { return kind_; }
  /// Direction, constant for the whole travel.
  Direction direction() const noexcept { return direction_; }

 private:
  void enter(State state, MonoTime now) noexcept;
  Demand demand(std::uint8_t message, std::uint16_t data_word) const noexcept;
  bool decel_point(const StepContext& ctx) const noexcept;
  bool at_level(const StepContext& ctx) const noexcept;
  std::uint32_t crawl_timeout_ms(const TravelConfig& config) const noexcept {
    return crawl_timeout_ms_ != 0 ? crawl_timeout_ms_ : config.crawl_timeout_ms;
  }
  void finish(StepContext& ctx) noexcept;

  State state_ = State::Idle;
  TravelKind kind_ = TravelKind::Dcp3Speed;
  dcp::Speed speed_ = dcp::Speed::V4;
  Direction direction_ = Direction::None;
  std::int64_t target_mm_ = 0;
  bool fast_start_ = false;
  bool by_position_ = false;
  std::uint32_t crawl_timeout_ms_ = 0;
  bool go_sent_ = false;
  bool brake_seen_open_ = false;
  bool travel_seen_ = false;
  lift::Cause end_cause_ = lift::Cause::None;
  MonoTime entered_{};
  MonoTime now_{};
  std::uint32_t cycles_in_state_ = 0;
  dcp::Protocol protocol_ = dcp::Protocol::Dcp3;
};

}  // namespace liftd::travel
