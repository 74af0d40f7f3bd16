#include "lift/rules.hpp"

namespace liftd::lift {

namespace {
// docs/api.md `calls`: the queue does not re-target a running travel.
constexpr std::string_view kAfterRunningTarget =
    "the car keeps travelling to the first queued floor: the change follows it";
}  // namespace

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

Answer LiftRules::answer_call(LiftModel& lift, const CallCommand& call, bool shutting_down,
                              bool heading_for) noexcept {
  using Op = CallCommand::Op;
  if (call.op == Op::Cancel) {
    if (!lift.calls().cancel(call.floor)) return {ReplyCode::BadRequest, "floor is not queued"};
    return {};
  }
  if (shutting_down) return {ReplyCode::NotReady, "the service is stopping"};
  const std::size_t floor_count = lift.floors().size();
  const bool front_kept = heading_for && lift.calls().size() > 0;
  CallError error = CallError::None;
  std::string_view detail;
  switch (call.op) {
    case Op::Add:
      error = lift.calls().add(call.floor, floor_count);
      break;
    case Op::Insert: {
      // Ahead of the floor a travel already runs to means right after it.
      const std::size_t position = call.position.value_or(lift.calls().size());
      const bool moved = front_kept && position == 0;
      error = lift.calls().insert(moved ? 1 : position, call.floor, floor_count);
      if (moved) detail = kAfterRunningTarget;
      break;
    }
    case Op::Set:
      error = lift.calls().set(std::span(call.floors.data(), call.count), floor_count, front_kept);
      if (front_kept) detail = kAfterRunningTarget;
      break;
    case Op::Cancel:
      break;
  }
  switch (error) {
    case CallError::None:
      return {ReplyCode::Ok, detail};
    case CallError::NoSuchFloor:
      return {ReplyCode::BadRequest, "no such floor"};
    case CallError::AlreadyQueued:
      return {ReplyCode::Ok, "already queued"};
    case CallError::Full:
      return {ReplyCode::Busy, "calls queue full"};
    case CallError::BadPosition:
      return {ReplyCode::BadRequest, "position is beyond the end of the queue"};
    case CallError::TwiceInARow:
      return {ReplyCode::BadRequest, "the same floor twice in a row"};
  }
  return {ReplyCode::BadRequest, "no such floor"};
}

}  // namespace liftd::lift
