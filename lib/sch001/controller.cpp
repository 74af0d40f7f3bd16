#include "sch001/controller.hpp"

#include <cstdlib>
#include <stdexcept>
#include <type_traits>

namespace liftd::sch001 {
namespace {

/// After start, the endpoint, the inputs and the position get this long before they count as
/// lost (the DCP lift allows two input timeouts the same way).
MonoTime start_grace(const ControllerConfig& config) {
  return config.inputs_timeout * 2;
}

/// How far from its nearest level a car at rest may have sunk for liftd to relevel it by
/// itself: beyond this it is not "at a floor" any more (the door zone of common practice).
constexpr std::int64_t kRelevelZoneMm = 150;

}  // namespace

std::string_view fault_text(FaultCode code) noexcept {
  switch (code) {
    case FaultCode::LinkFault:
      return "SCH001 link fault: no frame from the card for 10 s (card document 3f), or the CAN "
             "bus or socket failed; no travel command goes out";
    case FaultCode::DriveFault:
      return "the SCH001 card reports ERR: no travel command may go out (card document 3d)";
    case FaultCode::SafetyChain:
      return "safety chain open";
    case FaultCode::InputsLost:
      return "no input update from the I/O provider within inputs.timeout_ms";
    case FaultCode::PositionLost:
      return "the car position is unknown or stale: no travel possible";
    case FaultCode::AdvanceWarning:  // the card has no advance warning
    case FaultCode::kCount:
      break;
  }
  return "internal";
}

Sch001Controller::Sch001Controller(const ControllerConfig& config,
                                   const lift::PositionSource& position, MonoTime start)
    : config_(config),
      position_(position),
      link_(config.link, start),
      travel_(config.hydraulic),
      lift_(config.lift),
      start_at_(start) {
  if (!lift_.set_floors(config.floors_mm)) {
    throw std::invalid_argument("floors: need 2 or more strictly increasing levels");
  }
  if (config.floors_mm.size() > 255) {
    throw std::invalid_argument("floors: the SCH001 frame carries floor numbers 0..255");
  }
  publish(start);
}

// ---- rt::CanEngine ----

std::optional<can::Frame> Sch001Controller::on_frame(const can::Frame& frame,
                                                     MonoTime now) noexcept {
  const FrameResult r = link_.on_frame(frame, now);
  if (r.change != LinkChange::None) {
    ControllerEvent e;
    e.kind = ControllerEvent::Kind::Link;
    e.at = now;
    e.link = r.change;
    push_event(e);
  }
  if (r.status_changed && link_.status()) {
    ControllerEvent e;
    e.kind = ControllerEvent::Kind::Card;
    e.at = now;
    e.card = *link_.status();
    push_event(e);
  }
  if (frame.id == link_.ids().from_card) bus_fault_ = false;  // the bus carries frames again
  if (r.answer && r.answer->length == kCommandFrameLength) {
    bits_sent_ = CommandBits::from_byte(r.answer->data[1]);
    current_sent_ = r.answer->data[2];
    destination_sent_ = r.answer->data[3];
  }
  // The sequencing sees the new status at once (the answer already obeyed it: 3d, 3e).
  step(now);
  return r.answer;
}

void Sch001Controller::on_bus_error(const can::ErrorReport& report, MonoTime now) noexcept {
  ++bus_errors_;
  last_bus_error_ = report;
  if (report.is_fault()) bus_fault_ = true;
  if (report.restarted || report.back_to_active) bus_fault_ = false;
  ControllerEvent e;
  e.kind = ControllerEvent::Kind::BusError;
  e.at = now;
  e.bus_error = report;
  push_event(e);
  step(now);
}

void Sch001Controller::on_endpoint(bool up, MonoTime now) noexcept {
  endpoint_up_ = up;
  endpoint_failed_ = !up;
  if (up) bus_fault_ = false;
  ControllerEvent e;
  e.kind = ControllerEvent::Kind::Endpoint;
  e.at = now;
  e.endpoint_up = up;
  push_event(e);
  step(now);
}

void Sch001Controller::on_tick(MonoTime now) noexcept {
  if (link_.on_tick(now) == LinkChange::Silent) {
    ControllerEvent e;
    e.kind = ControllerEvent::Kind::Link;
    e.at = now;
    e.link = LinkChange::Silent;
    push_event(e);
  }
  step(now);
}

// ---- one step ----

TickInput Sch001Controller::build_input(MonoTime now) noexcept {
  TickInput in;
  in.now = now;
  in.position_mm = position_.position_mm(now);
  in.inputs = provider_inputs_;
  in.inputs.valid = inputs_seen_ && now - inputs_at_ <= config_.inputs_timeout;
  if (api_inspection_) {
    in.inputs.inspection = true;
    const bool held = now <= api_hold_until_;
    in.inputs.button_up = in.inputs.button_up || (held && api_direction_ == lift::Direction::Up);
    in.inputs.button_down =
        in.inputs.button_down || (held && api_direction_ == lift::Direction::Down);
  }
  in.card_allows_travel = link_.travel_allowed();
  in.card_error = link_.status() && link_.status()->err;
  in.card_silent = link_.silent();
  in.bus_ok = endpoint_up_ && !bus_fault_;
  return in;
}

void Sch001Controller::step(MonoTime now) noexcept {
  ++steps_;
  TickInput in = build_input(now);
  ControllerCommand command;
  while (commands_.try_pop(command)) {
    handle(command, in);
    in = build_input(now);  // an inputs command changes what follows
  }
  if (!place_known_ && in.position_mm) {
    // 3c: the current floor is the one the car last stopped at; at start, the nearest.
    if (const auto nearest = lift_.floors().nearest(*in.position_mm)) {
      travel_.set_current_floor(*nearest);
      place_known_ = true;
    }
  }
  // Inspection (the car-roof switch, or the API's): hold-to-run with the buttons.
  if (in.inputs.inspection) {
    if (travel_.kind() == TravelKind::Travel || travel_.kind() == TravelKind::Relevel) {
      travel_.abort(Cause::Stopped, now);
    }
    const lift::Direction d =
        in.inputs.button_up == in.inputs.button_down
            ? lift::Direction::None
            : (in.inputs.button_up ? lift::Direction::Up : lift::Direction::Down);
    (void)travel_.inspect(shutting_down_ ? lift::Direction::None : d, in);
  } else if (travel_.kind() == TravelKind::Inspection) {
    (void)travel_.inspect(lift::Direction::None, in);
  }
  update_faults(in, now);
  last_output_ = travel_.tick(lift_.floors(), in);
  drain_travel(now);
  if (!shutting_down_) {
    serve_calls(in);
    maybe_relevel(in);
    if (travel_.kind() != TravelKind::None) last_output_ = travel_.tick(lift_.floors(), in);
    drain_travel(now);
  }
  Command wanted;
  wanted.bits = last_output_.bits;
  wanted.current_floor = static_cast<std::uint8_t>(last_output_.current_floor);
  wanted.destination_floor = static_cast<std::uint8_t>(last_output_.destination_floor);
  link_.set_command(wanted);
  lift_.update(in.position_mm, travel_.direction(), std::nullopt);
  publish(now);
}

// ---- commands ----

void Sch001Controller::reply(std::uint32_t tag, ReplyCode code, std::string_view detail,
                             std::optional<std::size_t> floor) noexcept {
  if (tag == 0) return;
  CommandReply r;
  r.tag = tag;
  r.code = code;
  r.detail = detail;
  r.floor = floor;
  (void)replies_.try_push(r);  // as deep as the command queue
}

ReplyCode Sch001Controller::code_for(Cause cause) noexcept {
  switch (cause) {
    case Cause::CardError:
    case Cause::CardSilent:
    case Cause::BusFault:
    case Cause::SafetyChain:
    case Cause::InputsLost:
    case Cause::PositionLost:
      return ReplyCode::Fault;
    default:
      return ReplyCode::NotReady;
  }
}

std::string_view Sch001Controller::text_for(Cause cause) noexcept {
  switch (cause) {
    case Cause::CardError:
      return "the SCH001 card reports ERR (card document 3d)";
    case Cause::CardNotReady:
      return "the SCH001 card is not ready (RDY = 0, or no status frame heard yet; card document "
             "3e)";
    case Cause::CardSilent:
      return "no frame from the SCH001 card for 10 s (card document 3f)";
    case Cause::BusFault:
      return "the CAN bus or socket is not working";
    case Cause::SafetyChain:
      return "safety chain open";
    case Cause::DoorsUnlocked:
      return "doors not locked";
    case Cause::InputsLost:
      return "machine inputs lost";
    case Cause::PositionLost:
      return "car position unknown";
    default:
      return "not possible now";
  }
}

void Sch001Controller::handle(const ControllerCommand& command, TickInput& in) noexcept {
  const std::uint32_t tag = command.tag;
  std::visit(
      [&](const auto& body) {
        using T = std::decay_t<decltype(body)>;
        if constexpr (std::is_same_v<T, InputsCommand>) {
          provider_inputs_ = body.inputs;
          inputs_at_ = in.now;
          inputs_seen_ = true;
          reply(tag, ReplyCode::Ok);
        } else if constexpr (std::is_same_v<T, ShutdownCommand>) {
          shutting_down_ = true;
          lift_.calls().clear();
          if (body.force) {
            travel_.abort(Cause::Shutdown, in.now);
          } else {
            (void)travel_.stop(lift_.floors(), in);
          }
          reply(tag, ReplyCode::Ok);
        } else if constexpr (std::is_same_v<T, TravelCommand>) {
          if (shutting_down_) return reply(tag, ReplyCode::NotReady, "the service is stopping");
          if (body.floor >= lift_.floors().size()) {
            return reply(tag, ReplyCode::BadRequest, "no such floor in this installation");
          }
          if (in.inputs.inspection) {
            return reply(tag, ReplyCode::NotReady, "inspection is on");
          }
          if (travel_.kind() != TravelKind::None) {
            return reply(tag, ReplyCode::Busy, "a travel is running");
          }
          if (in.position_mm && std::llabs(*in.position_mm - lift_.floors().level_mm(body.floor)) <=
                                    static_cast<std::int64_t>(config_.lift.level_tolerance_mm)) {
            return reply(tag, ReplyCode::NotReady, "the car is already at that level");
          }
          const Cause why = travel_.start_travel(lift_.floors(), body.floor, body.speed, in);
          if (why != Cause::None) return reply(tag, code_for(why), text_for(why));
          travel_tag_ = tag;
          reply(tag, ReplyCode::Ok);
        } else if constexpr (std::is_same_v<T, StopCommand>) {
          lift_.calls().clear();
          const auto floor = travel_.stop(lift_.floors(), in);
          reply(tag, ReplyCode::Ok, {}, floor);
        } else if constexpr (std::is_same_v<T, RelevelCommand>) {
          if (shutting_down_) return reply(tag, ReplyCode::NotReady, "the service is stopping");
          if (travel_.kind() != TravelKind::None) {
            return reply(tag, ReplyCode::Busy, "a travel is running");
          }
          if (!in.position_mm) return reply(tag, ReplyCode::Fault, text_for(Cause::PositionLost));
          const auto nearest = lift_.floors().nearest(*in.position_mm);
          if (!nearest) return reply(tag, ReplyCode::NotReady, "no floor");
          if (std::llabs(*in.position_mm - lift_.floors().level_mm(*nearest)) <=
              static_cast<std::int64_t>(config_.hydraulic.stop_tolerance_mm)) {
            return reply(tag, ReplyCode::NotReady, "the car is level: nothing to relevel");
          }
          const Cause why = travel_.start_relevel(lift_.floors(), *nearest, in);
          if (why != Cause::None) return reply(tag, code_for(why), text_for(why));
          reply(tag, ReplyCode::Ok, {}, nearest);
        } else if constexpr (std::is_same_v<T, InspectionCommand>) {
          api_inspection_ = body.on;
          api_direction_ = body.on ? body.direction : lift::Direction::None;
          api_hold_until_ = in.now + config_.inspection_hold;
          reply(tag, ReplyCode::Ok);
        } else if constexpr (std::is_same_v<T, CallCommand>) {
          if (body.add) {
            if (shutting_down_) return reply(tag, ReplyCode::NotReady, "the service is stopping");
            switch (lift_.add_call(body.floor)) {
              case lift::CallError::None:
                return reply(tag, ReplyCode::Ok);
              case lift::CallError::NoSuchFloor:
                return reply(tag, ReplyCode::BadRequest, "no such floor in this installation");
              default:
                return reply(tag, ReplyCode::Busy, "the calls queue is full");
            }
          }
          if (!lift_.cancel_call(body.floor)) {
            return reply(tag, ReplyCode::BadRequest, "that floor is not in the calls queue");
          }
          reply(tag, ReplyCode::Ok);
        }
      },
      command.body);
}

// ---- travels, calls, faults ----

void Sch001Controller::drain_travel(MonoTime now) noexcept {
  TravelEvent t;
  while (travel_.poll_event(t)) {
    ControllerEvent e;
    e.kind = ControllerEvent::Kind::Travel;
    e.at = now;
    e.travel = t;
    push_event(e);
    if (t.type == TravelEvent::Type::Finished && t.kind == TravelKind::Travel) {
      const auto front = lift_.calls().front();
      if (front && *front == t.floor) {
        lift_.calls().pop_front();
        ControllerEvent served;
        served.kind = ControllerEvent::Kind::CallServed;
        served.at = now;
        served.floor = t.floor;
        push_event(served);
      }
    }
  }
  travel_dropped_.store(travel_.dropped_events(), std::memory_order_relaxed);
}

void Sch001Controller::serve_calls(TickInput& in) noexcept {
  if (travel_.kind() != TravelKind::None || in.inputs.inspection) return;
  const auto front = lift_.calls().front();
  if (!front) return;
  const std::size_t floor = *front;
  if (in.position_mm && std::llabs(*in.position_mm - lift_.floors().level_mm(floor)) <=
                            static_cast<std::int64_t>(config_.lift.level_tolerance_mm)) {
    lift_.calls().pop_front();  // already there
    ControllerEvent served;
    served.kind = ControllerEvent::Kind::CallServed;
    served.at = in.now;
    served.floor = floor;
    push_event(served);
    return;
  }
  (void)travel_.start_travel(lift_.floors(), floor, Speed::V4, in);  // waits while refused
}

void Sch001Controller::maybe_relevel(TickInput& in) noexcept {
  if (!config_.auto_relevel || travel_.kind() != TravelKind::None || in.inputs.inspection ||
      !in.position_mm) {
    return;
  }
  const auto nearest = lift_.floors().nearest(*in.position_mm);
  if (!nearest) return;
  const std::int64_t off = std::llabs(*in.position_mm - lift_.floors().level_mm(*nearest));
  if (off <= static_cast<std::int64_t>(config_.hydraulic.relevel_start_mm) ||
      off > kRelevelZoneMm) {
    return;
  }
  // Only where it may start now; otherwise it waits (a refused relevel is no event).
  if (travel_.forbidding(TravelKind::Relevel, in) == Cause::None) {
    (void)travel_.start_relevel(lift_.floors(), *nearest, in);
  }
}

void Sch001Controller::update_faults(const TickInput& in, MonoTime now) noexcept {
  const bool started = now - start_at_ > start_grace(config_);
  // A failed endpoint is a fault at once; one that has not opened yet after the start grace.
  set_fault(FaultCode::LinkFault,
            in.card_silent || bus_fault_ || endpoint_failed_ || (started && !endpoint_up_), now);
  set_fault(FaultCode::DriveFault, in.card_error && !in.card_silent, now);
  set_fault(FaultCode::InputsLost, started && !in.inputs.valid, now);
  set_fault(FaultCode::SafetyChain, in.inputs.valid && !in.inputs.safety_chain_closed, now);
  set_fault(FaultCode::PositionLost, started && !in.position_mm, now);
}

void Sch001Controller::set_fault(FaultCode code, bool active, MonoTime now) noexcept {
  const auto i = static_cast<std::size_t>(code);
  if (faults_[i] == active) return;
  faults_[i] = active;
  if (active) fault_since_[i] = now;
  ControllerEvent e;
  e.kind = active ? ControllerEvent::Kind::FaultRaised : ControllerEvent::Kind::FaultCleared;
  e.at = now;
  e.fault = code;
  push_event(e);
}

void Sch001Controller::push_event(const ControllerEvent& event) noexcept {
  if (!events_.try_push(event)) dropped_events_.fetch_add(1, std::memory_order_relaxed);
}

void Sch001Controller::publish(MonoTime now) noexcept {
  ControllerSnapshot s;
  s.at = now;
  s.steps = steps_;
  s.endpoint_up = endpoint_up_ && !bus_fault_;
  s.heard = link_.heard();
  s.silent = link_.silent();
  s.timeout_enabled = link_.timeout_enabled();
  s.card = link_.status();
  s.single_unit = link_.unit_signals_valid();
  s.counters = link_.counters();
  s.bus_errors = bus_errors_;
  s.last_bus_error = last_bus_error_;
  s.bits_sent = bits_sent_;
  s.current_floor_sent = current_sent_;
  s.destination_floor_sent = destination_sent_;
  s.motor_on = last_output_.motor_on;
  s.position_mm = lift_.position_mm();
  s.floor = lift_.current_floor();
  s.travel_kind = travel_.kind();
  s.phase = travel_.phase();
  s.direction = travel_.direction();
  s.target_floor = travel_.target();
  s.inputs = build_input(now).inputs;
  s.call_count = std::min(lift_.calls().size(), kMaxSnapshotCalls);
  for (std::size_t i = 0; i < s.call_count; ++i) {
    s.calls[i] = static_cast<std::uint8_t>(lift_.calls().at(i));
  }
  s.faults = faults_;
  s.fault_since = fault_since_;
  s.shutting_down = shutting_down_;
  s.quiesced = shutting_down_ && travel_.kind() == TravelKind::None && !bits_sent_.any();
  snapshot_.publish(s);
}

}  // namespace liftd::sch001
