#include "dcp/travel/dcp4_travel.hpp"

namespace liftd::travel {

namespace {
// DCP 7.2: the new distance must reach the drive at least 30 ms before the deceleration point,
// even if one exchange is repeated; add one cycle until our frame leaves and one for the repeat.
constexpr std::int64_t kExtensionLeadMs = 30 + 15 + 15;
// DCP 5.12.7: Ss has 5 BCD digits in cm.
constexpr std::int64_t kMaxI7DistanceCm = 99999;
}  // namespace

void Dcp4Travel::begin(const TravelRequest& request, const CycleInput& in,
                       const TravelConfig& config) noexcept {
  kind_ = request.kind;
  speed_ = kind_ == TravelKind::Dcp4Relevel ? dcp::Speed::VN : request.speed;
  target_mm_ = request.target_mm;
  const std::int64_t position = in.position_mm.value_or(request.target_mm);
  direction_ = request.target_mm >= position ? Direction::Up : Direction::Down;
  fast_start_ = request.fast_start && kind_ == TravelKind::Dcp4Distance;
  load_percent_ = fast_start_ ? std::nullopt : request.load_percent;  // DCP 5.12.8: not with VF
  brake_seen_open_ = false;
  travel_seen_ = false;
  go_sent_ = false;
  start_reported_ = false;
  unconfirmed_target_mm_.reset();
  end_cause_ = lift::Cause::None;
  i7_decel_mm_.reset();
  i7_reply_.reset();
  last_position_mm_.reset();
  speed_mm_per_s_ = 0;
  if (kind_ == TravelKind::Dcp4Distance && config.use_i7) {
    enter(State::StartParameters, in.now);
  } else if (fast_start_) {
    enter(State::FastStartHold, in.now);
  } else if (load_percent_) {
    enter(State::Load, in.now);
  } else {
    enter(State::SpeedMessage, in.now);
  }
}

void Dcp4Travel::enter(State state, MonoTime now) noexcept {
  state_ = state;
  entered_ = now;
  cycles_in_state_ = 0;
}

void Dcp4Travel::request_stop(lift::Cause cause) noexcept {
  // A fast stop (DCP 13) already ends the travel on its own ramp: a stop message now would drop
  // B2 while the brake is still open (DCP 11.1.1 d).
  if (state_ == State::Idle || state_ == State::TravelEnd || state_ == State::ControlledAbort ||
      state_ == State::FastStop) {
    return;
  }
  end_cause_ = cause;
  state_ = State::ControlledAbort;
  cycles_in_state_ = 0;
  entered_ = last_time_;
}

void Dcp4Travel::request_fast_stop() noexcept {
  if (state_ == State::Distance || state_ == State::FastStartGo) {
    end_cause_ = lift::Cause::StopRequested;
    state_ = State::FastStop;
    cycles_in_state_ = 0;
    entered_ = last_time_;
  } else {
    request_stop(lift::Cause::StopRequested);
  }
}

std::optional<std::uint32_t> Dcp4Travel::decel_distance_mm(const CycleInput& in) const noexcept {
  if (in.decel_distance_mm) return in.decel_distance_mm;
  return i7_decel_mm_;
}

std::optional<std::int64_t> Dcp4Travel::stop_distance_mm(
    const CycleInput& in, const TravelConfig& config) const noexcept {
  // DCP 11.1.2 note: a target may move "while it is greater than the deceleration distance the
  // drive controller had transmitted before the beginning of the travel" (I7's Sv); the live
  // value of the data bytes still grows while the car accelerates: take the larger.
  std::optional<std::uint32_t> decel = in.decel_distance_mm;
  if (i7_decel_mm_ && (!decel || *i7_decel_mm_ > *decel)) decel = i7_decel_mm_;
  if (!decel) return std::nullopt;
  // DCP 7.2: the new distance must reach the drive 30 ms before the deceleration point, "even
  // if the exchange of message has to be repeated": kExtensionLeadMs at the current speed.
  const std::int64_t lead_mm = speed_mm_per_s_ * kExtensionLeadMs / 1000;
  return static_cast<std::int64_t>(*decel) + static_cast<std::int64_t>(config.extension_margin_mm) +
         lead_mm;
}

ExtendResult Dcp4Travel::extend(std::int64_t target_mm, const CycleInput& in,
                                const TravelConfig& config) noexcept {
  if (kind_ != TravelKind::Dcp4Distance) return ExtendResult::NoDistanceTravel;
  switch (state_) {
    case State::StartParameters:
    case State::FastStartHold:
    case State::Load:
    case State::SpeedMessage:
    case State::Distance:
      break;
    default:
      return ExtendResult::NoDistanceTravel;
  }
  const bool further =
      direction_ == Direction::Up ? target_mm > target_mm_ : target_mm < target_mm_;
  if (!further) return ExtendResult::NotFurther;
  if (state_ != State::Distance) {  // nothing moving yet: the new target simply replaces the old
    target_mm_ = target_mm;
    return ExtendResult::Accepted;
  }
  if (unconfirmed_target_mm_) return ExtendResult::Busy;
  if (in.status.advance_warning) return ExtendResult::AdvanceWarning;  // DCP 9.1.5
  const auto limit_mm = stop_distance_mm(in, config);
  if (!limit_mm || !in.position_mm) return ExtendResult::DecelUnknown;
  const std::int64_t remaining = remaining_mm(target_mm_, *in.position_mm, direction_);
  if (remaining <= *limit_mm) return ExtendResult::TooLate;
  target_mm_ = target_mm;
  unconfirmed_target_mm_ = target_mm;
  cycles_since_change_ = 0;
  return ExtendResult::Pending;
}

ExtendResult Dcp4Travel::shorten(std::int64_t target_mm, const CycleInput& in,
                                 const TravelConfig& config) noexcept {
  if (kind_ != TravelKind::Dcp4Distance || state_ != State::Distance) {
    return ExtendResult::NoDistanceTravel;
  }
  if (unconfirmed_target_mm_) return ExtendResult::Busy;
  const auto limit_mm = stop_distance_mm(in, config);
  if (!limit_mm || !in.position_mm) return ExtendResult::DecelUnknown;
  if (remaining_mm(target_mm, *in.position_mm, direction_) <= *limit_mm) {
    return ExtendResult::TooLate;
  }
  const bool nearer = direction_ == Direction::Up ? target_mm < target_mm_ : target_mm > target_mm_;
  if (!nearer) return ExtendResult::NotFurther;
  target_mm_ = target_mm;
  unconfirmed_target_mm_ = target_mm;
  cycles_since_change_ = 0;
  return ExtendResult::Pending;
}

Demand Dcp4Travel::speed_demand(std::uint8_t message, dcp::Speed speed) const noexcept {
  Demand demand;
  demand.command = command_byte(message, direction_);
  demand.data_word = dcp::speed_word(speed);
  demand.profile.doors_locked_required = !(state_ == State::FastStartHold);
  demand.profile.door_bridge_allowed = kind_ == TravelKind::Dcp4Relevel;
  demand.profile.position_required = true;
  return demand;
}

Demand Dcp4Travel::distance_demand(std::uint8_t message, const StepContext& ctx) const noexcept {
  Demand demand;
  demand.command = command_byte(message, direction_);
  const std::int64_t position = ctx.in.position_mm.value_or(target_mm_);
  demand.data_word =
      dcp::remaining_distance_word(remaining_mm(target_mm_, position, direction_),
                                   dcp::remaining_distance_width(ctx.config.data_info_type));
  demand.profile.doors_locked_required =
      !(state_ == State::FastStartHold ||
        (state_ == State::ControlledAbort && fast_start_ && !go_sent_));
  demand.profile.door_bridge_allowed = kind_ == TravelKind::Dcp4Relevel;
  demand.profile.position_required = true;
  return demand;
}

void Dcp4Travel::track_acceptance(StepContext& ctx) noexcept {
  const CycleInput& in = ctx.in;
  if (unconfirmed_target_mm_) ++cycles_since_change_;
  // The reply to the first frame that carried the change tells (DCP 4.1, 7.2).
  const bool answered = unconfirmed_target_mm_ && cycles_since_change_ >= 2 && in.reply_fresh;
  if (answered && in.status.accepted) {
    ctx.emit(Event::Type::TargetExtended, kind_, lift::Cause::None, *unconfirmed_target_mm_);
    unconfirmed_target_mm_.reset();
  }
  // DCP 4.1 note: a plausibility error makes the drive stop on its emergency ramp with S5
  // cleared "until the lift has stopped". B2 stays until S6 falls (DCP 11.1.2 step 4).
  if (travel_seen_ && in.reply_fresh && in.status.brake_open && !in.status.accepted &&
      end_cause_ == lift::Cause::None) {
    end_cause_ = lift::Cause::TargetRefused;
    if (unconfirmed_target_mm_) {
      ctx.emit(Event::Type::TargetRefused, kind_, lift::Cause::TargetRefused,
               *unconfirmed_target_mm_);
      unconfirmed_target_mm_.reset();
    }
  }
}

void Dcp4Travel::finish(StepContext& ctx) noexcept {
  if (end_cause_ == lift::Cause::None && ctx.in.position_mm) {
    const std::int64_t off = remaining_mm(target_mm_, *ctx.in.position_mm, direction_);
    if ((off < 0 ? -off : off) > static_cast<std::int64_t>(ctx.config.arrival_tolerance_mm)) {
      end_cause_ = lift::Cause::StoppedOffLevel;
    }
  }
  if (unconfirmed_target_mm_) {  // ended before the drive answered the change
    ctx.emit(Event::Type::TargetRefused, kind_, end_cause_, *unconfirmed_target_mm_);
    unconfirmed_target_mm_.reset();
  }
  ctx.emit_end(kind_, end_cause_, target_mm_);
  state_ = State::Idle;
}

// Over 120 lines: one switch over the DCP4 travel states (DCP 11.1, 12, 13): split, it would
// hide the sequence.
Demand Dcp4Travel::step(StepContext& ctx) noexcept {
  const CycleInput& in = ctx.in;
  const TravelConfig& config = ctx.config;
  // Speed estimate for the extension lead (position delta over the last cycle).
  if (in.position_mm && last_position_mm_ && in.now > last_time_) {
    const std::int64_t delta = *in.position_mm - *last_position_mm_;
    const std::int64_t dt_us =
        std::chrono::duration_cast<std::chrono::microseconds>(in.now - last_time_).count();
    speed_mm_per_s_ = (delta < 0 ? -delta : delta) * 1'000'000 / dt_us;
  }
  last_position_mm_ = in.position_mm;
  last_time_ = in.now;
  if (in.status.brake_open) brake_seen_open_ = true;
  if (in.status.travel_active && !travel_seen_ &&
      (state_ == State::Distance || state_ == State::FastStartGo)) {
    travel_seen_ = true;
  }
  // DCP 4.1 S5 "Desired distance / speed accepted": the travel counts as started only once the
  // drive runs (S1) and has accepted it.
  if (travel_seen_ && !start_reported_ && in.status.accepted && end_cause_ == lift::Cause::None) {
    start_reported_ = true;
    ctx.emit(Event::Type::Started, kind_, lift::Cause::None, target_mm_);
  }
  ++cycles_in_state_;
  const auto since_ms = elapsed_ms(in.now, entered_);

  switch (state_) {
    case State::Idle:
      return {};

    case State::StartParameters: {
      if (cycles_in_state_ == 1) {
        ChannelRequest request;
        request.kind = ChannelRequest::Kind::StartParameters;
        request.vmax = speed_;
        const std::int64_t distance_cm =
            (remaining_mm(target_mm_, in.position_mm.value_or(target_mm_), direction_) + 5) / 10;
        request.desired_distance_cm = static_cast<std::uint32_t>(
            distance_cm < 0 ? 0
                            : (distance_cm > kMaxI7DistanceCm ? kMaxI7DistanceCm : distance_cm));
        ctx.channel_request = request;
      }
      const bool replied =
          in.channel_reply && in.channel_reply->kind == ChannelRequest::Kind::StartParameters;
      if (replied) {
        i7_reply_ = in.channel_reply;
        i7_decel_mm_ = in.channel_reply->decel_distance_cm * 10U;  // cm -> mm
      }
      if (replied || since_ms >= config.i7_timeout_ms) {
        if (fast_start_) {
          enter(State::FastStartHold, in.now);
        } else if (load_percent_) {
          enter(State::Load, in.now);
        } else {
          enter(State::SpeedMessage, in.now);
        }
      }
      return {};
    }

    case State::Load: {
      if (cycles_in_state_ == 1) {
        ChannelRequest request;
        request.kind = ChannelRequest::Kind::Load;
        request.load_percent = *load_percent_;
        ctx.channel_request = request;
      }
      const bool replied = in.channel_reply && in.channel_reply->kind == ChannelRequest::Kind::Load;
      if (replied || since_ms >= config.i8_timeout_ms) enter(State::SpeedMessage, in.now);
      return {};
    }

    case State::FastStartHold: {
      if (cycles_in_state_ == 1 && in.inputs.door_reversal) {
        // Reversal before the VF message went out: nothing to stop, no B0 at all.
        end_cause_ = lift::Cause::DoorReversal;
        finish(ctx);
        return {};
      }
      if (cycles_in_state_ == 1) {
        ctx.emit(Event::Type::FastStartArmed, kind_, lift::Cause::None, target_mm_);
      }
      if (in.inputs.door_reversal) {  // DCP 12.2: doors reopening, stop sequence
        request_stop(lift::Cause::DoorReversal);
        return distance_demand(nibble::kStop, ctx);
      }
      if (since_ms >= config.fast_start_timeout_ms) {  // DCP 12.1.2: time limited
        request_stop(lift::Cause::FastStartTimeout);
        return distance_demand(nibble::kStop, ctx);
      }
      if (cycles_in_state_ > speed_cycles(config) && in.inputs.doors_locked &&
          in.inputs.doors_closed) {
        enter(State::FastStartGo, in.now);
        go_sent_ = true;
        ++cycles_in_state_;
        return speed_demand(nibble::kAfterFastStartDcp4, speed_);
      }
      // DCP 12.1.1: activation by a VF speed message (B3 + B0); 12.1.2: then the remaining
      // distance 0x0000 while the car is held at the level. The stop message of 12.2.2
      // (B2 = 0) stays distinct from this hold.
      if (cycles_in_state_ <= speed_cycles(config)) {
        return speed_demand(nibble::kSpeed, dcp::Speed::VF);
      }
      Demand hold = distance_demand(nibble::kDistance, ctx);
      hold.data_word = 0x0000;
      return hold;
    }

    case State::FastStartGo:
      if (cycles_in_state_ <= speed_cycles(config)) {
        return speed_demand(nibble::kAfterFastStartDcp4, speed_);
      }
      enter(State::Distance, in.now);
      return distance_demand(nibble::kDistance, ctx);

    case State::SpeedMessage:
      if (cycles_in_state_ <= speed_cycles(config)) {
        return speed_demand(nibble::kSpeed, speed_);
      }
      // DCP 4.1 S5: the drive confirms the speed message before the travel starts.
      if (!(in.reply_fresh && in.status.accepted)) {
        if (since_ms >= config.start_timeout_ms) {
          request_stop(lift::Cause::TargetRefused);
          return distance_demand(nibble::kStop, ctx);
        }
        return speed_demand(nibble::kSpeed, speed_);
      }
      enter(State::Distance, in.now);
      go_sent_ = true;
      return distance_demand(nibble::kDistance, ctx);

    case State::Distance:
      track_acceptance(ctx);
      if (!brake_seen_open_ && since_ms >= config.start_timeout_ms) {
        request_stop(lift::Cause::DriveDidNotStart);
        return distance_demand(nibble::kStop, ctx);
      }
      // DCP 11.1.2 step 4: B2 withdrawn only once S6 fell at the level.
      if ((brake_seen_open_ && !in.status.brake_open) ||
          (travel_seen_ && !in.status.travel_active)) {
        enter(State::TravelEnd, in.now);
        return step(ctx);
      }
      return distance_demand(nibble::kDistance, ctx);

    case State::FastStop:
      if (!in.status.brake_open) {
        enter(State::TravelEnd, in.now);
        return step(ctx);
      }
      return speed_demand(nibble::kAfterFastStartDcp4, dcp::Speed::VF);  // DCP 13.1

    case State::TravelEnd:
    case State::ControlledAbort:
      if (stop_tail_done(in, since_ms, config, end_cause_)) {
        finish(ctx);
        return {};
      }
      return distance_demand(nibble::kStop, ctx);
  }
  return {};
}

}  // namespace liftd::travel
