#include "sch001/hydraulic_travel.hpp"

#include <chrono>
#include <cstdlib>

#include "lift/gate.hpp"
#include "lift/learning_travel.hpp"

namespace liftd::sch001 {
namespace {

using std::chrono::milliseconds;

/// The shaft's deceleration point that belongs to a speed: its API name V1 (fast), V3 or V4.
int speed_number(Speed speed) noexcept {
  switch (speed) {
    case Speed::V3:
      return 3;
    case Speed::V4:
      return 4;
    case Speed::Fast:
      break;
  }
  return 1;
}

}  // namespace

std::string_view to_string(Phase phase) noexcept {
  switch (phase) {
    case Phase::Idle:
      return "idle";
    case Phase::MotorStart:
      return "motor_start";
    case Phase::Fast:
      return "fast";
    case Phase::Slow:
      return "slow";
  }
  return "idle";
}

lift::Cause HydraulicTravel::drive_forbidding(const TickInput& in) const noexcept {
  if (!in.bus_ok) return lift::Cause::BusFault;
  if (in.card_silent) return lift::Cause::CardSilent;
  if (in.card_error) return lift::Cause::DriveFault;
  if (!in.card_allows_travel) return lift::Cause::DriveNotReady;  // no status yet, or RDY = 0 (3e)
  return lift::Cause::None;
}

lift::Cause HydraulicTravel::forbidding(TravelKind kind, const TickInput& in) const noexcept {
  if (const lift::Cause why = drive_forbidding(in); why != lift::Cause::None) return why;
  // The machine's rules, common to every drive kind (lib/lift/gate.hpp). Inspection: the
  // safety chain holds the door contacts.
  // A learning leg needs what a travel needs: locked doors and the position.
  const lift::MachineNeeds needs =
      lift::run_needs(kind == TravelKind::Learn ? TravelKind::Travel : kind,
                      config_.relevel_doors_open, /*steers_by_position=*/true);
  return lift::refusal_cause(lift::machine_refusal(in.inputs, in.position_mm.has_value(), needs));
}

lift::Cause HydraulicTravel::begin(TravelKind kind, const lift::FloorTable& floors,
                                   std::size_t floor, const TickInput& in) noexcept {
  if (const lift::Cause why = forbidding(kind, in); why != lift::Cause::None) return why;
  const std::int64_t level = floors.level_mm(floor);
  target_ = floor;
  return begin_run(kind, level,
                   level >= *in.position_mm ? lift::Direction::Up : lift::Direction::Down, in);
}

lift::Cause HydraulicTravel::begin_run(TravelKind kind, std::int64_t target_mm,
                                       lift::Direction direction, const TickInput& in) noexcept {
  kind_ = kind;
  target_mm_ = target_mm;
  direction_ = direction;
  started_at_ = in.now;
  limit_ms_ = config_.max_travel_ms;
  const bool up = direction_ == lift::Direction::Up;
  motor_on_ = up;  // up by the pump, down by the valve alone
  motor_on_at_ = in.now;
  phase_ = up ? Phase::MotorStart : (kind == TravelKind::Relevel ? Phase::Slow : Phase::Fast);
  const std::size_t floor = kind == TravelKind::Learn ? current_floor_ : target_;
  TravelEvent started{TravelEvent::Type::Started, kind_, direction_, floor,
                      lift::Cause::None,          in.now};
  if (kind == TravelKind::Travel || kind == TravelKind::Relevel) started.target = target_;
  push(started);
  return lift::Cause::None;
}

lift::Cause HydraulicTravel::start_learning(std::int64_t target_mm, lift::Direction direction,
                                            const TickInput& in) noexcept {
  if (direction == lift::Direction::None) return lift::Cause::PositionLost;
  if (const lift::Cause why = forbidding(TravelKind::Learn, in); why != lift::Cause::None) {
    return why;
  }
  speed_ = Speed::Fast;  // down: the ordinary fast speed before the slow one
  const lift::Cause started = begin_run(TravelKind::Learn, target_mm, direction, in);
  // The limiter must let a slow run cover the whole leg.
  limit_ms_ = lift::learn_leg_limit_ms(config_.max_travel_ms, target_mm - *in.position_mm);
  return started;
}

bool HydraulicTravel::end_learning_at(std::int64_t target_mm) noexcept {
  if (kind_ != TravelKind::Learn || direction_ != lift::Direction::Up) return false;
  target_mm_ = target_mm;
  return true;
}

lift::Cause HydraulicTravel::start_travel(const lift::FloorTable& floors, std::size_t floor,
                                          Speed speed, const TickInput& in) noexcept {
  // Speeds the unit lacks fall back to the next lower one it has.
  if (speed == Speed::V4 && !config_.has_v4) speed = Speed::V3;
  if (speed == Speed::V3 && !config_.has_v3) speed = Speed::Fast;
  speed_ = speed;
  return begin(TravelKind::Travel, floors, floor, in);
}

lift::Cause HydraulicTravel::start_relevel(const lift::FloorTable& floors, std::size_t floor,
                                           const TickInput& in) noexcept {
  speed_ = Speed::Fast;
  return begin(TravelKind::Relevel, floors, floor, in);
}

lift::Cause HydraulicTravel::inspect(lift::Direction direction, const TickInput& in) noexcept {
  if (direction == lift::Direction::None) {
    if (kind_ == TravelKind::Inspection) {
      end(TravelEvent::Type::Finished, lift::Cause::None, in.now);
    }
    return lift::Cause::None;
  }
  if (kind_ == TravelKind::Inspection && direction == direction_) return lift::Cause::None;
  if (kind_ == TravelKind::Inspection) end(TravelEvent::Type::Finished, lift::Cause::None, in.now);
  if (const lift::Cause why = forbidding(TravelKind::Inspection, in); why != lift::Cause::None) {
    return why;
  }
  kind_ = TravelKind::Inspection;
  direction_ = direction;
  started_at_ = in.now;
  limit_ms_ = config_.max_travel_ms;
  motor_on_ = direction == lift::Direction::Up;
  motor_on_at_ = in.now;
  phase_ = motor_on_ ? Phase::MotorStart : Phase::Slow;
  push({TravelEvent::Type::Started, kind_, direction_, current_floor_, lift::Cause::None, in.now});
  return lift::Cause::None;
}

std::optional<std::size_t> HydraulicTravel::stop(const lift::FloorTable& floors,
                                                 const TickInput& in) noexcept {
  switch (kind_) {
    case TravelKind::None:
      return std::nullopt;
    case TravelKind::Inspection:
      end(TravelEvent::Type::Finished, lift::Cause::None, in.now);
      return std::nullopt;
    case TravelKind::Relevel:
      return target_;  // a few millimetres at the slow speed: let it land
    case TravelKind::Learn:
      // No floor to land at: every signal drops, the valve's soft stop ends the run.
      end(TravelEvent::Type::Aborted, lift::Cause::StopRequested, in.now);
      return std::nullopt;
    case TravelKind::Travel:
      break;
  }
  const std::optional<std::size_t> landing = landing_floor(floors, in);
  if (!landing) {
    // Not moving yet (or blind): nothing to land, drop everything now.
    end(TravelEvent::Type::Aborted, lift::Cause::StopRequested, in.now);
    return std::nullopt;
  }
  if (*landing != target_) {
    target_ = *landing;
    target_mm_ = floors.level_mm(*landing);
  }
  return target_;
}

std::optional<std::size_t> HydraulicTravel::landing_floor(const lift::FloorTable& floors,
                                                          const TickInput& in) const noexcept {
  if (kind_ != TravelKind::Travel || phase_ == Phase::Idle || phase_ == Phase::MotorStart ||
      !in.position_mm) {
    return std::nullopt;
  }
  if (phase_ != Phase::Fast) return target_;
  // The first floor ahead still beyond this speed's slowdown distance.
  const auto n = static_cast<std::ptrdiff_t>(floors.size());
  const bool up = direction_ == lift::Direction::Up;
  for (std::ptrdiff_t i = up ? 0 : n - 1; up ? i < n : i >= 0; i += up ? 1 : -1) {
    const auto floor = static_cast<std::size_t>(i);
    const std::int64_t d =
        lift::distance_ahead(*in.position_mm, floors.level_mm(floor), direction_);
    if (d >= static_cast<std::int64_t>(slowdown_mm())) {
      return (up ? floor < target_ : floor > target_) ? floor : target_;
    }
  }
  return target_;
}

void HydraulicTravel::abort(lift::Cause cause, MonoTime now) noexcept {
  if (kind_ != TravelKind::None) end(TravelEvent::Type::Aborted, cause, now);
}

std::uint32_t HydraulicTravel::slowdown_mm() const noexcept {
  if (direction_ == lift::Direction::Down) return config_.slowdown_down_mm;
  switch (speed_) {
    case Speed::V4:
      return config_.slowdown_v4_mm;
    case Speed::V3:
      return config_.slowdown_v3_mm;
    case Speed::Fast:
      break;
  }
  return config_.slowdown_up_mm;
}

CommandBits HydraulicTravel::signals() const noexcept {
  CommandBits b;
  if (kind_ == TravelKind::None || phase_ == Phase::Idle || phase_ == Phase::MotorStart) return b;
  const bool up = direction_ == lift::Direction::Up;
  b.up = up;
  b.dw = !up;
  b.sfy = motor_on_;  // set once the motor runs, i.e. after the star-delta start (1.4)
  if (kind_ == TravelKind::Inspection) {
    b.msp = true;  // inspection speed (1.4: MSP, "Instandhaltung")
    return b;
  }
  if (phase_ != Phase::Fast) return b;  // slow approach: direction (and SFY) alone
  if (up) {
    b.hsp = true;
    b.sp1 = speed_ == Speed::V3;  // V3 = HSP + SP1
    b.sp2 = speed_ == Speed::V4;  // V4 = HSP + SP2
  } else if (config_.fast_down == FastDown::Sp3) {
    b.sp3 = true;  // card P453 = 1
  } else {
    b.hsp = true;  // card P435 = 0
  }
  return b;
}

void HydraulicTravel::measure_speed(const TickInput& in) noexcept {
  if (!in.position_mm) {
    last_position_mm_.reset();
    period_travel_mm_ = 0;
    return;
  }
  const auto elapsed = in.now - last_tick_;
  // A speed needs a base of at least half a status period: the controller may step twice on one
  // frame, microseconds apart, where a millimetre's step of the position would read as metres
  // per second. Until then the last measure stands.
  if (last_position_mm_ && elapsed < kStatusPeriod / 2) return;
  period_travel_mm_ = 0;
  if (last_position_mm_ && elapsed <= 2 * kStatusPeriod) {
    // Over one or two status periods the distance is a speed; over longer it says nothing about
    // the speed now (the car may have stopped and started again).
    const auto moved = std::abs(*in.position_mm - *last_position_mm_);
    period_travel_mm_ = moved * kStatusPeriod.count() /
                        std::chrono::duration_cast<std::chrono::milliseconds>(elapsed).count();
  }
  last_position_mm_ = in.position_mm;
  last_tick_ = in.now;
}

bool HydraulicTravel::slowdown_reached(std::int64_t remaining_mm) const noexcept {
  // The speed signals can drop only in an answer to a status frame (3b, 3c): at the one nearest
  // the slowdown point, i.e. now when the car is nearer the point than it would be past it at
  // the next frame (half a period's travel). Waiting for the first frame past the point would
  // put the slowdown anywhere up to a whole period's travel late (50 mm at 0.5 m/s), and the
  // slow approach, at a tenth of the speed, ten times as long as that late: the travel time
  // would vary by a second with the phase of the frames.
  return remaining_mm - period_travel_mm_ / 2 <= static_cast<std::int64_t>(slowdown_mm());
}

TickOutput HydraulicTravel::tick(const lift::FloorTable& floors, const TickInput& in) noexcept {
  measure_speed(in);
  if (kind_ != TravelKind::None) {
    if (const lift::Cause why = forbidding(kind_, in); why != lift::Cause::None) {
      end(TravelEvent::Type::Aborted, why, in.now);
    } else if (in.now - started_at_ > milliseconds(limit_ms_)) {
      end(TravelEvent::Type::Aborted, lift::Cause::TravelTimeout, in.now);
    }
  }
  if (phase_ == Phase::MotorStart && in.now - motor_on_at_ >= milliseconds(config_.star_delta_ms)) {
    phase_ = kind_ == TravelKind::Travel ? Phase::Fast : Phase::Slow;  // learning up: slow
  }
  if (kind_ == TravelKind::Learn && phase_ != Phase::MotorStart && in.position_mm) {
    // Ended by position alone: the level zones are what the learning records, not stops.
    const std::int64_t remaining = lift::distance_ahead(*in.position_mm, target_mm_, direction_);
    if (phase_ == Phase::Fast && slowdown_reached(remaining)) phase_ = Phase::Slow;
    if (remaining <= 0) {
      // 3c: the current floor is the one nearest where the leg ended.
      if (const auto nearest = floors.nearest(*in.position_mm)) current_floor_ = *nearest;
      end(TravelEvent::Type::Finished, lift::Cause::None, in.now);
    }
  }
  if ((kind_ == TravelKind::Travel || kind_ == TravelKind::Relevel) &&
      phase_ != Phase::MotorStart && in.position_mm) {
    const std::int64_t remaining = lift::distance_ahead(*in.position_mm, target_mm_, direction_);
    if (phase_ == Phase::Fast &&
        (slowdown_reached(remaining) || in.inputs.decel_point(speed_number(speed_), direction_))) {
      phase_ = Phase::Slow;
    }
    if (phase_ == Phase::Slow &&
        (remaining <= static_cast<std::int64_t>(config_.stop_tolerance_mm) ||
         in.inputs.level_zone)) {
      finish(in.now);
    }
  }
  // The inspection run stops at the terminal levels (the limit switches' job in the shaft).
  if (kind_ == TravelKind::Inspection && in.position_mm &&
      lift::at_terminal_level(floors, direction_, *in.position_mm)) {
    end(TravelEvent::Type::Finished, lift::Cause::None, in.now);
  }
  TickOutput out;
  out.bits = signals();
  out.motor_on = motor_on_;
  out.current_floor = current_floor_;
  out.destination_floor =
      kind_ == TravelKind::Travel || kind_ == TravelKind::Relevel ? target_ : current_floor_;
  return out;
}

void HydraulicTravel::finish(MonoTime now) noexcept {
  current_floor_ = target_;  // 3c: the current floor is updated at each stop
  end(TravelEvent::Type::Finished, lift::Cause::None, now);
}

void HydraulicTravel::end(TravelEvent::Type type, lift::Cause cause, MonoTime now) noexcept {
  const std::size_t floor = type == TravelEvent::Type::Finished &&
                                    (kind_ == TravelKind::Travel || kind_ == TravelKind::Relevel)
                                ? target_
                                : current_floor_;
  TravelEvent event{type, kind_, direction_, floor, cause, now};
  if (kind_ == TravelKind::Travel || kind_ == TravelKind::Relevel) event.target = target_;
  push(event);
  kind_ = TravelKind::None;
  phase_ = Phase::Idle;
  direction_ = lift::Direction::None;
  motor_on_ = false;  // every motor off: SFY drops with it (1.4)
}

}  // namespace liftd::sch001
