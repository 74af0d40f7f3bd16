// DcpController after each cycle (dcp_controller.cpp has the cycle itself and the commands): the
// link's and the travel's events drained into replies, journal events and the lift's record,
// the calls served, the fault table updated and the snapshot published.
#include <algorithm>

#include "dcp/control/dcp_controller.hpp"
#include "dcp/travel/gate.hpp"

namespace liftd::control {

using travel::TravelKind;

void DcpController::drain_link(MonoTime now) noexcept {
  while (auto c = link_.pop_completion()) {
    if (c->tag == kTravelTag) {
      internal_.active = false;
      if (internal_.kind == travel::ChannelRequest::Kind::Position &&
          c->result == dcp::RequestResult::LinkLost) {
        position_owed_ = true;  // lost with the link: send it again once it is back
      }
      if (c->result != dcp::RequestResult::Ok || !c->reply) continue;
      travel::ChannelReply r;
      r.kind = internal_.kind;
      if (const auto* i7 = std::get_if<dcp::StartParamsReply>(&*c->reply)) {
        r.short_travel = i7->kind == dcp::TravelKind::Short;
        r.min_distance_cm = i7->total_cm;
        r.decel_distance_cm = i7->decel_cm;
      } else if (const auto* i9 = std::get_if<dcp::PositionReply>(&*c->reply)) {
        // DCP 5.12.9.2: the extended reply carries the distance the drive measured.
        if (i9->extended && i9->travel_mm) {
          measured_mm_ = *i9->travel_mm;
          if (pending_i9_travel_mm_) slip_mm_ = *measured_mm_ - *pending_i9_travel_mm_;
        }
      }
      pending_reply_ = r;
      continue;
    }
    CommandReply r;
    r.tag = c->tag;
    switch (c->result) {
      case dcp::RequestResult::Ok:
      case dcp::RequestResult::AssumedMains:
        r.code = ReplyCode::Ok;
        r.detail = dcp::to_string(c->result);
        break;
      case dcp::RequestResult::Timeout:
        r.code = ReplyCode::Timeout;
        r.detail = "the drive did not answer";
        break;
      case dcp::RequestResult::LinkLost:
        r.code = ReplyCode::Fault;
        r.detail = "the link went down before the drive answered";
        break;
    }
    r.drive_reply = c->reply;
    push_reply(r);
  }
  while (auto e = link_.pop_event()) {
    ControllerEvent ev;
    ev.kind = ControllerEvent::Kind::Link;
    ev.at = e->at;
    ev.link = *e;
    push_event(ev);
  }
  while (auto d = link_.pop_drive_error()) {
    ControllerEvent ev;
    ev.kind = ControllerEvent::Kind::DriveError;
    ev.at = d->at;
    ev.drive_error = d->text;
    push_event(ev);
  }
  (void)now;
}

void DcpController::drain_travel(MonoTime now) noexcept {
  while (auto e = travel_.pop_event()) {
    if (e->type == travel::Event::Type::TargetExtended ||
        e->type == travel::Event::Type::TargetRefused || e->type == travel::Event::Type::Finished ||
        e->type == travel::Event::Type::Aborted) {
      settle_extension(*e);
    }
    ControllerEvent ev;
    ev.kind = ControllerEvent::Kind::Travel;
    ev.at = e->at;
    ev.travel = *e;
    push_event(ev);
    if (e->type == travel::Event::Type::Finished || e->type == travel::Event::Type::Aborted) {
      learning_leg_ended(e->type == travel::Event::Type::Aborted, e->cause);
    }
    switch (e->type) {
      case travel::Event::Type::FastStartArmed:
        fast_start_armed_ = true;
        break;
      case travel::Event::Type::Started:
        fast_start_armed_ = false;
        travel_start_mm_ = e->position_mm;
        break;
      case travel::Event::Type::Finished: {
        fast_start_armed_ = false;
        pending_i9_travel_mm_.reset();
        if (travel_start_mm_ && e->position_mm) {
          pending_i9_travel_mm_ = *e->position_mm - *travel_start_mm_;
        }
        // A travel between floors (not a relevelling) served the queued stop it ended at.
        const bool between_floors = e->kind == TravelKind::Dcp4Distance ||
                                    e->kind == TravelKind::Dcp3Speed ||
                                    e->kind == TravelKind::Dcp3Crawl;
        served_on_arrival(
            between_floors && e->position_mm
                ? lift_.floors().floor_at(*e->position_mm, config_.lift.level_tolerance_mm)
                : std::nullopt,
            now);
        target_floor_.reset();
        break;
      }
      case travel::Event::Type::Aborted:
        fast_start_armed_ = false;
        target_floor_.reset();
        // A travel ended by a fault or a stop drops the queue: the dispatcher re-assigns.
        calls_after_abort(e->cause, now);
        break;
      default:
        break;
    }
  }
  note_travel_dropped(travel_.dropped_events());
}

void DcpController::serve_calls() noexcept {
  const auto front = lift_.calls().front();
  if (!front || travel_.active_kind() != TravelKind::None || travel_.travel_queued() ||
      last_input_.status.travel_active) {
    return;
  }
  if (lift_.current_floor() == front) {
    lift_.calls().pop_front();
    call_served(*front, last_input_.now);
    return;
  }
  if (!link_.travel_allowed() || not_ready_reason(false)) return;  // wait until ready
  if (!call_stop_over(last_input_.now)) return;                    // the doors' time to open
  TravelCommand cmd;
  cmd.floor = *front;
  handle_travel(0, cmd);
}

void DcpController::update_faults(const travel::CycleInput& in, MonoTime now) noexcept {
  const bool link_up = link_.state() == dcp::LinkState::Up;
  set_fault(FaultCode::LinkFault, link_.state() == dcp::LinkState::Fault, now);
  set_fault(FaultCode::DriveFault, link_up && in.status.general_fault, now);
  set_fault(FaultCode::AdvanceWarning, link_up && in.status.advance_warning, now);
  set_machine_faults(in.inputs, in.position_mm.has_value(), link_.protocol() == dcp::Protocol::Dcp4,
                     now);
}

void DcpController::publish(MonoTime now) noexcept {
  ControllerSnapshot s;
  fill_core_snapshot(s, now, last_input_.inputs);
  s.cycle = cycle_;
  s.link = link_.state();
  s.protocol = link_.protocol();
  s.drive_info = link_.drive_info();
  const dcp::DriveSnapshot& drive = link_.drive();
  s.status_byte = drive.status;
  s.extended = drive.extended;
  s.decel_distance_mm = travel_.decel_distance_mm();
  s.power_mode = link_.power_mode();
  s.position_mm = last_input_.position_mm;
  s.next_possible_stop = lift_.next_possible_stop();
  s.travel_kind = travel_.active_kind();
  s.direction = travel_.direction();
  s.target_floor = target_floor_;
  s.fast_start_armed = fast_start_armed_;
  s.brake_open = last_output_.brake_open;
  s.contactors_on = last_output_.contactors_on;
  s.command = last_output_.command;
  s.data_word = last_output_.data_word;
  for (std::size_t r = 0; r < dcp::kDisplayRows; ++r) {
    const auto row = link_.display().row(r);
    std::copy(row.begin(), row.end(), s.display[r].begin());
  }
  s.display_version = link_.display().version();
  s.link_counters = link_.counters();
  s.last_travel_measured_mm = measured_mm_;
  s.last_travel_slip_mm = slip_mm_;
  s.handshake_problem = link_.handshake_problem();
  s.quiesced = shutting_down_ && travel_.active_kind() == TravelKind::None &&
               !last_input_.status.travel_active &&
               frames_at_rest_ >= static_cast<std::uint32_t>(config_.link.fault_after_bad_frames);
  // The drive's verdict on the status the next cycle's travel command is judged by.
  travel::CycleInput now_in = last_input_;
  read_drive(now_in);
  s.drive_allows_travel =
      travel::CommandGate::drive_forbidding(now_in, /*starting=*/true) == lift::Cause::None;
  publish_snapshot(s);
}

}  // namespace liftd::control
