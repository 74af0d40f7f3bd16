#include "dcp/travel/dcp3_travel.hpp"

namespace liftd::travel {

void Dcp3Travel::begin(const TravelRequest& request, Direction direction,
                       const CycleInput& in) noexcept {
  kind_ = request.kind;
  speed_ = kind_ == TravelKind::Dcp3Crawl ? dcp::Speed::V0 : request.speed;
  direction_ = direction;
  target_mm_ = request.target_mm;
  fast_start_ = request.fast_start;
  by_position_ = request.by_position;
  crawl_timeout_ms_ = request.crawl_timeout_ms;
  go_sent_ = false;
  brake_seen_open_ = false;
  travel_seen_ = false;
  end_cause_ = lift::Cause::None;
  protocol_ = in.protocol;
  now_ = in.now;
  enter(fast_start_ ? State::FastStartHold : State::SpeedMessage, in.now);
}

void Dcp3Travel::enter(State state, MonoTime now) noexcept {
  state_ = state;
  entered_ = now;
  cycles_in_state_ = 0;
}

void Dcp3Travel::request_stop(lift::Cause cause) noexcept {
  // A fast stop (DCP 13) already ends the travel on its own ramp.
  if (state_ == State::Idle || state_ == State::TravelEnd || state_ == State::ControlledAbort ||
      state_ == State::FastStop) {
    return;
  }
  end_cause_ = cause;
  enter(State::ControlledAbort, now_);
}

bool Dcp3Travel::stop_at(std::int64_t target_mm) noexcept {
  // Only before the deceleration point: from there on the car already crawls to its level. The
  // go after a fast start (DCP 12.1.3) is a moving travel too.
  if ((state_ != State::Travel && state_ != State::FastStartGo) || speed_ == dcp::Speed::V0) {
    return false;
  }
  target_mm_ = target_mm;
  return true;
}

bool Dcp3Travel::end_crawl_at(std::int64_t target_mm) noexcept {
  if (state_ != State::Travel || speed_ != dcp::Speed::V0 || !by_position_) return false;
  target_mm_ = target_mm;
  return true;
}

void Dcp3Travel::request_fast_stop() noexcept {
  if (state_ == State::Travel || state_ == State::Creep || state_ == State::FastStartGo) {
    end_cause_ = lift::Cause::StopRequested;
    enter(State::FastStop, now_);
  } else {
    request_stop(lift::Cause::StopRequested);
  }
}

Demand Dcp3Travel::demand(std::uint8_t message, std::uint16_t data_word) const noexcept {
  Demand out;
  out.command = command_byte(message, direction_);
  out.data_word = data_word;
  out.profile.doors_locked_required =
      !(state_ == State::FastStartHold ||
        (state_ == State::ControlledAbort && fast_start_ && !go_sent_));
  return out;
}

bool Dcp3Travel::decel_point(const StepContext& ctx) const noexcept {
  if (ctx.config.dcp3_reference == Dcp3Reference::ShaftSignals && !by_position_) {
    return ctx.in.inputs.decel_point(speed_number(speed_), direction_);
  }
  if (!ctx.in.position_mm) return false;
  const auto svx = ctx.config.dcp3_decel_distance_mm[speed_index(speed_)];
  return remaining_mm(target_mm_, *ctx.in.position_mm, direction_) <=
         static_cast<std::int64_t>(svx);
}

bool Dcp3Travel::at_level(const StepContext& ctx) const noexcept {
  if (ctx.config.dcp3_reference == Dcp3Reference::ShaftSignals && !by_position_) {
    return ctx.in.inputs.level_zone;
  }
  if (!ctx.in.position_mm) return false;
  // DCP 10.1.1 step 4: B2 off at the level, which by position is the crawl stop distance ahead
  // of it (dcp3_stop_lead_mm). Not the level tolerance: that says whether a car standing still
  // is level, and withdrawing B2 inside it would stop every car short by the tolerance.
  return remaining_mm(target_mm_, *ctx.in.position_mm, direction_) <=
         static_cast<std::int64_t>(ctx.config.dcp3_stop_lead_mm);
}

void Dcp3Travel::finish(StepContext& ctx) noexcept {
  ctx.emit_end(kind_, end_cause_, target_mm_);
  state_ = State::Idle;
}

// Over 120 lines: one switch over the DCP3 travel states (DCP 10, 12, 13): split, it would
// hide the sequence.
Demand Dcp3Travel::step(StepContext& ctx) noexcept {
  const CycleInput& in = ctx.in;
  const TravelConfig& config = ctx.config;
  now_ = in.now;
  if (in.status.brake_open) brake_seen_open_ = true;
  if (in.status.travel_active && !travel_seen_ &&
      (state_ == State::Travel || state_ == State::FastStartGo || state_ == State::Creep)) {
    travel_seen_ = true;
    ctx.emit(Event::Type::Started, kind_, lift::Cause::None, target_mm_);
  }
  ++cycles_in_state_;
  const auto since_ms = elapsed_ms(in.now, entered_);
  const std::uint8_t after_fast_start = after_fast_start_nibble(protocol_);

  switch (state_) {
    case State::Idle:
      return {};

    case State::FastStartHold:
      if (cycles_in_state_ == 1 && in.inputs.door_reversal) {
        // Reversal before the VF message went out: nothing to stop, no B0 at all.
        end_cause_ = lift::Cause::DoorReversal;
        finish(ctx);
        return {};
      }
      if (cycles_in_state_ == 1) {
        ctx.emit(Event::Type::FastStartArmed, kind_, lift::Cause::None, target_mm_);
      }
      if (in.inputs.door_reversal) {  // DCP 12.2: stop sequence on door reversal
        request_stop(lift::Cause::DoorReversal);
        return demand(nibble::kStop, 0);
      }
      if (since_ms >= config.fast_start_timeout_ms) {  // DCP 12.1.2
        request_stop(lift::Cause::FastStartTimeout);
        return demand(nibble::kStop, 0);
      }
      if (cycles_in_state_ > speed_cycles(config) && in.inputs.doors_locked &&
          in.inputs.doors_closed) {
        enter(State::FastStartGo, in.now);
        go_sent_ = true;
        ++cycles_in_state_;
        return demand(after_fast_start, dcp::speed_word(speed_));
      }
      return demand(nibble::kSpeed, dcp::speed_word(dcp::Speed::VF));  // DCP 12.1.1

    case State::FastStartGo:
      if (cycles_in_state_ <= speed_cycles(config)) {
        return demand(after_fast_start, dcp::speed_word(speed_));  // DCP 12.1.3
      }
      enter(State::Travel, in.now);
      return step(ctx);

    case State::SpeedMessage:
      if (cycles_in_state_ <= speed_cycles(config)) {
        return demand(nibble::kSpeed, dcp::speed_word(speed_));
      }
      // DCP 4.1 S5: the drive confirms the speed message before the travel command follows.
      if (!(in.reply_fresh && in.status.accepted)) {
        if (since_ms >= config.start_timeout_ms) {
          request_stop(lift::Cause::TargetRefused);
          return demand(nibble::kStop, 0);
        }
        return demand(nibble::kSpeed, dcp::speed_word(speed_));
      }
      enter(State::Travel, in.now);
      go_sent_ = true;
      return step(ctx);

    case State::Travel:
      if (!brake_seen_open_ && since_ms >= config.start_timeout_ms) {
        request_stop(lift::Cause::DriveDidNotStart);
        return demand(nibble::kStop, 0);
      }
      if (speed_ == dcp::Speed::V0) {
        if (since_ms >= crawl_timeout_ms(config)) {
          request_stop(lift::Cause::LevelNotReached);
          return demand(nibble::kStop, 0);
        }
        // DCP 10.3 step 3: B1 and B2 withdrawn together at the level; the drive positions.
        if (at_level(ctx)) {
          enter(State::TravelEnd, in.now);
          return demand(nibble::kStop, 0);
        }
        return demand(nibble::kTravel, 0);
      }
      if (decel_point(ctx)) {  // DCP 10.1.1 step 3: B1 off at SVx before the level
        // B1 alone first, whatever the position says: the drive slows to crawl on it, and only
        // then does B2 position the car (step 4); both at once would be a stop message at
        // speed (DCP 3.5.3.2).
        enter(State::Creep, in.now);
        return demand(nibble::kDistance, 0);
      }
      return demand(nibble::kTravel, 0);

    case State::Creep:
      if (since_ms >= crawl_timeout_ms(config)) {
        request_stop(lift::Cause::LevelNotReached);
        return demand(nibble::kStop, 0);
      }
      if (at_level(ctx)) {  // DCP 10.1.1 steps 4, 5: B2 off at the level, B0 until S1 = 0
        enter(State::TravelEnd, in.now);
        return demand(nibble::kStop, 0);
      }
      return demand(nibble::kDistance, 0);

    case State::FastStop:
      if (!in.status.brake_open) {
        enter(State::TravelEnd, in.now);
        return step(ctx);
      }
      return demand(after_fast_start, dcp::speed_word(dcp::Speed::VF));  // DCP 13.1

    case State::TravelEnd:
    case State::ControlledAbort:
      if (stop_tail_done(in, since_ms, config, end_cause_)) {
        finish(ctx);
        return {};
      }
      return demand(nibble::kStop, 0);
  }
  return {};
}

}  // namespace liftd::travel
