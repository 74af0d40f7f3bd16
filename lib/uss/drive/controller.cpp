#include "uss/drive/controller.hpp"

#include <algorithm>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <type_traits>

#include "drive/drive.hpp"

namespace liftd::uss {

UssController::UssController(const UssControllerConfig& config, Master& master,
                             const PositionSource& position, MonoTime start)
    : ControllerCore(lift::core_config_of(config, start), config.travel),
      config_(config),
      master_(master),
      position_(position) {
  if (config.floors_mm.size() < 2) {
    throw std::invalid_argument("floors: need 2 or more strictly increasing levels");
  }
  if (const auto bad = validate(config.travel)) {
    throw std::invalid_argument("uss: bad travel setting " + std::string(*bad));
  }
  if (config.drive_address > kMaxSlaveAddress || !master.slave(config.drive_address).configured) {
    throw std::invalid_argument("uss.drive.address: not a configured slave of the bus");
  }
  if (config.drive_pzd_words < 2 || config.drive_pzd_words > kMaxPzdWords) {
    throw std::invalid_argument(
        "uss: the lift drive needs 2..16 PZD words (PZD1 STW/ZSW, PZD2 HSW/HIW, C 5.1)");
  }
  if (config.normalisation.raw_full_scale <= 0 || !(config.normalisation.full_scale > 0.0)) {
    throw std::invalid_argument("uss.normalisation: full scale must be positive (C 5.2.2)");
  }
  if (config.link_fault_replies == 0) {
    throw std::invalid_argument("uss.link_fault_replies: must be 1 or more");
  }
  publish(start);
}

// ---- uss::UssHooks ----

void UssController::after_exchange(MonoTime now) noexcept {
  step(now);
}

void UssController::on_port(bool up, MonoTime now) noexcept {
  port_up_ = up;
  // A lost port stays a link fault until the drive answers on the reopened one (update_faults):
  // one episode, one raise and one clear, however often the port is reopened meanwhile.
  if (!up) port_failed_ = true;
  push_event({.kind = ControllerEvent::Kind::Port, .at = now, .port_up = up});
  step(now);
}

// ---- one step ----

DriveInput UssController::build_input(MonoTime now) const noexcept {
  DriveInput in;
  in.now = now;
  in.position_mm = position_.position_mm(now);
  in.inputs = current_inputs(now);
  const SlaveState& s = master_.slave(config_.drive_address);
  // C 5.1: PZD1 of the reply is ZSW, PZD2 the main actual value HIW.
  in.zsw = s.pzd_in_count >= 1 ? s.pzd_in[0] : 0;
  in.actual_percent = s.pzd_in_count >= 2
                          ? config_.normalisation.from_raw(static_cast<std::int16_t>(s.pzd_in[1]))
                          : 0.0;
  in.replies = s.good;
  in.link_ok = port_up_ && s.heard && s.pzd_in_count >= 1 &&
               s.consecutive_failures < config_.link_fault_replies;
  return in;
}

void UssController::step(MonoTime now) noexcept {
  drain_master(now);
  const DriveInput in = step_lift(now, *this);

  // C 5.1: PZD1 STW, PZD2 the main setpoint HSW (normalised, C 5.2.2), further words 0.
  std::array<std::uint16_t, kMaxPzdWords> words{};
  words[0] = last_output_.stw;
  setpoint_raw_ = config_.normalisation.to_raw(last_output_.setpoint_percent);
  words[1] = static_cast<std::uint16_t>(setpoint_raw_);
  master_.set_pzd(config_.drive_address,
                  std::span<const std::uint16_t>(words.data(), config_.drive_pzd_words));

  if (in.link_ok) {
    const ProfileState state = travel_.profile().state();
    // Local control (ZSW bit 9 = 0) holds every travel back whatever the state: told too.
    const bool plc_control = travel_.profile().plc_control(in.zsw);
    if (!state_reported_ || state != last_state_ || plc_control != last_plc_control_) {
      state_reported_ = true;
      last_state_ = state;
      last_plc_control_ = plc_control;
      ControllerEvent e;
      e.kind = ControllerEvent::Kind::DriveState;
      e.at = now;
      e.drive_state = state;
      e.plc_control = plc_control;
      e.zsw = in.zsw;
      push_event(e);
    }
  }
  // While running at speed by position the car can still stop at any floor beyond its
  // speed's slowdown distance (LiftTravel::stop uses the same rule).
  std::optional<std::uint32_t> decel;
  if (travel_.phase() == Phase::Run && config_.travel.reference == Reference::Position) {
    decel = config_.travel.slowdown_mm[speed_index(travel_.speed())];
  }
  lift_.update(in.position_mm, travel_.direction(), decel);
  if (master_.cycles() != sampled_pass_) {
    sampled_pass_ = master_.cycles();
    lift::DriveBits bits;
    bits.command = last_output_.stw;  // C 5.1: the control word sent
    bits.status = in.zsw;             // C 5.1: the drive's status word
    sample_travel(now, travel_.kind() != TravelKind::None, LiftTravel::kind_name(travel_.kind()),
                  in.position_mm, travel_.target(), bits);
  }
  publish(now);
}

void UssController::drain_master(MonoTime now) noexcept {
  LinkChange change;
  while (master_.poll_link_change(change)) {
    ControllerEvent e;
    e.kind = ControllerEvent::Kind::Link;
    e.at = change.at;
    e.link = change;
    push_event(e);
  }
  while (master_.poll_spontaneous(report_)) {
    ControllerEvent e;
    e.kind = ControllerEvent::Kind::Spontaneous;
    e.at = report_.at;
    e.spontaneous = report_;
    push_event(e);
  }
  while (master_.poll_pkw_result(pkw_result_)) {
    if (pkw_result_.tag == 0) continue;
    CommandReply r;
    r.tag = pkw_result_.tag;
    r.code = ReplyCode::Ok;
    r.pkw = pkw_result_;
    push_reply(r);
  }
  MirrorResult mirror;
  while (master_.poll_mirror(mirror)) {
    if (mirror.tag != 0 && mirror.tag != kStartMirrorTag) {
      CommandReply r;
      r.tag = mirror.tag;
      r.code = ReplyCode::Ok;
      r.mirror = mirror;
      push_reply(r);
      continue;
    }
    ControllerEvent e;
    e.kind = ControllerEvent::Kind::Mirror;
    e.at = now;
    e.mirror = mirror;
    push_event(e);
  }
}

// ---- commands ----

namespace {

/// The USS drive's own refusals (its status word, C 5.1; the installation's speeds); the
/// machine's are every kind's.
constexpr lift::CauseRefusal kDriveRefusals[] = {
    {lift::Cause::LinkDown, ReplyCode::Fault,
     "the USS link to the drive is down (no current reply)"},
    {lift::Cause::DriveFault, ReplyCode::Fault,
     "the drive reports a fault (ZSW bit 3) or missed a state in time: drive_reset "
     "acknowledges it"},
    {lift::Cause::DriveDidNotStart, ReplyCode::Fault,
     "the drive did not start the motor in time after it was enabled"},
    {lift::Cause::DriveDidNotStop, ReplyCode::Fault, "the drive did not report the stop in time"},
    {lift::Cause::DriveNotReady, ReplyCode::NotReady,
     "the drive is not ready (not ready to switch on, or ZSW bit 9 = 0: local control)"},
    {lift::Cause::AdvanceWarning, ReplyCode::NotReady, "the drive reports a warning (ZSW bit 7)"},
    {lift::Cause::SpeedNotConfigured, ReplyCode::BadRequest,
     "that speed has no setpoint in this installation (uss.speeds)"},
};

}  // namespace

lift::Refusal UssController::refusal(lift::Cause cause) noexcept {
  return lift::refusal_for(kDriveRefusals, cause);
}

void UssController::handle(const ControllerCommand& command, DriveInput& in) noexcept {
  const std::uint32_t tag = command.tag;
  std::visit(
      [&](const auto& body) {
        using T = std::decay_t<decltype(body)>;
        if constexpr (std::is_same_v<T, DriveResetCommand>) {
          if (travel_.busy()) {
            return reply(tag, ReplyCode::Busy, "a travel is running: no drive reset during travel");
          }
          travel_.acknowledge();
          reply(tag, ReplyCode::Ok, {});
        } else if constexpr (std::is_same_v<T, ParameterCommand>) {
          if (body.address > kMaxSlaveAddress || !master_.slave(body.address).configured) {
            return reply(tag, ReplyCode::BadRequest, "no such slave on the USS bus");
          }
          if (!master_.submit_pkw(body.address, body.request, tag)) {
            if (master_.slave(body.address).pkw_busy) {
              return reply(tag, ReplyCode::Busy, "a parameter request to that slave is running");
            }
            return reply(tag, ReplyCode::BadRequest,
                         "the request does not fit the slave's PKW area (uss.slaves[].pkw)");
          }
          // The reply follows with the result (drain_master).
        } else if constexpr (std::is_same_v<T, MirrorCommand>) {
          if (body.address > kMaxSlaveAddress || !master_.slave(body.address).configured) {
            return reply(tag, ReplyCode::BadRequest, "no such slave on the USS bus");
          }
          if (!master_.request_mirror(body.address, tag)) {
            return reply(tag, ReplyCode::Busy, "a mirror to that slave is still pending");
          }
        } else {
          handle_lift(tag, body, in, *this);  // every lift's commands
        }
      },
      command.body);
}

std::optional<lift::Refusal> UssController::drive_travel_refusal(
    const TravelCommand& command) const noexcept {
  if (speed_number(command.speed) == 0 || !travel_.speed_available(command.speed)) {
    return lift::Refusal{ReplyCode::BadRequest, refusal(lift::Cause::SpeedNotConfigured).detail};
  }
  return std::nullopt;
}

std::optional<lift::Answer> UssController::drive_learn_refusal(const DriveInput&) const noexcept {
  if (!travel_.speed_available(SpeedName::V0)) {
    return lift::Answer{ReplyCode::BadRequest, refusal(lift::Cause::SpeedNotConfigured).detail};
  }
  return std::nullopt;
}

bool UssController::start_learn_leg(std::int64_t target_mm, lift::Direction direction,
                                    const DriveInput& in) noexcept {
  return travel_.start_learning(target_mm, direction, fastest_speed(), in) == lift::Cause::None;
}

SpeedName UssController::fastest_speed() const noexcept {
  for (const std::string_view name : drive::kTravelSpeedNames) {
    const auto speed = parse_speed(name);
    if (speed && travel_.speed_available(*speed)) return *speed;
  }
  return SpeedName::V4;
}

// ---- what only the USS lift knows (ControllerCore::step_lift) ----

void UssController::inspect_run(lift::Direction direction, const DriveInput& in) noexcept {
  (void)travel_.inspect(lift_.floors(), direction, in);
}

void UssController::start_call_travel(std::size_t floor, const DriveInput& in) noexcept {
  // The fastest speed the installation has, in the order DCP 3.5.3.7 adds them.
  const SpeedName speed = fastest_speed();
  if (travel_.speed_available(speed)) {
    (void)travel_.start_travel(lift_.floors(), floor, speed, in);
  }
}

lift::Cause UssController::start_relevel_run(std::size_t floor, lift::Direction direction,
                                             const DriveInput& in) noexcept {
  return travel_.start_relevel(lift_.floors(), floor, direction, in);
}

void UssController::run_travel(const DriveInput& in) noexcept {
  last_output_ = travel_.tick(lift_.floors(), in);
}

lift::RelevelPolicy UssController::relevel_policy() const noexcept {
  lift::RelevelPolicy policy;
  policy.automatic = config_.auto_relevel;
  policy.threshold_mm = config_.relevel_threshold_mm;
  policy.zone_mm = config_.relevel_zone_mm;
  policy.level_tolerance_mm = config_.travel.level_tolerance_mm;
  return policy;
}

// ---- faults ----

void UssController::update_faults(const DriveInput& in, MonoTime now) noexcept {
  const bool started = start_grace_over(now);
  const SlaveState& s = master_.slave(config_.drive_address);
  const bool failing = s.heard && s.consecutive_failures >= config_.link_fault_replies;
  if (port_failed_ && port_up_ && s.responding) port_failed_ = false;  // heard on the new port
  // A lost port or a drive missing its replies is a fault at once; a port not open or a drive
  // not heard yet after the start grace.
  set_fault(FaultCode::LinkFault, port_failed_ || failing || (started && (!port_up_ || !s.heard)),
            now);
  set_fault(FaultCode::DriveFault,
            in.link_ok && ((in.zsw & zsw::kFault) != 0 ||
                           travel_.profile().supervision() != Supervision::None),
            now);
  set_fault(FaultCode::AdvanceWarning, in.link_ok && (in.zsw & zsw::kWarning) != 0, now);
  set_machine_faults(in.inputs, in.position_mm.has_value(),
                     config_.travel.reference == Reference::Position, now);
}

void UssController::publish(MonoTime now) noexcept {
  ControllerSnapshot& s = snapshot_scratch_;
  s.port_up = port_up_;
  s.slave_count = 0;
  for (std::size_t a = 0; a <= kMaxSlaveAddress; ++a) {
    const SlaveState& st = master_.slave(static_cast<std::uint8_t>(a));
    if (!st.configured) continue;
    SlaveSnapshot& out = s.slaves[s.slave_count++];
    out.address = static_cast<std::uint8_t>(a);
    out.heard = st.heard;
    out.responding = st.responding;
    out.consecutive_failures = st.consecutive_failures;
    out.good = st.good;
    out.failures = st.failures;
    out.pzd_in = st.pzd_in;
    out.pzd_in_count = st.pzd_in_count;
    out.pkw_busy = st.pkw_busy;
  }
  const DriveInput in = build_input(now);
  const SlaveState& drive = master_.slave(config_.drive_address);
  s.drive_address = config_.drive_address;
  s.drive_heard = drive.heard;
  s.link_ok = in.link_ok;
  s.stw_sent = last_output_.stw;
  s.zsw = in.zsw;
  s.drive_state = travel_.profile().state();
  s.wish = last_output_.wish;
  s.supervision = travel_.profile().supervision();
  s.acknowledging = travel_.profile().acknowledging();
  s.setpoint_raw = setpoint_raw_;
  s.setpoint_percent = config_.normalisation.from_raw(setpoint_raw_);
  s.actual_raw = drive.pzd_in_count >= 2 ? static_cast<std::int16_t>(drive.pzd_in[1]) : 0;
  s.actual_percent = in.actual_percent;
  s.brake_open = last_output_.brake_open;
  s.contactors_on = last_output_.contactors_on;
  s.rx = master_.rx_counters();
  s.cycles = master_.cycles();
  s.expected_cycle_time = master_.expected_cycle_time();
  s.last_cycle_time = master_.last_cycle_time();
  s.speed = travel_.speed();
  fill_lift_snapshot(s, now, in);
  s.quiesced = shutting_down_ && !travel_.busy() && (last_output_.stw & stw::kOn) == 0 &&
               !last_output_.brake_open && !last_output_.contactors_on &&
               !(in.link_ok && operation_enabled(in.zsw));
  publish_snapshot(s);
}

}  // namespace liftd::uss
