#include "dcp/control/dcp_controller.hpp"

#include <stdexcept>

#include "dcp/travel/gate.hpp"

namespace liftd::control {
namespace {

using travel::TravelKind;

std::string_view abort_text(lift::Cause cause) noexcept {
  switch (cause) {
    case lift::Cause::LinkDown:
      return "link to the drive is not up";
    case lift::Cause::NoHandshake:
      return "no valid I0 handshake with the drive yet";
    case lift::Cause::DriveNotReady:
      return "drive not ready (S0 = 0)";
    case lift::Cause::AdvanceWarning:
      return "drive advance warning (S2 = 1)";
    case lift::Cause::DriveFault:
      return "drive general fault (S3 = 1)";
    default:  // the machine's: the same words on every drive kind
      return lift::shared_cause_text(cause);
  }
}

}  // namespace

// ---- names ----

// ---- construction ----

DcpController::DcpController(const ControllerConfig& config, const PositionSource& position)
    // The start grace counts from the first cycle (frame_to_send), not from here.
    : ControllerCore(lift::core_config_of(config), config.travel),
      config_(config),
      position_(position),
      link_(config.link) {
  if (auto bad = travel::validate(config.travel)) {
    throw std::invalid_argument("travel setting out of range: " + std::string(*bad));
  }
  publish(MonoTime{});
}

// ---- the cycle ----

std::span<const std::uint8_t> DcpController::frame_to_send(MonoTime now) noexcept {
  if (cycle_++ == 0) restart_start_grace(now);
  // Inputs (machine inputs, the API's inspection buttons) and the clock first, so this cycle's
  // input is current; then every other command is
  // judged against that input (a travel asked for right after the handshake is not refused with
  // the previous cycle's state).
  std::size_t deferred = 0;
  Command command;
  travel::CycleInput before;  // what the inputs and the clock need: the time
  before.now = now;
  while (deferred < deferred_.size() && next_command(command)) {
    if (std::holds_alternative<InputsCommand>(command.body) ||
        std::holds_alternative<InspectionCommand>(command.body) ||  // a held button: an input
        std::holds_alternative<ClockCommand>(command.body)) {
      handle(command, before);
    } else {
      deferred_[deferred++] = command;
    }
  }
  last_input_ = build_input(now);
  travel_.observe(last_input_);
  for (std::size_t i = 0; i < deferred; ++i) handle(deferred_[i], last_input_);
  // DCP 5.12.9: the next travel begins once the I9 for the last stop has reached the drive.
  travel_.hold_start(position_owed_ || (internal_.active &&
                                        internal_.kind == travel::ChannelRequest::Kind::Position));

  last_output_ = travel_.step(last_input_);
  sample_learning(last_input_.position_mm, last_input_.inputs, last_input_.now, travel_.direction(),
                  [this](std::int64_t target_mm) { return travel_.end_crawl_at(target_mm); });
  // Stationary as the position shows it: a car whose drive enable was cut may still slide on the
  // brake after S1 fell (at most 1 mm of encoder jitter between two cycles).
  const auto position = last_input_.position_mm;
  const bool car_stands =
      !position || (previous_position_mm_ && std::abs(*position - *previous_position_mm_) <= 1);
  previous_position_mm_ = position;
  if (last_output_.channel_request) {
    submit_channel(*last_output_.channel_request);
  } else if (position_owed_ && car_stands && travel_.active_kind() == TravelKind::None &&
             !last_input_.status.travel_active && !last_input_.status.brake_open &&
             link_.travel_allowed() && !internal_.active) {
    // DCP 5.12.9: "The actual position of the lift car will be send after each stopping ...
    // That also applies to travels using the speed assignments VI (inspection), V0 (crawling)
    // or VN (relevelling)"; 5.12.9.1: "while the drive is stationary". DCP3 without an
    // absolute position sends 'E' (invalid value).
    travel::ChannelRequest request;
    request.kind = travel::ChannelRequest::Kind::Position;
    request.position_mm = last_input_.position_mm;
    submit_channel(request);
    position_owed_ = !internal_.active;
  }
  link_.set_process(last_output_.command, last_output_.data_word);
  frame_ = link_.next_frame(now);
  constexpr std::uint8_t kMotionBits =
      dcp::command_bit::kDriveEnable | dcp::command_bit::kTravel | dcp::command_bit::kStopSwitch;
  frames_at_rest_ = (frame_[0] & kMotionBits) != 0 ? 0 : frames_at_rest_ + 1;
  return frame_;
}

bool DcpController::on_reply(std::span<const std::uint8_t> reply, MonoTime now) noexcept {
  if (reply.size() != dcp::kFrameSize) {
    link_.on_no_reply(now);
    return false;
  }
  const std::span<const std::uint8_t, dcp::kFrameSize> bytes(reply.data(), dcp::kFrameSize);
  link_.on_reply(bytes, now);
  return dcp::decode_slave(bytes).has_value();
}

void DcpController::after_cycle(MonoTime now) noexcept {
  drain_link(now);
  drain_travel(now);
  step_learn();
  // DCP 5.12.9: every stop owes the drive an I9, whatever ended the travel.
  const TravelKind kind = travel_.active_kind();
  if (last_kind_ != TravelKind::None && kind == TravelKind::None) position_owed_ = true;
  last_kind_ = kind;
  lift_.update(last_input_.position_mm, travel_.direction(), travel_.decel_distance_mm());
  update_faults(last_input_, now);
  serve_calls();
  sample_travel(now, kind != TravelKind::None, travel::to_string(kind), last_input_.position_mm,
                target_floor_, drive_bits());
  publish(now);
}

lift::DriveBits DcpController::drive_bits() const noexcept {
  lift::DriveBits bits;
  bits.command = frame_[0];
  bits.status = link_.drive().status.value_or(0);
  // DCP 4.1, 11.1: a DCP4 travel on remaining distance sends it in the data bytes while B3 is
  // off; with B3 they carry a speed.
  const TravelKind kind = travel_.active_kind();
  const bool distance_word =
      link_.protocol() == dcp::Protocol::Dcp4 &&
      (kind == TravelKind::Dcp4Distance || kind == TravelKind::Dcp4Relevel) &&
      (frame_[0] & dcp::command_bit::kDriveEnable) != 0 &&
      (frame_[0] & dcp::command_bit::kSpeedData) == 0;
  if (distance_word) bits.remaining_mm = last_output_.data_word;
  return bits;
}

travel::CycleInput DcpController::build_input(MonoTime now) noexcept {
  travel::CycleInput in;
  in.now = now;
  read_drive(in);
  in.position_mm = position_.position_mm(now);
  in.inputs = current_inputs(now);
  in.channel_reply = pending_reply_;
  pending_reply_.reset();
  return in;
}

void DcpController::read_drive(travel::CycleInput& in) const noexcept {
  in.link_up = link_.realtime_up();  // DCP 7.3: the real-time channel alone (DCP 5.1)
  in.reply_fresh = link_.last_exchange_good();
  in.handshake_done = link_.travel_allowed();
  in.protocol = link_.protocol().value_or(dcp::Protocol::ComChan);
  const dcp::DriveSnapshot& drive = link_.drive();
  in.status = drive.status ? dcp::Status::from_byte(*drive.status) : dcp::Status{};
  in.decel_distance_mm.reset();
  if (drive.deceleration && !drive.deceleration->saturated) {
    in.decel_distance_mm = drive.deceleration->deceleration_distance_mm;
  }
  in.extended = drive.extended;
}

// ---- commands ----

void DcpController::reply_extended(std::uint32_t tag) noexcept {
  if (tag == 0) return;
  CommandReply r;
  r.tag = tag;
  r.code = ReplyCode::Ok;
  r.detail = "target extended";
  r.extended = true;
  push_reply(r);
}

void DcpController::handle(const Command& command, travel::CycleInput& in) noexcept {
  const std::uint32_t tag = command.tag;
  std::visit(
      [&](const auto& body) {
        using T = std::decay_t<decltype(body)>;
        if constexpr (std::is_same_v<T, TravelCommand>) {
          handle_travel(tag, body);
        } else if constexpr (std::is_same_v<T, StopCommand>) {
          handle_stop(tag);
        } else if constexpr (std::is_same_v<T, ShutdownCommand>) {
          // As on every lift (ControllerCore's ShutdownCommand): no new travel or call, the
          // running travel stops as `stop` stops it, or at once when forced.
          shutting_down_ = true;
          drop_calls(lift::Cause::ShuttingDown, in.now);
          travel_.shut_down(body.force);
          if (!body.force) handle_stop(0);
          reply(tag, ReplyCode::Ok);
        } else if constexpr (std::is_same_v<T, FastStopCommand>) {
          if (travel_.active_kind() == TravelKind::None && !travel_.travel_queued()) {
            reply(tag, ReplyCode::BadRequest, "no travel running");
            return;
          }
          drop_calls(lift::Cause::StopRequested, in.now);
          travel_.fast_stop();
          reply(tag, ReplyCode::Ok);
        } else if constexpr (std::is_same_v<T, RelevelCommand>) {
          handle_relevel(tag);
        } else if constexpr (std::is_same_v<T, CallCommand>) {
          const bool running = travel_.active_kind() != TravelKind::None || travel_.travel_queued();
          const bool heading_for =
              running && target_floor_.has_value() && target_floor_ == lift_.calls().front();
          if (body.op == CallCommand::Op::Cancel && heading_for && body.floor == target_floor_) {
            cancel_target(tag, body.floor);
            return;
          }
          const lift::Answer a = answer_call(body, heading_for);
          reply(tag, a.code, a.detail);
        } else if constexpr (std::is_same_v<T, InspectionCommand> ||
                             std::is_same_v<T, InputsCommand>) {
          handle_shared(tag, body, in);
        } else if constexpr (std::is_same_v<T, FastStartCommand>) {
          if (!fast_start_armed_) {
            reply(tag, ReplyCode::BadRequest, "no fast start armed");
          } else if (body.action == FastStartCommand::Action::Abort) {
            travel_.stop();  // DCP 12.2.2: controlled termination, wait for S6
            reply(tag, ReplyCode::Ok);
          } else if (!last_input_.inputs.doors_locked) {
            reply(tag, ReplyCode::NotReady, "doors not locked: the car leaves when they are");
          } else {
            reply(tag, ReplyCode::Ok);  // DCP 12.1.3: the go message follows doors locked
          }
        } else if constexpr (std::is_same_v<T, LinkCommand>) {
          const auto* sw = std::get_if<dcp::SwitchRequest>(&body.request);
          if (sw != nullptr && sw->function == dcp::SwitchFunction::Reset &&
              (travel_.active_kind() != TravelKind::None || last_input_.status.travel_active)) {
            reply(tag, ReplyCode::Busy, "a travel is running: reset the drive when it is at rest");
            return;
          }
          const dcp::SubmitResult r = link_.submit(body.request, tag);
          switch (r) {
            case dcp::SubmitResult::Accepted:
              break;  // the completion answers
            case dcp::SubmitResult::QueueFull:
              reply(tag, ReplyCode::Busy, dcp::to_string(r));
              break;
            case dcp::SubmitResult::LinkNotUp:
              reply(tag, ReplyCode::NotReady, dcp::to_string(r));
              break;
            case dcp::SubmitResult::Invalid:
            case dcp::SubmitResult::TooLate:
              reply(tag, ReplyCode::BadRequest, dcp::to_string(r));
              break;
          }
        } else if constexpr (std::is_same_v<T, ClockCommand>) {
          link_.set_civil_time(body.time);
        } else if constexpr (std::is_same_v<T, LearnCommand>) {
          handle_learn(tag);
        }
      },
      command.body);
}

std::optional<std::string_view> DcpController::not_ready_reason(bool fast_start) const noexcept {
  travel::GateProfile profile;
  profile.doors_locked_required = !fast_start;
  profile.position_required = last_input_.protocol == dcp::Protocol::Dcp4;
  const lift::Cause cause = travel::CommandGate::forbidding(last_input_, profile, true);
  if (cause == lift::Cause::None) return std::nullopt;
  return abort_text(cause);
}

dcp::Speed DcpController::choose_dcp3_speed(std::int64_t distance_mm) const noexcept {
  // DCP 10.1/10.2: the fastest installed speed whose fixed deceleration distance SVx fits the
  // travel; none fits -> crawl V0 (DCP 10.3).
  for (dcp::Speed s : dcp::dcp3_travel_speeds(config_.travel.dcp3_speed_count)) {
    const std::uint32_t sv = config_.travel.dcp3_decel_distance_mm[travel::speed_index(s)];
    if (sv > 0 && static_cast<std::int64_t>(sv) < distance_mm) return s;
  }
  return dcp::Speed::V0;
}

void DcpController::handle_travel(std::uint32_t tag, const TravelCommand& cmd) noexcept {
  if (const std::optional<lift::Refusal> refusal = first_travel_refusal(cmd.floor)) {
    reply(tag, refusal->code, refusal->detail);
    return;
  }
  if (!link_.travel_allowed()) {
    reply(tag, ReplyCode::NotReady, abort_text(lift::Cause::LinkDown));
    return;
  }
  // Before a running travel's target is extended too (DCP 9.1.1), as on every kind.
  if (last_input_.inputs.button_mode()) {
    reply(tag, ReplyCode::NotReady, lift::kButtonModeText);
    return;
  }
  const std::int64_t target_mm = lift_.floors().level_mm(cmd.floor);
  const dcp::Protocol protocol = *link_.protocol();
  const TravelKind running = travel_.active_kind();
  if (running == TravelKind::Dcp4Distance && !cmd.fast_start) {
    const travel::ExtendResult r = travel_.extend_target(target_mm);
    if (r == travel::ExtendResult::Accepted) {
      target_floor_ = cmd.floor;
      reply_extended(tag);
    } else if (r == travel::ExtendResult::Pending) {
      // DCP 4.1 / 7.2: answered once the drive's S5 accepts or refuses the new distance.
      extend_tag_ = tag == 0 ? kInternalTag : tag;
      extend_floor_ = cmd.floor;
    } else {
      reply(tag, r == travel::ExtendResult::AdvanceWarning ? ReplyCode::NotReady : ReplyCode::Busy,
            travel::to_string(r));
    }
    return;
  }
  if (running != TravelKind::None) {
    reply(tag, ReplyCode::Busy, "a travel is running that cannot be re-targeted");
    return;
  }
  if (auto why = not_ready_reason(cmd.fast_start)) {
    reply(tag, last_input_.status.general_fault ? ReplyCode::Fault : ReplyCode::NotReady, *why);
    return;
  }
  travel::TravelRequest request;
  request.target_mm = target_mm;
  request.fast_start = cmd.fast_start;
  request.load_percent = cmd.load_percent;
  if (protocol == dcp::Protocol::Dcp4) {
    request.kind = TravelKind::Dcp4Distance;
    request.speed = cmd.speed.value_or(dcp::Speed::V4);
  } else {
    const std::int64_t distance =
        last_input_.position_mm ? std::abs(target_mm - *last_input_.position_mm) : 0;
    request.speed = cmd.speed.value_or(choose_dcp3_speed(distance));
    request.kind = request.speed == dcp::Speed::V0 ? TravelKind::Dcp3Crawl : TravelKind::Dcp3Speed;
  }
  const travel::StartResult r = travel_.start(request);
  if (r != travel::StartResult::Accepted) {
    reply(tag,
          r == travel::StartResult::Busy             ? ReplyCode::Busy
          : r == travel::StartResult::NoPosition     ? ReplyCode::NotReady
          : r == travel::StartResult::InspectionMode ? ReplyCode::NotReady
                                                     : ReplyCode::BadRequest,
          travel::to_string(r));
    return;
  }
  target_floor_ = cmd.floor;
  travel_tag_ = tag;
  reply(tag, ReplyCode::Ok);
}

std::optional<std::size_t> DcpController::next_stop_floor() const noexcept {
  const auto position = last_input_.position_mm;
  const lift::Direction direction = travel_.direction();
  if (!position || direction == lift::Direction::None) return std::nullopt;
  std::optional<std::int64_t> needed_mm;
  if (travel_.active_kind() == TravelKind::Dcp4Distance) {
    needed_mm = travel_.stop_distance_mm();
  } else if (travel_.active_kind() == TravelKind::Dcp3Speed) {
    // DCP 10.1.1 step 3: the car slows to crawl within SVx after B1 drops, so the stop floor's
    // deceleration point must still lie ahead.
    needed_mm =
        static_cast<std::int64_t>(
            config_.travel.dcp3_decel_distance_mm[travel::speed_index(travel_.dcp3().speed())]) +
        static_cast<std::int64_t>(config_.travel.extension_margin_mm);
  }
  if (!needed_mm) return std::nullopt;
  return lift::next_possible_stop(lift_.floors(), *position, direction,
                                  static_cast<std::uint32_t>(*needed_mm), 0);
}

DcpController::MovingTravel DcpController::moving_travel() const noexcept {
  const TravelKind kind = travel_.active_kind();
  MovingTravel m;
  // A car that moves under a distance or speed travel stops at a floor; the stop message of
  // DCP 3.5.3.2 is only for the deceleration and for travels that do not move yet.
  m.dcp4 = kind == TravelKind::Dcp4Distance &&
           travel_.dcp4().state() == travel::Dcp4Travel::State::Distance &&
           (travel_.dcp4().moving() || last_input_.status.brake_open);
  const auto dcp3_state = travel_.dcp3().state();
  m.dcp3 = kind == TravelKind::Dcp3Speed && (dcp3_state == travel::Dcp3Travel::State::FastStartGo ||
                                             dcp3_state == travel::Dcp3Travel::State::Travel ||
                                             dcp3_state == travel::Dcp3Travel::State::Creep);
  m.before_decel_point = m.dcp4 || dcp3_state != travel::Dcp3Travel::State::Creep;
  return m;
}

std::optional<std::size_t> DcpController::stop_travel() noexcept {
  const TravelKind kind = travel_.active_kind();
  const MovingTravel m = moving_travel();
  // A VN' relevelling (DCP 11.1.4) already ends at the nearest level, B2 held until S6 falls
  // (step 4): it is left to finish there.
  const bool dcp4_relevel = kind == TravelKind::Dcp4Relevel &&
                            travel_.dcp4().state() == travel::Dcp4Travel::State::Distance;
  std::optional<std::size_t> stop_floor;
  if (dcp4_relevel) {
    stop_floor =
        lift_.floors().floor_at(travel_.dcp4().target_mm(), config_.lift.level_tolerance_mm);
  } else if (m.dcp4 || m.dcp3) {
    std::optional<std::int64_t> level;
    const auto floor = m.before_decel_point ? next_stop_floor() : std::nullopt;
    if (floor) level = travel_.stop_at(lift_.floors().level_mm(*floor));
    // No nearer floor within reach (or no position): the car goes on to its own target.
    if (!level && m.dcp4) level = travel_.dcp4().target_mm();
    if (!level && m.dcp3) level = travel_.dcp3().target_mm();
    stop_floor = lift_.floors().floor_at(*level, config_.lift.level_tolerance_mm);
    if (stop_floor) target_floor_ = stop_floor;
  } else {
    travel_.stop();
  }
  return stop_floor;
}

void DcpController::handle_stop(std::uint32_t tag) noexcept {
  stop_learning();
  const std::optional<std::size_t> stop_floor = stop_travel();
  drop_calls(lift::Cause::StopRequested, last_input_.now, stop_floor);
  reply(tag, ReplyCode::Ok, {}, stop_floor);
}

void DcpController::cancel_target(std::uint32_t tag, std::size_t floor) noexcept {
  // docs/api.md `calls` cancel: the running travel stops at the next floor it can still stop at
  // (as `stop` stops it), the rest of the queue goes on; too late for any floor before it: said.
  const MovingTravel m = moving_travel();
  if (m.dcp4 || m.dcp3) {
    const auto landing = m.before_decel_point ? next_stop_floor() : std::nullopt;
    if (!landing || *landing == floor) {
      reply(tag, ReplyCode::Busy, lift::kTooLateToCancel);
      return;
    }
  }
  lift_.calls().pop_front();
  keep_calls_on_stop_ = true;
  const std::optional<std::size_t> stop_floor = stop_travel();
  if (stop_floor == floor) {  // the drive could not take the shorter distance
    (void)lift_.calls().insert(0, floor, lift_.floors().size());
    keep_calls_on_stop_ = false;
    reply(tag, ReplyCode::Busy, lift::kTooLateToCancel);
    return;
  }
  reply(tag, ReplyCode::Ok, stop_floor ? lift::kCancelStopsAt : lift::kCancelStopsNow, stop_floor);
}

// ---- the learning travel (lift::LearningTravel through ControllerCore) ----

void DcpController::handle_learn(std::uint32_t tag) noexcept {
  // The gates of a travel to the lowest floor: the service stop, the link, a running travel, the
  // machine and the drive.
  ControllerCore::handle_learn(
      tag, last_input_.position_mm, config_.travel.level_tolerance_mm,
      [this]() -> std::optional<lift::Answer> {
        if (!link_.travel_allowed()) {
          return lift::Answer{ReplyCode::NotReady, abort_text(lift::Cause::LinkDown)};
        }
        if (travel_.active_kind() != TravelKind::None) {
          return lift::Answer{ReplyCode::Busy, "a travel is running"};
        }
        return drive_refuses_learning();
      },
      [this](std::int64_t target_mm, lift::Direction direction) {
        return start_learn_leg(target_mm, direction);
      });
}

std::optional<lift::Answer> DcpController::drive_refuses_learning() const noexcept {
  if (auto why = not_ready_reason(false)) {
    return lift::Answer{last_input_.status.general_fault ? ReplyCode::Fault : ReplyCode::NotReady,
                        *why};
  }
  return std::nullopt;
}

bool DcpController::start_learn_leg(std::int64_t target_mm, lift::Direction direction) noexcept {
  travel::TravelRequest request;
  request.target_mm = target_mm;
  request.direction = direction;
  request.by_position = true;
  const std::int64_t distance =
      last_input_.position_mm ? std::abs(target_mm - *last_input_.position_mm) : 0;
  if (direction == lift::Direction::Up) {
    // DCP 10.3 crawl travel, which DCP4 mode keeps for travels without a remaining distance
    // (DCP 11): V0 all the way, so each zone edge is seen within a millimetre.
    request.kind = TravelKind::Dcp3Crawl;
    request.speed = dcp::Speed::V0;
  } else if (*link_.protocol() == dcp::Protocol::Dcp4) {
    request.kind = TravelKind::Dcp4Distance;
    request.speed = dcp::Speed::V4;
  } else {
    request.speed = choose_dcp3_speed(distance);
    request.kind = request.speed == dcp::Speed::V0 ? TravelKind::Dcp3Crawl : TravelKind::Dcp3Speed;
  }
  request.crawl_timeout_ms =
      config_.travel.crawl_timeout_ms + static_cast<std::uint32_t>(distance) * kLearnCrawlMsPerMm;
  return travel_.start(request) == travel::StartResult::Accepted;
}

void DcpController::step_learn() noexcept {
  step_learning(
      travel_.active_kind() != TravelKind::None,
      [this]() -> std::optional<lift::Answer> { return drive_refuses_learning(); },
      [this](std::int64_t target_mm, lift::Direction direction) {
        return start_learn_leg(target_mm, direction);
      });
}

void DcpController::settle_extension(const travel::Event& event) noexcept {
  if (extend_tag_ == 0) return;
  const std::uint32_t tag = extend_tag_ == kInternalTag ? 0 : extend_tag_;
  extend_tag_ = 0;
  if (event.type == travel::Event::Type::TargetExtended) {
    target_floor_ = extend_floor_;
    reply_extended(tag);
  } else if (event.type == travel::Event::Type::TargetRefused) {
    reply(tag, ReplyCode::Fault,
          "the drive refused the new target (S5 cleared, DCP 4.1): it stops on its emergency ramp");
  } else {
    reply(tag, ReplyCode::Fault, "the travel ended before the drive accepted the new target");
  }
}

void DcpController::handle_relevel(std::uint32_t tag) noexcept {
  if (!link_.travel_allowed()) {
    reply(tag, ReplyCode::NotReady, abort_text(lift::Cause::LinkDown));
    return;
  }
  if (!last_input_.position_mm) {
    // Without a position the shaft's relevelling zones give the direction (relevelling without
    // remaining distance, DCP 9.2.3); with neither there is nothing to relevel to.
    const lift::Inputs& shaft = last_input_.inputs;
    if (shaft.relevel_up == shaft.relevel_down) {
      reply(tag, ReplyCode::NotReady, lift::kNoRelevelReference);
      return;
    }
    travel::TravelRequest request;
    request.kind = TravelKind::Relevel;
    request.speed = dcp::Speed::VN;
    request.direction = shaft.relevel_up ? travel::Direction::Up : travel::Direction::Down;
    const travel::StartResult r = travel_.start(request);
    if (r != travel::StartResult::Accepted) {
      reply(tag, r == travel::StartResult::Busy ? ReplyCode::Busy : ReplyCode::NotReady,
            travel::to_string(r));
      return;
    }
    reply(tag, ReplyCode::Ok);
    return;
  }
  const auto nearest = lift_.floors().nearest(*last_input_.position_mm);
  if (!nearest) {
    reply(tag, ReplyCode::BadRequest, "no floors configured");
    return;
  }
  travel::TravelRequest request;
  request.target_mm = lift_.floors().level_mm(*nearest);
  request.kind =
      *link_.protocol() == dcp::Protocol::Dcp4 ? TravelKind::Dcp4Relevel : TravelKind::Relevel;
  request.speed = dcp::Speed::VN;
  const travel::StartResult r = travel_.start(request);
  if (r != travel::StartResult::Accepted) {
    reply(tag,
          r == travel::StartResult::Busy           ? ReplyCode::Busy
          : r == travel::StartResult::AlreadyThere ? ReplyCode::BadRequest
                                                   : ReplyCode::NotReady,
          travel::to_string(r));
    return;
  }
  target_floor_ = *nearest;
  reply(tag, ReplyCode::Ok);
}

void DcpController::submit_channel(const travel::ChannelRequest& request) noexcept {
  if (internal_.active) return;  // one travel request at a time; the travel times out otherwise
  dcp::Request r;
  switch (request.kind) {
    case travel::ChannelRequest::Kind::StartParameters:
      r = dcp::StartParamsRequest{
          request.vmax == dcp::Speed::V3 ? dcp::MaxSpeed::V3 : dcp::MaxSpeed::V4,
          request.desired_distance_cm};
      break;
    case travel::ChannelRequest::Kind::Load:
      r = dcp::LoadRequest{request.load_percent};
      break;
    case travel::ChannelRequest::Kind::Position: {
      dcp::PositionRequest p;
      p.position_mm = request.position_mm
                          ? dcp::SignedMm(static_cast<std::int32_t>(*request.position_mm))
                          : dcp::SignedMm{};
      r = p;
      break;
    }
  }
  if (link_.submit(r, kTravelTag) == dcp::SubmitResult::Accepted) {
    internal_.active = true;
    internal_.kind = request.kind;
  }
}

}  // namespace liftd::control
