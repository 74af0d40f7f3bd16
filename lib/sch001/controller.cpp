#include "sch001/controller.hpp"

#include <cstdlib>
#include <stdexcept>
#include <type_traits>

namespace liftd::sch001 {

Sch001Controller::Sch001Controller(const ControllerConfig& config, const PositionSource& position,
                                   MonoTime start)
    : ControllerCore(lift::core_config_of(config, start), config.hydraulic),
      config_(config),
      position_(position),
      link_(config.link, start) {
  if (config.floors_mm.size() > 255) {
    throw std::invalid_argument("floors: the SCH001 frame carries floor numbers 0..255");
  }
  publish(start);
}

// ---- rt::CanEngine ----

void Sch001Controller::on_frame(const can::Frame& frame, MonoTime now,
                                rt::CanOutbox& out) noexcept {
  const FrameResult r = link_.on_frame(frame, now);
  if (r.change != LinkChange::None) {
    ControllerEvent e;
    e.kind = ControllerEvent::Kind::Link;
    e.at = now;
    e.link = r.change;
    push_event(e);
  }
  if (r.status_changed) ++status_changes_;
  // Card document 1.6: no other node may use the card's identifiers. One that sends on ours
  // commands the card beside us: a wiring or set-up fault, never a frame to act on.
  if (frame.id == link_.ids().to_card) own_id_at_ = now;
  if (link_.heard()) endpoint_lost_ = false;                  // the card is heard on this endpoint
  if (frame.id == link_.ids().from_card) bus_fault_ = false;  // the bus carries frames again
  answer_ = r.answer;
  // The sequencing sees the new status at once (the answer already obeyed it: 3d, 3e).
  step(now);
  // The runner sends it when this returns and tells on_sent(); each call starts with an empty
  // outbox, so there is room for this one answer.
  if (answer_ && !out.send(*answer_)) answer_.reset();
}

void Sch001Controller::on_sent(const can::Frame& /*frame: answer_*/, bool delivered,
                               MonoTime now) noexcept {
  // on_frame() stepped already: step again only when the link fault comes or goes.
  const bool was_failing = send_failures_ >= kSendFailuresForFault;
  if (delivered) {
    send_failures_ = 0;
    if (answer_ && answer_->length == kCommandFrameLength) {
      bits_sent_ = CommandBits::from_byte(answer_->data[1]);
      current_sent_ = answer_->data[2];
      destination_sent_ = answer_->data[3];
    }
  } else if (send_failures_ < kSendFailuresForFault) {
    ++send_failures_;
  }
  answer_.reset();
  if (was_failing != (send_failures_ >= kSendFailuresForFault)) {
    step(now);
  } else {
    publish(now);
  }
}

void Sch001Controller::on_bus_error(const can::ErrorReport& report, MonoTime now) noexcept {
  ++bus_errors_;
  last_bus_error_ = report;
  if (report.is_fault()) bus_fault_ = true;
  if (report.restarted || report.back_to_active) bus_fault_ = false;
  step(now);
}

void Sch001Controller::on_endpoint(bool up, MonoTime now) noexcept {
  endpoint_up_ = up;
  if (up) {
    // Whatever the card said on the old endpoint is void: link init, no travel bit, travels
    // refused, until its first frame on this one (card document 3d, 3e).
    link_.endpoint_reopened(now);
    bus_fault_ = false;
    send_failures_ = 0;
    bits_sent_ = CommandBits{};
  } else {
    endpoint_lost_ = true;
  }
  push_event({.kind = ControllerEvent::Kind::Endpoint, .at = now, .endpoint_up = up});
  step(now);
}

void Sch001Controller::on_tick(MonoTime now, rt::CanOutbox& /*out: only answers*/) noexcept {
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
  in.inputs = current_inputs(now);
  in.card_allows_travel = link_.travel_allowed();
  in.card_error = link_.status() && link_.status()->err;
  in.card_silent = link_.silent();
  in.bus_ok =
      endpoint_up_ && !bus_fault_ && send_failures_ < kSendFailuresForFault && !foreign_sender_;
  return in;
}

void Sch001Controller::step(MonoTime now) noexcept {
  foreign_sender_ = own_id_at_ && now - *own_id_at_ < kCardTimeout;
  const TickInput in = step_lift(now, *this);
  Command wanted;
  wanted.bits = last_output_.bits;
  wanted.current_floor = static_cast<std::uint8_t>(last_output_.current_floor);
  wanted.destination_floor = static_cast<std::uint8_t>(last_output_.destination_floor);
  link_.set_command(wanted);
  lift_.update(in.position_mm, travel_.direction(), std::nullopt);
  lift::DriveBits bits;
  bits.command = last_output_.bits.to_byte();  // 3c: the command byte of our answer
  bits.status = link_.status() ? link_.status()->to_byte() : 0;  // 3b: the card's status byte
  sample_travel(now, travel_.kind() != TravelKind::None, HydraulicTravel::kind_name(travel_.kind()),
                in.position_mm, travel_.target(), bits);
  publish(now);
}

// ---- commands ----

namespace {

/// The card's own refusals (card document 3d, 3e, 3f); the machine's are every kind's.
constexpr lift::CauseRefusal kCardRefusals[] = {
    {lift::Cause::DriveFault, ReplyCode::Fault, "the SCH001 card reports ERR (card document 3d)"},
    {lift::Cause::DriveNotReady, ReplyCode::NotReady,
     "the SCH001 card is not ready (RDY = 0, or no status frame heard yet; card document 3e)"},
    {lift::Cause::CardSilent, ReplyCode::Fault,
     "no frame from the SCH001 card for 10 s (card document 3f)"},
    {lift::Cause::BusFault, ReplyCode::Fault, "the CAN bus or socket is not working"},
};

}  // namespace

lift::Refusal Sch001Controller::refusal(lift::Cause cause) noexcept {
  return lift::refusal_for(kCardRefusals, cause);
}

void Sch001Controller::handle(const ControllerCommand& command, TickInput& in) noexcept {
  // Every command the hydraulic lift takes is every lift's.
  std::visit([&](const auto& body) { handle_lift(command.tag, body, in, *this); }, command.body);
}

std::optional<lift::Refusal> Sch001Controller::drive_travel_refusal(const TravelCommand&) noexcept {
  return std::nullopt;  // the unit has its two speeds on every installation (card document 3c)
}

// ---- what only the hydraulic lift knows (ControllerCore::step_lift) ----

void Sch001Controller::inspect_run(lift::Direction direction, const TickInput& in) noexcept {
  (void)travel_.inspect(direction, in);
}

void Sch001Controller::start_call_travel(std::size_t floor, const TickInput& in) noexcept {
  (void)travel_.start_travel(lift_.floors(), floor, Speed::V4, in);
}

lift::Cause Sch001Controller::start_relevel_run(std::size_t floor, lift::Direction,
                                                const TickInput& in) noexcept {
  // The hydraulic lift relevels by position only (HydraulicTravel: it steers by position); a
  // relevelling signal alone finds the position missing.
  return travel_.start_relevel(lift_.floors(), floor, in);
}

void Sch001Controller::run_travel(const TickInput& in) noexcept {
  last_output_ = travel_.tick(lift_.floors(), in);
}

bool Sch001Controller::start_learn_leg(std::int64_t target_mm, lift::Direction direction,
                                       const TickInput& in) noexcept {
  return travel_.start_learning(target_mm, direction, in) == lift::Cause::None;
}

std::optional<lift::Answer> Sch001Controller::drive_learn_refusal(const TickInput&) noexcept {
  return std::nullopt;  // the unit's slow speed is always there
}

lift::RelevelPolicy Sch001Controller::relevel_policy() const noexcept {
  lift::RelevelPolicy policy;
  policy.automatic = config_.auto_relevel;
  policy.threshold_mm = config_.hydraulic.relevel_start_mm;
  policy.level_tolerance_mm = config_.hydraulic.stop_tolerance_mm;
  return policy;
}

void Sch001Controller::update_faults(const TickInput& in, MonoTime now) noexcept {
  const bool started = start_grace_over(now);
  // A failed endpoint is a fault at once, until the card is heard on a new one (one episode,
  // one raise and one clear); one that has not opened yet after the start grace.
  set_fault(FaultCode::LinkFault,
            in.card_silent || bus_fault_ || send_failures_ >= kSendFailuresForFault ||
                foreign_sender_ || endpoint_lost_ || (started && !endpoint_up_),
            now);
  set_fault(FaultCode::DriveFault, in.card_error && !in.card_silent, now);
  set_machine_faults(in.inputs, in.position_mm.has_value(), /*position_needed=*/true, now);
}

void Sch001Controller::publish(MonoTime now) noexcept {
  ControllerSnapshot s;
  fill_lift_snapshot(s, now, build_input(now));
  s.endpoint_up = endpoint_up_ && !bus_fault_;
  s.heard = link_.heard();
  s.ever_heard = link_.ever_heard();
  s.endpoint_lost = endpoint_lost_;
  s.silent = link_.silent();
  s.send_failing = send_failures_ >= kSendFailuresForFault;
  s.foreign_sender = foreign_sender_;
  s.status_changes = status_changes_;
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
  s.quiesced = shutting_down_ && travel_.kind() == TravelKind::None && !bits_sent_.any();
  publish_snapshot(s);
}

}  // namespace liftd::sch001
