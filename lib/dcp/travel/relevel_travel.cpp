#include "dcp/travel/relevel_travel.hpp"

namespace liftd::travel {

void RelevelTravel::begin(const TravelRequest& request, Direction direction,
                          const CycleInput& in) noexcept {
  direction_ = direction;
  target_mm_ = request.target_mm;
  brake_seen_open_ = false;
  travel_seen_ = false;
  end_cause_ = lift::Cause::None;
  now_ = in.now;
  enter(State::SpeedMessage, in.now);
}

void RelevelTravel::enter(State state, MonoTime now) noexcept {
  state_ = state;
  entered_ = now;
  cycles_in_state_ = 0;
}

void RelevelTravel::request_stop(lift::Cause cause) noexcept {
  if (state_ != State::SpeedMessage && state_ != State::Relevel) return;
  end_cause_ = cause;
  enter(State::ControlledAbort, now_);
}

Demand RelevelTravel::demand(std::uint8_t message, std::uint16_t data_word) const noexcept {
  Demand out;
  out.command = command_byte(message, direction_);
  out.data_word = data_word;
  out.profile.door_bridge_allowed = true;  // relevelling with bridged door contacts
  return out;
}

bool RelevelTravel::at_level(const StepContext& ctx) const noexcept {
  if (ctx.in.position_mm) {
    return remaining_mm(target_mm_, *ctx.in.position_mm, direction_) <=
           static_cast<std::int64_t>(ctx.config.level_tolerance_mm);
  }
  // Without a position the shaft says it: inside the level zone, and the relevelling signal that
  // asked for this direction has dropped (the car is back within the tolerance).
  return ctx.in.inputs.level_zone && !ctx.in.inputs.relevel_towards(direction_);
}

void RelevelTravel::finish(StepContext& ctx) noexcept {
  ctx.emit_end(TravelKind::Relevel, end_cause_, target_mm_);
  state_ = State::Idle;
}

Demand RelevelTravel::step(StepContext& ctx) noexcept {
  const CycleInput& in = ctx.in;
  now_ = in.now;
  if (in.status.brake_open) brake_seen_open_ = true;
  if (in.status.travel_active && !travel_seen_ && state_ == State::Relevel) {
    travel_seen_ = true;
    ctx.emit(Event::Type::Started, TravelKind::Relevel, lift::Cause::None, target_mm_);
  }
  ++cycles_in_state_;
  const auto since_ms = elapsed_ms(in.now, entered_);

  switch (state_) {
    case State::Idle:
      return {};

    case State::SpeedMessage:
      if (cycles_in_state_ <= speed_cycles(ctx.config)) {
        return demand(nibble::kSpeed, dcp::speed_word(dcp::Speed::VN));
      }
      enter(State::Relevel, in.now);
      return step(ctx);

    case State::Relevel:
      if (!brake_seen_open_ && since_ms >= ctx.config.start_timeout_ms) {
        request_stop(lift::Cause::DriveDidNotStart);
        return demand(nibble::kStop, 0);
      }
      if (since_ms >= ctx.config.crawl_timeout_ms) {
        request_stop(lift::Cause::LevelNotReached);
        return demand(nibble::kStop, 0);
      }
      if (at_level(ctx)) {
        if (ctx.config.relevel_electric_stop) {
          enter(State::ElectricStop, in.now);
          return demand(nibble::kStop, 0);
        }
        enter(State::Coast, in.now);
        return {};
      }
      return demand(nibble::kRelevelling, 0);

    case State::Coast:
      if (!in.status.travel_active || since_ms >= ctx.config.stop_timeout_ms) {
        if (in.status.travel_active) end_cause_ = lift::Cause::DriveDidNotStop;
        finish(ctx);
      }
      return {};

    case State::ElectricStop:
    case State::ControlledAbort:
      if (stop_tail_done(in, since_ms, ctx.config, end_cause_)) {
        finish(ctx);
        return {};
      }
      return demand(nibble::kStop, 0);
  }
  return {};
}

}  // namespace liftd::travel
