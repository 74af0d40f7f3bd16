// Travel sequencing of a hydraulic lift driven through the SCH001 card, sans-I/O: which of the
// card's signals (UP DW HSP MSP SFY SP1 SP2 SP3, card document 1.4 and 3c) are on at each moment
// of a travel, a relevelling or an inspection run, given the car position, the machine's inputs
// and whether the card allows travel commands. Called every few milliseconds by the SCH001
// controller; no allocation, lock or system call.
//
// From the card's document: the meaning of every signal (1.4), SFY only while all motors are on
// and cleared when all are off (1.4), no travel command with ERR or without RDY (3d, 3e).
// From common hydraulic practice (docs/sch001.md): up by the pump (motor started star-delta
// before the valves open), down by the valve alone (motor off), fast speed until a slowdown
// distance before the level, then the slow (levelling) speed to the level, where every signal
// drops and the valve's own soft stop lands the car; relevelling by the slow speed when the car
// sinks out of the level zone (oil leakage, cooling), with the doors open where allowed; a
// motor run-time limiter ending a travel that takes too long.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string_view>

#include "common/defaults.hpp"
#include "common/mono_time.hpp"
#include "lift/cause.hpp"
#include "lift/floors.hpp"
#include "lift/inputs.hpp"
#include "lift/travel_event.hpp"
#include "sch001/defaults.hpp"
#include "sch001/protocol.hpp"

namespace liftd::sch001 {

/// Which signal makes the fast speed down: HSP when card P435 = 0, SP3 when card P453 = 1.
enum class FastDown : std::uint8_t { Hsp, Sp3 };

/// The hydraulic installation as the sequencing needs it (config `sch001.*`).
struct HydraulicConfig {
  bool has_v3 = false;                 ///< the unit has speed V3 (HSP + SP1)
  bool has_v4 = false;                 ///< the unit has speed V4 (HSP + SP2)
  FastDown fast_down = FastDown::Hsp;  ///< mirrors card P435 / P453
  /// Motor contactors on until SFY (star-delta start).
  std::uint32_t star_delta_ms = defaults::kStarDeltaMs;
  /// Fast speed up ends this far below the level, down this far above it.
  std::uint32_t slowdown_up_mm = defaults::kSlowdownUpMm;
  std::uint32_t slowdown_down_mm = defaults::kSlowdownDownMm;
  std::uint32_t slowdown_v3_mm = defaults::kSlowdownV3Mm;  ///< V3 up ends this far below
  std::uint32_t slowdown_v4_mm = defaults::kSlowdownV4Mm;  ///< V4 up ends this far below
  /// The slow approach stops within this of the level.
  std::uint32_t stop_tolerance_mm = defaults::kStopToleranceMm;
  /// Relevelling starts when the car is this far off.
  std::uint32_t relevel_start_mm = defaults::kRelevelStartMm;
  /// Motor run-time limiter: a travel longer than this ends.
  std::uint32_t max_travel_ms = defaults::kMaxTravelMs;
  bool relevel_doors_open = true;  ///< relevel with the doors open (door zone bridged)
};

/// The speed a travel asks for (config and API names V1 fast, V3, V4).
enum class Speed : std::uint8_t { Fast, V3, V4 };

/// What runs.
using lift::TravelKind;

/// Where a travel is.
enum class Phase : std::uint8_t {
  Idle,
  MotorStart,  ///< up: motor contactors on, waiting for the star-delta start before SFY
  Fast,        ///< at the travel's speed
  Slow,        ///< slow approach after the slowdown point
};
/// "idle", "motor_start", "fast", "slow".
std::string_view to_string(Phase phase) noexcept;

/// The facts of one tick.
struct TickInput {
  MonoTime now{};
  std::optional<std::int64_t> position_mm;  ///< nullopt: unknown
  lift::Inputs inputs{};
  bool card_allows_travel = false;  ///< CardLink::travel_allowed()
  bool card_error = false;          ///< the card's ERR
  bool card_silent = false;         ///< the card timed out
  bool bus_ok = true;               ///< the CAN endpoint works
};

/// What goes out after a tick.
struct TickOutput {
  CommandBits bits;       ///< the card's signals
  bool motor_on = false;  ///< motor contactor output (up travels and up relevelling)
  std::size_t current_floor = 0;
  std::size_t destination_floor = 0;
};

/// Something that happened, drained by the controller.
using TravelEvent = lift::BasicTravelEvent<TravelKind>;

/// The sequencer. Floors are the installation's; the car's current floor is the last one it
/// stopped at (3c: "updated each time the stop contact is reached").
class HydraulicTravel : public lift::RunState<Phase> {
 public:
  explicit HydraulicTravel(const HydraulicConfig& config) noexcept : config_(config) {}

