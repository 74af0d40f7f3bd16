#include "lift/rules.hpp"

namespace liftd::lift {

Inputs LiftRules::current_inputs(MonoTime now) const noexcept {
  Inputs in = provider_inputs_;
  in.valid = inputs_seen_ && now - inputs_at_ <= inputs_timeout_;
  if (api_inspection_) {
    in.inspection = true;
    const bool held = now <= api_hold_until_;
    in.button_up = in.button_up || (held && api_direction_ == Direction::Up);
    in.button_down = in.button_down || (held && api_direction_ == Direction::Down);
  }
  return in;
}

Answer LiftRules::answer_call(LiftModel& lift, bool add, std::size_t floor,
                              bool shutting_down) noexcept {
  if (!add) {
    if (!lift.cancel_call(floor)) return {ReplyCode::BadRequest, "floor is not queued"};
    return {};
  }
  if (shutting_down) return {ReplyCode::NotReady, "the service is stopping"};
  switch (lift.add_call(floor)) {
    case CallError::None:
      return {};
    case CallError::NoSuchFloor:
      return {ReplyCode::BadRequest, "no such floor"};
    case CallError::AlreadyQueued:
      return {ReplyCode::Ok, "already queued"};
    case CallError::Full:
      return {ReplyCode::Busy, "calls queue full"};
  }
  return {ReplyCode::BadRequest, "no such floor"};
}

}  // namespace liftd::lift
