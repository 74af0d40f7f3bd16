// DCP4 travels on remaining distance: V4'/V3' (DCP 11.1.2, 11.1.3) with start parameters (I7),
// load (I8), target extension and fast start / fast stop (DCP 12, 13); VN' relevelling (11.1.4).
#pragma once

#include <cstdint>
#include <optional>

#include "dcp/travel/step_context.hpp"

namespace liftd::travel {

/// State machine of one DCP4 travel on remaining distance.
class Dcp4Travel {
 public:
  /// States in the order of DCP figures 11-3 / 11-7 and the fast start figures of chapter 12.
  enum class State : std::uint8_t {
    Idle,             ///< 0000: no travel
    StartParameters,  ///< 0000: I7 (Vmax, Ss) on the channel, waiting for ftyp/Sg/Sv
    FastStartHold,    ///< 1001+VF, then 0101 with 0x0000: car held, brake open, doors closing
    FastStartGo,      ///< 1101 + speed: speed after fast start once the doors are locked
    Load,             ///< 0000: I8 on the channel, waiting a little for its reply
    SpeedMessage,     ///< 1001 + speed (V4, V3 or VN), B4 = direction (step 1)
    Distance,         ///< 0101 + remaining distance: B2+B0 until S6 falls at the level (2..4)
    TravelEnd,        ///< 0001: B2 withdrawn, B0 held until S1 = 0 (11.1.4 step 5)
    FastStop,         ///< 1101 + VF: fast stop ramp (DCP 13) until S6 = 0
    ControlledAbort,  ///< 0001: stop message, wait for S6 = 0 and S1 = 0 (DCP 12.2.2)
  };

  /// Starts a travel (the caller validated the request).
  void begin(const TravelRequest& request, const CycleInput& in,
             const TravelConfig& config) noexcept;
  /// One cycle: the demand for the next frame.
  Demand step(StepContext& ctx) noexcept;
  /// Gate refused: the command byte is already clear; forget the travel.
  void abort_immediate() noexcept { state_ = State::Idle; }
  /// Controlled stop (DCP 12.2.2 stop message, also for a user stop).
  void request_stop(lift::Cause cause) noexcept;
  /// DCP 13: fast stop during the travel.
  void request_fast_stop() noexcept;
  /// Target extension (DCP 9.1.5, 11.1.2 note, 7.2: 30 ms before the deceleration point).
  ExtendResult extend(std::int64_t target_mm, const CycleInput& in,
                      const TravelConfig& config) noexcept;
  /// A user stop: land at `target_mm`, a level before the current target that the car can
  /// still reach (the caller picks it with stop_distance_mm()). Pending until S5 confirms.
  ExtendResult shorten(std::int64_t target_mm, const CycleInput& in,
                       const TravelConfig& config) noexcept;
  /// The shortest remaining distance a new target may have now: the larger of I7's Sv and the
  /// live deceleration distance, plus the margin and the DCP 7.2 lead. Nullopt when unknown.
  std::optional<std::int64_t> stop_distance_mm(const CycleInput& in,
                                               const TravelConfig& config) const noexcept;
  /// Whether the car is moving under a distance travel (a stop retargets instead of stopping).
  bool moving() const noexcept { return state_ == State::Distance && brake_seen_open_; }
  /// The deceleration distance known now: data bytes, else I7's Sv.
  std::optional<std::uint32_t> decel_distance_mm(const CycleInput& in) const noexcept;

  /// The drive's I7 answer for this travel (ftyp, Sg, Sv), once it arrived.
  const std::optional<ChannelReply>& start_parameters() const noexcept { return i7_reply_; }
  /// Whether a travel is in progress.
  bool active() const noexcept { return state_ != State::Idle; }
  /// Current state.
  State state() const noexcept { return state_; }
  /// Travel kind (Dcp4Distance or Dcp4Relevel).
  TravelKind kind() const noexcept { return kind_; }
  /// Destination level.
  std::int64_t target_mm() const noexcept { return target_mm_; }
  /// Direction, constant for the whole travel (DCP 9.1.2).
  Direction direction() const noexcept { return direction_; }

 private:
  void enter(State state, MonoTime now) noexcept;
  Demand distance_demand(std::uint8_t nibble, const StepContext& ctx) const noexcept;
  Demand speed_demand(std::uint8_t nibble, dcp::Speed speed) const noexcept;
  void finish(StepContext& ctx) noexcept;
  void track_acceptance(StepContext& ctx) noexcept;

  State state_ = State::Idle;
  TravelKind kind_ = TravelKind::Dcp4Distance;
  dcp::Speed speed_ = dcp::Speed::V4;
  Direction direction_ = Direction::None;
  std::int64_t target_mm_ = 0;
  bool fast_start_ = false;
  std::optional<std::uint8_t> load_percent_;
  MonoTime entered_{};
  std::uint32_t cycles_in_state_ = 0;
  bool brake_seen_open_ = false;
  bool travel_seen_ = false;
  bool go_sent_ = false;
  bool start_reported_ = false;                        ///< Started sent (S1 with S5, DCP 4.1)
  std::optional<std::int64_t> unconfirmed_target_mm_;  ///< a change S5 has not confirmed yet
  std::uint32_t cycles_since_change_ = 0;
  lift::Cause end_cause_ = lift::Cause::None;
  std::optional<std::uint32_t> i7_decel_mm_;
  std::optional<ChannelReply> i7_reply_;
  std::optional<std::int64_t> last_position_mm_;
  MonoTime last_time_{};
  std::int64_t speed_mm_per_s_ = 0;
};

}  // namespace liftd::travel