  /// What a run of `kind` is called (status travel.state, travel events): a travel to a floor is
  /// "hydraulic" (lift::travel_kind_name).
  static constexpr std::string_view kind_name(TravelKind kind) noexcept {
    return lift::travel_kind_name(kind, "hydraulic");
  }

  /// Starts a travel to `floor` at `speed` (V3/V4 fall back to fast where the unit lacks them).
  /// lift::Cause::None when it started; else why not (conditions of `in`).
  lift::Cause start_travel(const lift::FloorTable& floors, std::size_t floor, Speed speed,
                           const TickInput& in) noexcept;
  /// Starts relevelling to `floor` (slow speed, doors may be open where allowed).
  lift::Cause start_relevel(const lift::FloorTable& floors, std::size_t floor,
                            const TickInput& in) noexcept;
  /// Starts a leg of the learning travel to `target_mm` going `direction`, ended by position (no
  /// floor of the table, no level-zone stop). Up at the slow (levelling) speed all the way, the
  /// pump started as for a travel; down by the valve at the fast speed until slowdown_down_mm
  /// before the target, then slow. The run-time limiter allows a slow run of the leg
  /// (lift::learn_leg_limit_ms over max_travel_ms). Every gate of a travel applies.
  lift::Cause start_learning(std::int64_t target_mm, lift::Direction direction,
                             const TickInput& in) noexcept;
  /// A learning leg going up ends at `target_mm` instead (the run-out after the last zone);
  /// false when no such leg runs.
  bool end_learning_at(std::int64_t target_mm) noexcept;
  /// Inspection: hold-to-run `direction` (None: stand still). The run ends when released.
  lift::Cause inspect(lift::Direction direction, const TickInput& in) noexcept;
  /// Stop at the next floor ahead the car can still reach by the slow approach; a car already
  /// slowing keeps its floor; with no floor ahead reachable, every signal drops now. A learning
  /// leg drops every signal now (the valve's soft stop lands the car).
  /// Returns the floor the car will stop at (nullopt: stopped at once between floors).
  std::optional<std::size_t> stop(const lift::FloorTable& floors, const TickInput& in) noexcept;
  /// The floor a travel between floors would land at if stop() were called now (the next
  /// possible stop): the first floor ahead beyond the slowdown distance at speed, the target once
  /// slowing; nullopt while no such travel moves (not yet started, no position, other kinds).
  std::optional<std::size_t> landing_floor(const lift::FloorTable& floors,
                                           const TickInput& in) const noexcept;
  /// Ends whatever runs at once, with `cause` (reported once).
  void abort(lift::Cause cause, MonoTime now) noexcept;

  /// One step: checks the conditions, moves through the phases, returns the signals.
  TickOutput tick(const lift::FloorTable& floors, const TickInput& in) noexcept;

  /// The condition of `in` that forbids moving now, for a run of `kind`, or None: the drive's
  /// (drive_forbidding()), then the machine's.
  lift::Cause forbidding(TravelKind kind, const TickInput& in) const noexcept;
  /// The card's side of forbidding(): the bus, a silent card, ERR, RDY (3d, 3e, 3f). Status
  /// `drive.state` is `ready` only when it is None.
  lift::Cause drive_forbidding(const TickInput& in) const noexcept;

  /// Something runs: no new run may start.
  bool busy() const noexcept { return kind_ != TravelKind::None; }
  const HydraulicConfig& config() const noexcept { return config_; }

 private:
  lift::Cause begin(TravelKind kind, const lift::FloorTable& floors, std::size_t floor,
                    const TickInput& in) noexcept;
  lift::Cause begin_run(TravelKind kind, std::int64_t target_mm, lift::Direction direction,
                        const TickInput& in) noexcept;
  void finish(MonoTime now) noexcept;
  void end(TravelEvent::Type type, lift::Cause cause, MonoTime now) noexcept;
  void push(const TravelEvent& event) noexcept { events_.push(event); }
  std::uint32_t slowdown_mm() const noexcept;
  bool slowdown_reached(std::int64_t remaining_mm) const noexcept;
  void measure_speed(const TickInput& in) noexcept;
  CommandBits signals() const noexcept;

  HydraulicConfig config_;
  Speed speed_ = Speed::Fast;
  std::uint32_t limit_ms_ = 0;  ///< the run-time limiter of this run
  MonoTime motor_on_at_{};
  bool motor_on_ = false;
  /// Where the car was at the last tick, and when: the distance it covers in one status period
  /// (3b) is measured from it.
  std::optional<std::int64_t> last_position_mm_;
  MonoTime last_tick_{};
  std::int64_t period_travel_mm_ = 0;  ///< the car's distance per status period, 0 when unknown
};

}  // namespace liftd::sch001
