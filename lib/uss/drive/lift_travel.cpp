#include "uss/drive/lift_travel.hpp"

#include <chrono>

#include "lift/gate.hpp"
#include "lift/learning_travel.hpp"

namespace liftd::uss {
namespace {

using std::chrono::milliseconds;

constexpr std::array<std::string_view, kSpeedCount> kSpeedNames = {"V0", "VN", "VI", "V1", "V2",
                                                                   "V3", "V4", "V5", "V6", "V7"};

bool is_travel_speed(SpeedName speed) noexcept {
  return speed_number(speed) != 0;
}

/// C 5.2.1 table 5.5: the drive runs the motor: operation enabled (bit 2), no fault (bit 3), no
/// OFF2 (bit 4 = 1) and no OFF3 (bit 5 = 1) pending.
bool drive_running(std::uint16_t zsw) noexcept {
  constexpr std::uint16_t mask = zsw::kOperationEnabled | zsw::kFault | zsw::kNoOff2 | zsw::kNoOff3;
  return (zsw & mask) == (zsw::kOperationEnabled | zsw::kNoOff2 | zsw::kNoOff3);
}

double magnitude(double v) noexcept {
  return v < 0.0 ? -v : v;
}

}  // namespace

std::string_view to_string(SpeedName speed) noexcept {
  return kSpeedNames[speed_index(speed)];
}

std::optional<SpeedName> parse_speed(std::string_view name) noexcept {
  for (std::size_t i = 0; i < kSpeedNames.size(); ++i) {
    if (kSpeedNames[i] == name) return static_cast<SpeedName>(i);
  }
  return std::nullopt;
}

int speed_number(SpeedName speed) noexcept {
  switch (speed) {
    case SpeedName::V1:
      return 1;
    case SpeedName::V2:
      return 2;
    case SpeedName::V3:
      return 3;
    case SpeedName::V4:
      return 4;
    case SpeedName::V5:
      return 5;
    case SpeedName::V6:
      return 6;
    case SpeedName::V7:
      return 7;
    case SpeedName::V0:
    case SpeedName::VN:
    case SpeedName::VI:
      break;
  }
  return 0;
}

std::optional<std::string_view> validate(const LiftTravelConfig& c) noexcept {
  // C 5.2.2 with the usual 4000 hex = 100 %: a 16-bit setpoint reaches just under 200 %.
  for (double p : c.speed_percent) {
    if (!(p >= 0.0 && p < 200.0)) return "speeds";
  }
  if (c.speed_percent[speed_index(SpeedName::V0)] <= 0.0) return "speeds.V0";
  bool any_travel_speed = false;
  std::uint32_t shortest_slowdown = 0;
  for (std::size_t i = 0; i < kSpeedCount; ++i) {
    const auto speed = static_cast<SpeedName>(i);
    if (!is_travel_speed(speed) || c.speed_percent[i] <= 0.0) continue;
    any_travel_speed = true;
    if (c.reference == Reference::Position) {
      if (c.slowdown_mm[i] == 0) return "slowdown_mm";
      if (shortest_slowdown == 0 || c.slowdown_mm[i] < shortest_slowdown) {
        shortest_slowdown = c.slowdown_mm[i];
      }
    }
  }
  if (!any_travel_speed) return "speeds";
  if (c.reference == Reference::Position && c.stop_lead_mm >= shortest_slowdown) {
    return "stop_lead_mm";
  }
  if (!(c.standstill_percent > 0.0 &&
        c.standstill_percent < c.speed_percent[speed_index(SpeedName::V0)])) {
    return "standstill_percent";
  }
  if (c.profile.switch_on_timeout_ms == 0) return "switch_on_timeout_ms";
  if (c.profile.stop_timeout_ms == 0) return "stop_timeout_ms";
  if (c.profile.acknowledge_hold_ms == 0) return "acknowledge_hold_ms";
  if (c.standstill_timeout_ms == 0) return "standstill_timeout_ms";
  if (c.crawl_timeout_ms == 0) return "crawl_timeout_ms";
  if (c.max_travel_ms == 0) return "max_travel_ms";
  return std::nullopt;
}

std::string_view to_string(Phase phase) noexcept {
  switch (phase) {
    case Phase::Idle:
      return "idle";
    case Phase::Contactors:
      return "contactors";
    case Phase::SwitchOn:
      return "switch_on";
    case Phase::BrakeRelease:
      return "brake_release";
    case Phase::Run:
      return "run";
    case Phase::Crawl:
      return "crawl";
    case Phase::Stopping:
      return "stopping";
    case Phase::BrakeApply:
      return "brake_apply";
    case Phase::SwitchOff:
      return "switch_off";
    case Phase::Halt:
      return "halt";
  }
  return "idle";
}

ProfileWish abort_wish(lift::Cause cause) noexcept {
  switch (cause) {
    // The safety circuit or the drive itself says stop now: pulses off, brake falls (C 5.2.1
    // table 5.2, OFF2: "Motor trudelt aus").
    case lift::Cause::SafetyChainOpen:
    case lift::Cause::DoorsNotLocked:
    case lift::Cause::LinkDown:
    case lift::Cause::DriveFault:
    case lift::Cause::DriveNotReady:
    case lift::Cause::DriveDidNotStop:
    case lift::Cause::TravelTimeout:
    case lift::Cause::ShuttingDown:
    // Causes only the DCP and SCH001 travels raise never end a USS run; should one, it is a link,
    // door or drive refusal like those above.
    case lift::Cause::NoHandshake:
    case lift::Cause::DoorReversal:
    case lift::Cause::FastStartTimeout:
    case lift::Cause::StoppedOffLevel:
    case lift::Cause::TargetRefused:
    case lift::Cause::CardSilent:
    case lift::Cause::BusFault:
      return ProfileWish::Coast;
    // The lift controller lost what it steers by: quickest controlled stop (OFF3, "Schnellhalt").
    case lift::Cause::InputsLost:
    case lift::Cause::PositionLost:
    case lift::Cause::LevelNotReached:
    case lift::Cause::ModeChanged:
      return ProfileWish::QuickStop;
    // Not moving yet, or a user stop between floors: the normal ramp (OFF1).
    case lift::Cause::None:
    case lift::Cause::StopRequested:
    case lift::Cause::AdvanceWarning:
    case lift::Cause::DriveDidNotStart:
    case lift::Cause::SpeedNotConfigured:
      break;
  }
  return ProfileWish::Stop;
}

// ---- gating ----

lift::Cause LiftTravel::drive_forbidding(const DriveInput& in) const noexcept {
  if (!in.link_ok) return lift::Cause::LinkDown;
  if ((in.zsw & zsw::kFault) != 0 || profile_.supervision() != Supervision::None) {
    return lift::Cause::DriveFault;
  }
  if (!profile_.plc_control(in.zsw)) return lift::Cause::DriveNotReady;  // C 5.2.1 ZSW bit 9
  if (decode_status(in.zsw) == ProfileState::NotReadyToSwitchOn) return lift::Cause::DriveNotReady;
  if (config_.warning_blocks_start && (in.zsw & zsw::kWarning) != 0) {
    return lift::Cause::AdvanceWarning;
  }
  return lift::Cause::None;
}

lift::Cause LiftTravel::forbidding(TravelKind kind, const DriveInput& in) const noexcept {
  if (const lift::Cause why = drive_forbidding(in); why != lift::Cause::None) return why;
  return ending(kind, in);
}

lift::Cause LiftTravel::ending(TravelKind kind, const DriveInput& in) const noexcept {
  if (!in.link_ok) return lift::Cause::LinkDown;
  if ((in.zsw & zsw::kFault) != 0) return lift::Cause::DriveFault;  // C 5.2.1 ZSW bit 3
  switch (profile_.supervision()) {
    case Supervision::NotSwitchedOn:
      return lift::Cause::DriveDidNotStart;
    case Supervision::NotStopped:
      return lift::Cause::DriveDidNotStop;
    case Supervision::None:
      break;
  }
  if (!profile_.plc_control(in.zsw)) return lift::Cause::DriveNotReady;
  // The machine's rules, common to every drive kind (lib/lift/gate.hpp). Inspection: the
  // safety chain holds the door contacts.
  // A learning leg needs what a travel needs, and the position whatever the reference.
  const bool learn = kind == TravelKind::Learn;
  const lift::MachineNeeds needs =
      lift::run_needs(learn ? TravelKind::Travel : kind, config_.relevel_doors_open,
                      learn || config_.reference == Reference::Position);
  return lift::refusal_cause(lift::machine_refusal(in.inputs, in.position_mm.has_value(), needs));
}

// ---- starting and stopping ----

lift::Cause LiftTravel::begin(TravelKind kind, std::size_t floor, SpeedName speed,
                              lift::Direction direction, const DriveInput& in) noexcept {
  if (!speed_available(speed)) return lift::Cause::SpeedNotConfigured;
  if (const lift::Cause why = forbidding(kind, in); why != lift::Cause::None) return why;
  kind_ = kind;
  target_ = floor;
  speed_ = speed;
  direction_ = direction;
  started_at_ = in.now;
  run_limit_ms_ = config_.max_travel_ms;
  crawl_limit_ms_ = config_.crawl_timeout_ms;
  inspect_stop_ = false;
  enter(Phase::Contactors, in.now);
  push(TravelEvent::Type::Started, lift::Cause::None, in.now);
  return lift::Cause::None;
}

lift::Cause LiftTravel::start_travel(const lift::FloorTable& floors, std::size_t floor,
                                     SpeedName speed, const DriveInput& in) noexcept {
  if (!is_travel_speed(speed)) return lift::Cause::SpeedNotConfigured;
  lift::Direction direction = lift::Direction::None;
  if (in.position_mm) {
    direction =
        floors.level_mm(floor) >= *in.position_mm ? lift::Direction::Up : lift::Direction::Down;
  } else if (floor != current_floor_) {
    // Shaft signals without a position: from the floor the car last stopped at.
    direction = floor > current_floor_ ? lift::Direction::Up : lift::Direction::Down;
  } else {
    return lift::Cause::PositionLost;  // no way to tell which way
  }
  target_mm_ = floors.level_mm(floor);
  return begin(TravelKind::Travel, floor, speed, direction, in);
}

lift::Cause LiftTravel::start_relevel(const lift::FloorTable& floors, std::size_t floor,
                                      lift::Direction direction, const DriveInput& in) noexcept {
  if (in.position_mm) {
    direction =
        floors.level_mm(floor) >= *in.position_mm ? lift::Direction::Up : lift::Direction::Down;
  }
  if (direction == lift::Direction::None) return lift::Cause::PositionLost;
  target_mm_ = floors.level_mm(floor);
  return begin(TravelKind::Relevel, floor, SpeedName::VN, direction, in);
}

lift::Cause LiftTravel::start_learning(std::int64_t target_mm, lift::Direction direction,
                                       SpeedName approach, const DriveInput& in) noexcept {
  if (direction == lift::Direction::None || !in.position_mm) return lift::Cause::PositionLost;
  // Up: the crawl setpoint all the way, so each zone edge is seen at the crawl. Down: the
  // approach may go fast and crawl the last part, as a travel does.
  const SpeedName speed =
      direction == lift::Direction::Up || !is_travel_speed(approach) || !speed_available(approach)
          ? SpeedName::V0
          : approach;
  const std::int64_t distance = target_mm - *in.position_mm;
  const std::int64_t previous_target_mm = target_mm_;
  target_mm_ = target_mm;
  const lift::Cause why = begin(TravelKind::Learn, current_floor_, speed, direction, in);
  if (why != lift::Cause::None) {
    target_mm_ = previous_target_mm;
    return why;
  }
  // The limits must let a crawl cover the whole leg.
  run_limit_ms_ = lift::learn_leg_limit_ms(config_.max_travel_ms, distance);
  crawl_limit_ms_ = lift::learn_leg_limit_ms(config_.crawl_timeout_ms, distance);
  return lift::Cause::None;
}

bool LiftTravel::end_learning_at(std::int64_t target_mm) noexcept {
  if (kind_ != TravelKind::Learn || direction_ != lift::Direction::Up) return false;
  if (phase_ != Phase::Contactors && phase_ != Phase::SwitchOn && phase_ != Phase::BrakeRelease &&
      phase_ != Phase::Run && phase_ != Phase::Crawl) {
    return false;  // stopping already
  }
  target_mm_ = target_mm;
  return true;
}

lift::Cause LiftTravel::inspect(const lift::FloorTable& floors, lift::Direction direction,
                                const DriveInput& in) noexcept {
  if (kind_ == TravelKind::Inspection) {
    // Hold-to-run: released or reversed, the run stops first (a reversal starts afresh once
    // this run has ended and the button is still held).
    if (direction != direction_) normal_stop(in.now);
    return lift::Cause::None;
  }
  if (direction == lift::Direction::None || busy()) return lift::Cause::None;
  if (in.position_mm && lift::at_terminal_level(floors, direction, *in.position_mm)) {
    return lift::Cause::None;  // a button held at the terminal level moves nothing
  }
  return begin(TravelKind::Inspection, current_floor_, SpeedName::VI, direction, in);
}

void LiftTravel::normal_stop(MonoTime now) noexcept {
  inspect_stop_ = true;
  switch (phase_) {
    case Phase::Contactors:
    case Phase::SwitchOn:
      // Nothing moves and the brake never opened: switch off (OFF1) and end.
      enter(Phase::SwitchOff, now);
      break;
    case Phase::BrakeRelease:
    case Phase::Run:
    case Phase::Crawl:
      enter(Phase::Stopping, now);
      break;
    case Phase::Idle:
    case Phase::Stopping:
    case Phase::BrakeApply:
    case Phase::SwitchOff:
    case Phase::Halt:
      break;
  }
}

std::optional<std::size_t> LiftTravel::stop(const lift::FloorTable& floors,
                                            const DriveInput& in) noexcept {
  switch (kind_) {
    case TravelKind::None:
      return std::nullopt;
    case TravelKind::Inspection:
      normal_stop(in.now);
      return std::nullopt;
    case TravelKind::Relevel:
      return target_;  // a few millimetres at VN: let it land
    case TravelKind::Learn:
      normal_stop(in.now);  // no floor to land at: the drive's ramp to standstill
      return std::nullopt;
    case TravelKind::Travel:
      break;
  }
  if (phase_ == Phase::Contactors || phase_ == Phase::SwitchOn || phase_ == Phase::BrakeRelease) {
    abort(lift::Cause::StopRequested, in.now);  // not moving yet: nothing to land
    return std::nullopt;
  }
  if (phase_ != Phase::Run || config_.reference != Reference::Position) return target_;
  if (!in.position_mm) {
    abort(lift::Cause::StopRequested, in.now);
    return std::nullopt;
  }
  const std::optional<std::size_t> ahead = first_floor_beyond_slowdown(floors, *in.position_mm);
  if (!ahead) {
    abort(lift::Cause::StopRequested, in.now);
    return std::nullopt;
  }
  if (earlier_than_target(*ahead)) {
    target_ = *ahead;
    target_mm_ = floors.level_mm(*ahead);
  }
  return target_;
}

std::optional<std::size_t> LiftTravel::landing_floor(const lift::FloorTable& floors,
                                                     const DriveInput& in) const noexcept {
  if (kind_ != TravelKind::Travel) return std::nullopt;
  switch (phase_) {
    case Phase::Run:
      break;
    case Phase::Crawl:
    case Phase::Stopping:
      return target_;
    default:  // not moving yet, or the tail of a run
      return std::nullopt;
  }
  if (config_.reference != Reference::Position || !in.position_mm) return target_;
  const std::optional<std::size_t> ahead = first_floor_beyond_slowdown(floors, *in.position_mm);
  return ahead && earlier_than_target(*ahead) ? *ahead : target_;  // else too late for any
}

std::optional<std::size_t> LiftTravel::first_floor_beyond_slowdown(
    const lift::FloorTable& floors, std::int64_t position_mm) const noexcept {
  const std::uint32_t slowdown = config_.slowdown_mm[speed_index(speed_)];
  const auto n = static_cast<std::ptrdiff_t>(floors.size());
  const bool up = direction_ == lift::Direction::Up;
  for (std::ptrdiff_t i = up ? 0 : n - 1; up ? i < n : i >= 0; i += up ? 1 : -1) {
    const auto floor = static_cast<std::size_t>(i);
    if (lift::distance_ahead(position_mm, floors.level_mm(floor), direction_) >=
        static_cast<std::int64_t>(slowdown)) {
      return floor;
    }
  }
  return std::nullopt;
}

bool LiftTravel::earlier_than_target(std::size_t floor) const noexcept {
  return direction_ == lift::Direction::Up ? floor < target_ : floor > target_;
}

void LiftTravel::abort(lift::Cause cause, MonoTime now) noexcept {
  const ProfileWish wish = abort_wish(cause);
  if (kind_ == TravelKind::None) {
    // A halt tail already runs: a coast overrides its ramp (no second report).
    if (phase_ == Phase::Halt && wish == ProfileWish::Coast) {
      halt_wish_ = wish;
      halt_brake_ = false;
      coast_hold_ = true;
    }
    return;
  }
  push(TravelEvent::Type::Aborted, cause, now);
  // The brake may stay open through an OFF1/OFF3 ramp only where it was open already.
  const bool brake_was_open = phase_ == Phase::BrakeRelease || phase_ == Phase::Run ||
                              phase_ == Phase::Crawl || phase_ == Phase::Stopping;
  halt_wish_ = wish;
  halt_brake_ = brake_was_open && wish != ProfileWish::Coast;
  if (wish == ProfileWish::Coast) coast_hold_ = true;
  kind_ = TravelKind::None;
  inspect_stop_ = false;
  enter(Phase::Halt, now);
}

void LiftTravel::enter(Phase phase, MonoTime now) noexcept {
  phase_ = phase;
  entered_at_ = now;
}

void LiftTravel::finish(MonoTime now) noexcept {
  if (kind_ == TravelKind::Travel || kind_ == TravelKind::Relevel) current_floor_ = target_;
  push(TravelEvent::Type::Finished, lift::Cause::None, now);
  kind_ = TravelKind::None;
  direction_ = lift::Direction::None;
  inspect_stop_ = false;
  enter(Phase::Idle, now);
}

void LiftTravel::push(TravelEvent::Type type, lift::Cause cause, MonoTime now) noexcept {
  // A travel or relevelling names its target; an inspection run and a learning leg the floor
  // the car was at (a finished learning leg: the one nearest where it ended).
  const bool to_floor = kind_ == TravelKind::Travel || kind_ == TravelKind::Relevel;
  const bool landed = type == TravelEvent::Type::Finished && to_floor;
  const std::size_t floor = type == TravelEvent::Type::Started && to_floor ? target_
                            : landed                                       ? target_
                                                                           : current_floor_;
  TravelEvent event{type, kind_, direction_, floor, cause, now};
  if (to_floor) event.target = target_;
  events_.push(event);
}

// ---- one step ----

bool LiftTravel::decel_point(const DriveInput& in) const noexcept {
  if (config_.reference == Reference::ShaftSignals && kind_ != TravelKind::Learn) {
    return in.inputs.decel_point(speed_number(speed_), direction_);
  }
  if (!in.position_mm) return false;
  return lift::distance_ahead(*in.position_mm, target_mm_, direction_) <=
         static_cast<std::int64_t>(config_.slowdown_mm[speed_index(speed_)]);
}

bool LiftTravel::at_level(const DriveInput& in) const noexcept {
  if (in.position_mm && (config_.reference == Reference::Position || kind_ == TravelKind::Relevel ||
                         kind_ == TravelKind::Learn)) {
    // The setpoint goes to 0 the crawl's ramp distance before the level, so the car stops on
    // it (the role a stop flag ahead of the level plays in the shaft).
    return lift::distance_ahead(*in.position_mm, target_mm_, direction_) <=
           static_cast<std::int64_t>(config_.stop_lead_mm);
  }
  if (kind_ == TravelKind::Relevel) {
    // Inside the level zone, and the relevelling signal that asked for this direction dropped.
    return in.inputs.level_zone && !in.inputs.relevel_towards(direction_);
  }
  return config_.reference == Reference::ShaftSignals && in.inputs.level_zone;
}

double LiftTravel::run_setpoint(const DriveInput& in) const noexcept {
  SpeedName speed = speed_;
  if (phase_ == Phase::Crawl) speed = SpeedName::V0;
  if (kind_ == TravelKind::Inspection) {
    // DCP 9.2.1: inspection at VI, at V0 in the end zone it travels into.
    const bool end_zone = (direction_ == lift::Direction::Up && in.inputs.end_zone_top) ||
                          (direction_ == lift::Direction::Down && in.inputs.end_zone_bottom);
    speed = end_zone ? SpeedName::V0 : SpeedName::VI;
  }
  const double percent = config_.speed_percent[speed_index(speed)];
  // C 5.2.2: a signed normalised setpoint; up is positive.
  return direction_ == lift::Direction::Down ? -percent : percent;
}

void LiftTravel::sequence(const lift::FloorTable& floors, const DriveInput& in) noexcept {
  const MonoTime since = in.now - entered_at_;
  const bool running = drive_running(in.zsw);
  const bool standstill = magnitude(in.actual_percent) <= config_.standstill_percent;
  switch (phase_) {
    case Phase::Idle:
    case Phase::Halt:
      return;
    case Phase::Contactors:
      if (since >= milliseconds(config_.contactor_ms)) enter(Phase::SwitchOn, in.now);
      return;
    case Phase::SwitchOn:
      // The profile walks the drive to "operation enabled"; its supervision ends a drive that
      // does not get there (DriveDidNotStart, via ending()).
      if (decode_status(in.zsw) == ProfileState::OperationEnabled) {
        enter(Phase::BrakeRelease, in.now);
      }
      return;
    case Phase::BrakeRelease:
      if (!running) return abort(lift::Cause::DriveNotReady, in.now);
      if (since >= milliseconds(config_.brake_release_ms)) enter(Phase::Run, in.now);
      return;
    case Phase::Run:
      if (!running) return abort(lift::Cause::DriveNotReady, in.now);
      if (kind_ == TravelKind::Travel || (kind_ == TravelKind::Learn && speed_ != SpeedName::V0)) {
        if (decel_point(in)) enter(Phase::Crawl, in.now);
      } else if (kind_ == TravelKind::Learn) {
        // The crawl up through the zones: by position to the leg's end, bounded like a crawl.
        if (at_level(in)) {
          enter(Phase::Stopping, in.now);
        } else if (since >= milliseconds(crawl_limit_ms_)) {
          abort(lift::Cause::LevelNotReached, in.now);
        }
      } else if (kind_ == TravelKind::Relevel) {
        // Relevelling runs at VN all the way: bounded like a crawl.
        if (at_level(in)) {
          enter(Phase::Stopping, in.now);
        } else if (since >= milliseconds(crawl_limit_ms_)) {
          abort(lift::Cause::LevelNotReached, in.now);
        }
      } else if (in.position_mm && floors.size() > 0 &&
                 lift::at_terminal_level(floors, direction_, *in.position_mm)) {
        // The inspection run stops at the terminal levels (the limit switches' job in the shaft).
        enter(Phase::Stopping, in.now);
      }
      return;
    case Phase::Crawl:
      if (!running) return abort(lift::Cause::DriveNotReady, in.now);
      if (at_level(in)) {
        enter(Phase::Stopping, in.now);
      } else if (since >= milliseconds(crawl_limit_ms_)) {
        abort(lift::Cause::LevelNotReached, in.now);
      }
      return;
    case Phase::Stopping:
      if (!running) return abort(lift::Cause::DriveNotReady, in.now);
      if (standstill) {
        enter(Phase::BrakeApply, in.now);
      } else if (since >= milliseconds(config_.standstill_timeout_ms)) {
        abort(lift::Cause::DriveDidNotStop, in.now);
      }
      return;
    case Phase::BrakeApply:
      if (!running) return abort(lift::Cause::DriveNotReady, in.now);
      if (since >= milliseconds(config_.brake_apply_ms)) enter(Phase::SwitchOff, in.now);
      return;
    case Phase::SwitchOff:
      // C 5.2.1 table 5.2 OFF1: "bei n/f = 0 und I = 0 Spannungsfreischaltung": the run is over
      // when ZSW bit 2 drops. The profile supervision ends a drive that stays on.
      if (!operation_enabled(in.zsw)) {
        if (kind_ == TravelKind::Learn && in.position_mm) {
          if (const auto nearest = floors.nearest(*in.position_mm)) current_floor_ = *nearest;
        }
        finish(in.now);
      }
      return;
  }
}

DriveOutput LiftTravel::tick(const lift::FloorTable& floors, const DriveInput& in) noexcept {
  if (kind_ != TravelKind::None) {
    lift::Cause why = ending(kind_, in);
    // Motor run-time limiter; as common practice has it, not on inspection runs (a technician
    // may walk the whole shaft at VI, and lets go of the button to stop).
    if (why == lift::Cause::None && kind_ != TravelKind::Inspection &&
        in.now - started_at_ > milliseconds(run_limit_ms_)) {
      why = lift::Cause::TravelTimeout;  // motor run-time limiter
    }
    if (why != lift::Cause::None) abort(why, in.now);
  } else if (phase_ == Phase::Halt) {
    // A halt on a ramp turns into a coast when a safety condition comes on top.
    if (const lift::Cause why = ending(TravelKind::Inspection, in);
        why != lift::Cause::None && abort_wish(why) == ProfileWish::Coast) {
      abort(why, in.now);
    }
  }
  sequence(floors, in);

  const bool standstill = magnitude(in.actual_percent) <= config_.standstill_percent;
  const bool enabled = operation_enabled(in.zsw) && (in.zsw & zsw::kFault) == 0;
  if (phase_ == Phase::Halt) {
    if (standstill || !enabled) halt_brake_ = false;
    // The halt ends when the drive reports its pulses off. Without current replies, or when the
    // drive keeps running past stop_timeout_ms (the profile supervision latches NotStopped),
    // it ends too, and OFF2 is held until a reply shows ZSW bit 2 = 0.
    if (in.link_ok && !enabled) {
      enter(Phase::Idle, in.now);
    } else if (!in.link_ok ||
               in.now - entered_at_ >= milliseconds(config_.profile.stop_timeout_ms)) {
      coast_hold_ = true;
      enter(Phase::Idle, in.now);
    }
    if (phase_ == Phase::Idle) {
      direction_ = lift::Direction::None;
      halt_brake_ = false;
    }
  }
  if (in.link_ok && !operation_enabled(in.zsw)) coast_hold_ = false;

  DriveOutput out;
  switch (phase_) {
    case Phase::Idle:
      // While the safety chain is open (or unknown) nothing may switch the drive on, and after
      // a coast the drive keeps OFF2 until it reports its pulses off: OFF2. Else OFF1.
      out.wish = in.inputs.valid && in.inputs.safety_chain_closed && !coast_hold_
                     ? ProfileWish::Stop
                     : ProfileWish::Coast;
      break;
    case Phase::Contactors:
      out.wish = ProfileWish::Stop;  // takes an inhibited drive to "ready to switch on"
      out.contactors_on = true;
      break;
    case Phase::SwitchOn:
    case Phase::BrakeApply:
      out.wish = ProfileWish::Run;
      out.contactors_on = true;
      out.brake_open = false;
      break;
    case Phase::BrakeRelease:
    case Phase::Stopping:
      out.wish = ProfileWish::Run;
      out.contactors_on = true;
      out.brake_open = in.link_ok && drive_running(in.zsw);
      break;
    case Phase::Run:
    case Phase::Crawl:
      out.wish = ProfileWish::Run;
      out.contactors_on = true;
      out.brake_open = in.link_ok && drive_running(in.zsw);
      out.setpoint_percent = run_setpoint(in);
      break;
    case Phase::SwitchOff:
      out.wish = ProfileWish::Stop;
      out.contactors_on = true;
      break;
    case Phase::Halt:
      out.wish = halt_wish_;
      out.contactors_on = halt_wish_ != ProfileWish::Coast;
      out.brake_open = halt_brake_ && in.link_ok;
      break;
  }
  ProfileInput pin;
  pin.now = in.now;
  pin.zsw = in.zsw;
  pin.replies = in.replies;
  pin.link_ok = in.link_ok;
  out.stw = profile_.step(out.wish, pin);
  out_ = out;
  return out;
}

}  // namespace liftd::uss
