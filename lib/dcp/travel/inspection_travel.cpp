#include "dcp/travel/inspection_travel.hpp"

namespace liftd::travel {

namespace {
Direction pressed_direction(const lift::Inputs& inputs) noexcept {
  if (!(inputs.inspection || inputs.recall)) return Direction::None;
  if (inputs.button_up == inputs.button_down) return Direction::None;  // none, or both: stop
  return inputs.button_up ? Direction::Up : Direction::Down;
}
}  // namespace

void InspectionTravel::abort_immediate() noexcept {
  aborted_ = true;
  need_release_ = true;  // a new button travel only after the button was let go
  state_ = State::Released;
  cycles_in_state_ = 0;
}

Demand InspectionTravel::demand(std::uint8_t message, std::uint16_t data_word) const noexcept {
  Demand out;
  out.command = command_byte(message, direction_);
  out.data_word = data_word;
  // DCP 9.2.1: the safety chain (with the door contacts) decides; no separate doors-locked input.
  out.profile.doors_locked_required = false;
  return out;
}

bool InspectionTravel::in_end_zone(const lift::Inputs& inputs) const noexcept {
  return direction_ == Direction::Up ? inputs.end_zone_top : inputs.end_zone_bottom;
}

Demand InspectionTravel::step(StepContext& ctx) noexcept {
  const CycleInput& in = ctx.in;
  const Direction pressed = pressed_direction(in.inputs);
  ++cycles_in_state_;
  if (in.status.travel_active && !travel_seen_ && (state_ == State::Vi || state_ == State::Crawl)) {
    travel_seen_ = true;
    ctx.emit(Event::Type::Started, kind_, lift::Cause::None, 0);
  }
  // DCP 9.2.1 step 4: B0 off the moment the button is released (or the direction changes).
  if ((state_ == State::SpeedMessage || state_ == State::Vi || state_ == State::Crawl) &&
      pressed != direction_) {
    state_ = State::Released;
    cycles_in_state_ = 0;
  }

  switch (state_) {
    case State::Idle:
      // DCP 9.1.1: B0 off while stationary; a travel needs S1 = 0 first.
      if (pressed == Direction::None) need_release_ = false;
      if (pressed == Direction::None || need_release_ || in.status.travel_active) return {};
      kind_ = in.inputs.inspection ? TravelKind::Inspection : TravelKind::Recall;
      direction_ = pressed;
      travel_seen_ = false;
      aborted_ = false;
      state_ = State::SpeedMessage;
      cycles_in_state_ = 1;
      return demand(nibble::kSpeed, dcp::speed_word(dcp::Speed::VI));

    case State::SpeedMessage:
      if (cycles_in_state_ <= speed_cycles(ctx.config)) {
        return demand(nibble::kSpeed, dcp::speed_word(dcp::Speed::VI));  // DCP 9.2.1.2 note
      }
      cycles_in_state_ = 0;
      // DCP 9.2.1.2: from inside the end zone towards the end, B2 only (crawl V0).
      state_ = in_end_zone(in.inputs) ? State::Crawl : State::Vi;
      return state_ == State::Crawl ? demand(nibble::kDistance, 0) : demand(nibble::kTravel, 0);

    case State::Vi:
      if (in_end_zone(in.inputs)) {  // DCP 9.2.1.1 step 3: B1 off, crawl while B2
        state_ = State::Crawl;
        cycles_in_state_ = 0;
        return demand(nibble::kDistance, 0);
      }
      return demand(nibble::kTravel, 0);

    case State::Crawl:
      return demand(nibble::kDistance, 0);

    case State::Released:
      if (!in.status.travel_active || !in.link_up) {
        if (!aborted_) ctx.emit(Event::Type::Finished, kind_, lift::Cause::None, 0);
        state_ = State::Idle;
        direction_ = Direction::None;
      }
      return {};
  }
  return {};
}

}  // namespace liftd::travel
