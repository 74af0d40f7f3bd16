#include "dcp/travel/controller.hpp"

namespace liftd::travel {

namespace {
// After an auto relevelling could not start or was aborted, wait this long before the next try.
constexpr std::chrono::milliseconds kRelevelRetry{1000};

bool speed_in(std::span<const dcp::Speed> speeds, dcp::Speed speed) noexcept {
  for (const auto s : speeds) {
    if (s == speed) return true;
  }
  return false;
}
}  // namespace

bool TravelController::busy() const noexcept {
  return pending_.has_value() || dcp4_.active() || dcp3_.active() || inspection_.active() ||
         relevel_.active();
}

TravelKind TravelController::active_kind() const noexcept {
  if (dcp4_.active()) return dcp4_.kind();
  if (dcp3_.active()) return dcp3_.kind();
  if (inspection_.active()) return inspection_.kind();
  if (relevel_.active()) return TravelKind::Relevel;
  return TravelKind::None;
}

std::int64_t TravelController::active_target_mm() const noexcept {
  if (dcp4_.active()) return dcp4_.target_mm();
  if (dcp3_.active()) return dcp3_.target_mm();
  if (relevel_.active()) return relevel_.target_mm();
  if (pending_) return pending_->target_mm;
  return 0;
}

Direction TravelController::direction() const noexcept {
  if (dcp4_.active()) return dcp4_.direction();
  if (dcp3_.active()) return dcp3_.direction();
  if (inspection_.active()) return inspection_.direction();
  if (relevel_.active()) return relevel_.direction();
  return Direction::None;
}

std::optional<std::uint32_t> TravelController::decel_distance_mm() const noexcept {
  if (dcp4_.active()) return dcp4_.decel_distance_mm(last_);
  return last_.decel_distance_mm;
}

StartResult TravelController::start(const TravelRequest& request) noexcept {
  if (shut_down_) return StartResult::ShuttingDown;
  if (busy() || last_.status.travel_active) return StartResult::Busy;
  if (last_.inputs.inspection || last_.inputs.recall) return StartResult::InspectionMode;
  const dcp::Protocol protocol = last_.protocol;
  if (protocol == dcp::Protocol::ComChan) return StartResult::WrongProtocol;
  Direction direction = request.direction;
  if (last_.position_mm && direction == Direction::None &&
      request.target_mm != *last_.position_mm) {
    direction = request.target_mm > *last_.position_mm ? Direction::Up : Direction::Down;
  }
  const auto distance_mm = [&]() -> std::int64_t {
    const std::int64_t d = request.target_mm - *last_.position_mm;
    return d < 0 ? -d : d;
  };

  switch (request.kind) {
    case TravelKind::Dcp4Distance:
    case TravelKind::Dcp4Relevel:
      if (protocol != dcp::Protocol::Dcp4) return StartResult::WrongProtocol;
      if (request.kind == TravelKind::Dcp4Distance && request.speed != dcp::Speed::V4 &&
          request.speed != dcp::Speed::V3) {
        return StartResult::BadSpeed;  // DCP 11.1.1: V4' or V3'
      }
      if (request.kind == TravelKind::Dcp4Relevel && request.fast_start) {
        return StartResult::BadSpeed;
      }
      if (!last_.position_mm) return StartResult::NoPosition;
      if (distance_mm() <= static_cast<std::int64_t>(config_.level_tolerance_mm)) {
        return StartResult::AlreadyThere;
      }
      break;
    case TravelKind::Dcp3Speed:
      if (protocol == dcp::Protocol::Dcp3) {
        if (!speed_in(dcp::dcp3_travel_speeds(config_.dcp3_speed_count), request.speed)) {
          return StartResult::BadSpeed;  // DCP 3.5.3.7 table
        }
      } else if (request.speed != dcp::Speed::V4 && request.speed != dcp::Speed::V3) {
        return StartResult::BadSpeed;  // DCP 3.5.3.7: V7, V6, V5, V2, V1 not in DCP4
      }
      [[fallthrough]];
    case TravelKind::Dcp3Crawl:
      // A travel to a level the car stands at, as for DCP4 above (docs/api.md `travel`).
      if (request.direction == Direction::None && last_.position_mm &&
          distance_mm() <= static_cast<std::int64_t>(config_.level_tolerance_mm)) {
        return StartResult::AlreadyThere;
      }
      if (direction == Direction::None) return StartResult::NoDirection;
      if ((config_.dcp3_reference == Dcp3Reference::Position || request.by_position) &&
          !last_.position_mm) {
        return StartResult::NoPosition;
      }
      break;
    case TravelKind::Relevel:
      if (request.fast_start) return StartResult::BadSpeed;
      if (direction == Direction::None) return StartResult::NoDirection;
      break;
    case TravelKind::Inspection:
    case TravelKind::Recall:
    case TravelKind::None:
      return StartResult::InspectionMode;  // button driven, not by request
  }
  pending_ = request;
  pending_direction_ = direction;
  return StartResult::Accepted;
}

void TravelController::begin_pending(const CycleInput& in) noexcept {
  if (!pending_ || start_held_) return;
  const TravelRequest request = *pending_;
  pending_.reset();
  switch (request.kind) {
    case TravelKind::Dcp4Distance:
    case TravelKind::Dcp4Relevel:
      dcp4_.begin(request, in, config_);
      break;
    case TravelKind::Dcp3Speed:
    case TravelKind::Dcp3Crawl:
      dcp3_.begin(request, pending_direction_, in);
      break;
    case TravelKind::Relevel:
      relevel_.begin(request, pending_direction_, in);
      break;
    default:
      break;
  }
  // The auto relevelling reference: only where the target is a real level (a learning travel's
  // legs, by_position, end beyond the terminal levels).
  if (request.by_position) {
    home_level_mm_.reset();
  } else if (request.kind == TravelKind::Dcp4Distance ||
             ((request.kind == TravelKind::Dcp3Speed || request.kind == TravelKind::Dcp3Crawl) &&
              config_.dcp3_reference == Dcp3Reference::Position)) {
    home_level_mm_ = request.target_mm;
  } else if (request.kind != TravelKind::Dcp4Relevel) {
    home_level_mm_.reset();
  }
}

void TravelController::drop_queued(lift::Cause cause) noexcept {
  if (!pending_) return;
  const TravelRequest dropped = *pending_;
  pending_.reset();
  StepContext ctx{config_, last_, events_};
  ctx.emit(Event::Type::Aborted, dropped.kind, cause, dropped.target_mm);
}

void TravelController::stop() noexcept {
  drop_queued(lift::Cause::StopRequested);
  dcp4_.request_stop(lift::Cause::StopRequested);
  dcp3_.request_stop(lift::Cause::StopRequested);
  relevel_.request_stop(lift::Cause::StopRequested);
}

void TravelController::fast_stop() noexcept {
  drop_queued(lift::Cause::StopRequested);
  if (dcp4_.active()) dcp4_.request_fast_stop();
  if (dcp3_.active()) dcp3_.request_fast_stop();
  relevel_.request_stop(lift::Cause::StopRequested);
}

ExtendResult TravelController::extend_target(std::int64_t target_mm) noexcept {
  if (!dcp4_.active()) return ExtendResult::NoDistanceTravel;
  const ExtendResult result = dcp4_.extend(target_mm, last_, config_);
  if (result == ExtendResult::Accepted || result == ExtendResult::Pending) {
    home_level_mm_ = target_mm;
  }
  if (result == ExtendResult::Accepted) {  // before the start: goes out with the first distance
    StepContext ctx{config_, last_, events_};
    ctx.emit(Event::Type::TargetExtended, dcp4_.kind(), lift::Cause::None, target_mm);
  }
  return result;  // Pending: the machine reports S5's verdict
}

std::optional<std::int64_t> TravelController::stop_distance_mm() const noexcept {
  if (!dcp4_.active()) return std::nullopt;
  return dcp4_.stop_distance_mm(last_, config_);
}

std::optional<std::int64_t> TravelController::stop_at(std::int64_t target_mm) noexcept {
  drop_queued(lift::Cause::StopRequested);
  if (dcp4_.active() && dcp4_.kind() == TravelKind::Dcp4Distance &&
      dcp4_.state() == Dcp4Travel::State::Distance) {
    // DCP 11.1.1 d: B2 stays until S6 falls at a level; the remaining distance now ends at the
    // next possible stop instead of a stop message at speed (DCP 3.5.3.2: "During
    // deceleration" only). A level the car can no longer reach leaves the target as it is.
    if (dcp4_.shorten(target_mm, last_, config_) == ExtendResult::Pending) {
      home_level_mm_ = target_mm;
    }
    return dcp4_.target_mm();
  }
  if (dcp3_.active() && dcp3_.stop_at(target_mm)) {
    if (config_.dcp3_reference == Dcp3Reference::Position) home_level_mm_ = target_mm;
    return target_mm;
  }
  stop();
  return std::nullopt;
}

void TravelController::shut_down(bool force) noexcept {
  shut_down_ = true;
  drop_queued(lift::Cause::ShuttingDown);
  home_level_mm_.reset();  // no automatic relevelling from now on
  if (force && (dcp4_.active() || dcp3_.active() || relevel_.active() || inspection_.active())) {
    const TravelKind kind = active_kind();
    const std::int64_t target_mm = active_target_mm();
    abort_all_immediately();
    StepContext ctx{config_, last_, events_};
    ctx.emit(Event::Type::Aborted, kind, lift::Cause::ShuttingDown, target_mm);
  }
}

void TravelController::abort_all_immediately() noexcept {
  dcp4_.abort_immediate();
  dcp3_.abort_immediate();
  relevel_.abort_immediate();
  if (inspection_.active()) inspection_.abort_immediate();
}

void TravelController::maybe_auto_relevel(const CycleInput& in) noexcept {
  if (shut_down_ || start_held_ || !config_.auto_relevel || busy()) return;
  if (in.protocol == dcp::Protocol::ComChan || in.status.travel_active) return;
  if (in.inputs.inspection || in.inputs.recall || in.now < relevel_blocked_until_) return;
  if (!in.position_mm) {
    relevel_by_shaft_signals(in);
    return;
  }
  if (!home_level_mm_ || in.protocol != dcp::Protocol::Dcp4) return;
  if (!lift::drift_needs_relevel(*home_level_mm_ - *in.position_mm, config_.relevel_threshold_mm,
                                 config_.relevel_zone_mm)) {
    return;
  }
  GateProfile profile;
  profile.door_bridge_allowed = config_.relevel_doors_open;
  profile.position_required = true;
  if (CommandGate::forbidding(in, profile, true) != lift::Cause::None) {
    relevel_blocked_until_ = in.now + kRelevelRetry;
    return;
  }
  TravelRequest request;
  request.kind = TravelKind::Dcp4Relevel;
  request.speed = dcp::Speed::VN;
  request.target_mm = *home_level_mm_;
  dcp4_.begin(request, in, config_);
}

void TravelController::relevel_by_shaft_signals(const CycleInput& in) noexcept {
  // Without a position the shaft's relevelling zones say where the level is: exactly one of them
  // asks for a direction (both at once contradict each other and move nothing).
  if (in.inputs.relevel_up == in.inputs.relevel_down) return;
  GateProfile profile;
  profile.door_bridge_allowed = config_.relevel_doors_open;
  if (CommandGate::forbidding(in, profile, true) != lift::Cause::None) {
    relevel_blocked_until_ = in.now + kRelevelRetry;
    return;
  }
  TravelRequest request;
  request.kind = TravelKind::Relevel;
  request.speed = dcp::Speed::VN;
  request.direction = in.inputs.relevel_up ? Direction::Up : Direction::Down;
  relevel_.begin(request, request.direction, in);
}

CycleOutput TravelController::step(const CycleInput& in) noexcept {
  last_ = in;
  StepContext ctx{config_, in, events_};
  const bool fault = in.link_up && in.status.general_fault;
  if (fault != fault_seen_) {  // DCP 9.1.6: report S3 edges
    fault_seen_ = fault;
    ctx.emit(fault ? Event::Type::DriveFault : Event::Type::DriveFaultCleared, active_kind(),
             fault ? lift::Cause::DriveFault : lift::Cause::None, active_target_mm());
    // DCP 9.1.6: S3 resets B0 and ends the travel at once, whatever its machine is waiting for.
    // Without this a machine that sees S6/S1 drop in the same reply ends "normally" off the
    // level, and the event would blame the position instead of the drive.
    if (fault) drop_queued(lift::Cause::DriveFault);
    if (fault && (dcp4_.active() || dcp3_.active() || relevel_.active())) {
      const TravelKind kind = active_kind();
      const std::int64_t target_mm = active_target_mm();
      dcp4_.abort_immediate();
      dcp3_.abort_immediate();
      relevel_.abort_immediate();
      if (kind != TravelKind::None) {
        ctx.emit(Event::Type::Aborted, kind, lift::Cause::DriveFault, target_mm);
      }
    }
  }

  // Inspection / recall switched on during a normal travel: end it at once (DCP 9.1.1).
  if (in.inputs.inspection || in.inputs.recall) drop_queued(lift::Cause::ModeChanged);
  if ((in.inputs.inspection || in.inputs.recall) &&
      (dcp4_.active() || dcp3_.active() || relevel_.active())) {
    const TravelKind kind = active_kind();
    const std::int64_t target_mm = active_target_mm();
    dcp4_.abort_immediate();
    dcp3_.abort_immediate();
    relevel_.abort_immediate();
    if (kind != TravelKind::None) {
      ctx.emit(Event::Type::Aborted, kind, lift::Cause::ModeChanged, target_mm);
    }
  }
  begin_pending(in);
  maybe_auto_relevel(in);

  Demand demand;
  if (dcp4_.active()) {
    demand = dcp4_.step(ctx);
  } else if (dcp3_.active()) {
    demand = dcp3_.step(ctx);
  } else if (relevel_.active()) {
    demand = relevel_.step(ctx);
  } else if (inspection_.active() ||
             ((in.inputs.inspection || in.inputs.recall) && !shut_down_ && !start_held_)) {
    demand = inspection_.step(ctx);
  }

  const TravelKind kind = active_kind();
  // travel.relevel_with_doors "closed": no relevelling over the bridged door zone, whichever
  // relevelling asks for it (VN' of DCP 11.2, VN without remaining distance of DCP 9.2.3).
  if (!config_.relevel_doors_open) demand.profile.door_bridge_allowed = false;
  GateResult gated = gate_.apply(demand, in);
  if (gated.violation != lift::Cause::None) {
    if (kind == TravelKind::Dcp4Relevel || kind == TravelKind::Relevel) {
      relevel_blocked_until_ = in.now + kRelevelRetry;
    }
    const std::int64_t target_mm = active_target_mm();
    abort_all_immediately();
    ctx.emit(Event::Type::Aborted, kind, gated.violation, target_mm);
  }
  gated.output.channel_request = ctx.channel_request;
  return gated.output;
}

}  // namespace liftd::travel
