#include "daemon/hydraulic_lift.hpp"

#include <poll.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include "api/commands.hpp"
#include "can/interface_info.hpp"
#include "daemon/lift_common.hpp"
#include "log/log.hpp"

namespace liftd::daemon {
namespace {

using namespace std::chrono_literals;
using api::Result;

constexpr auto kCardReplyGrace = 3s;  // the CAN thread answers within a tick; this catches a stall
constexpr auto kCardShutdownGrace = 300ms;  // after a forced end: three answers without a signal
constexpr auto kRejectLogInterval = 10s;  // rejected card frames are journalled at most this often
constexpr double kSinkMmPerS = 2.0;       // `sim sink`: a leaking valve or cooling oil

}  // namespace

sch001::ControllerConfig sch001_controller_config(const config::Config& c) {
  sch001::ControllerConfig out;
  std::string why;
  const auto ids = sch001::ids_for(static_cast<std::uint32_t>(c.sch001.base),
                                   static_cast<std::uint32_t>(c.sch001.controller_node), &why);
  if (!ids) throw std::invalid_argument("sch001: " + why);
  out.link.ids = *ids;
  out.link.single_unit = c.sch001.single_unit;
  sch001::HydraulicConfig& h = out.hydraulic;
  h.has_v3 = c.sch001.has_v3;
  h.has_v4 = c.sch001.has_v4;
  h.fast_down =
      c.sch001.fast_down == config::FastDown::sp3 ? sch001::FastDown::Sp3 : sch001::FastDown::Hsp;
  h.star_delta_ms = static_cast<std::uint32_t>(c.sch001.star_delta_ms);
  h.slowdown_up_mm = static_cast<std::uint32_t>(c.sch001.slowdown_up_mm);
  h.slowdown_down_mm = static_cast<std::uint32_t>(c.sch001.slowdown_down_mm);
  h.slowdown_v3_mm = static_cast<std::uint32_t>(c.sch001.slowdown_v3_mm);
  h.slowdown_v4_mm = static_cast<std::uint32_t>(c.sch001.slowdown_v4_mm);
  h.stop_tolerance_mm = static_cast<std::uint32_t>(c.sch001.stop_tolerance_mm);
  h.relevel_start_mm = static_cast<std::uint32_t>(c.sch001.relevel_start_mm);
  h.max_travel_ms = static_cast<std::uint32_t>(c.sch001.max_travel_ms);
  h.relevel_doors_open = c.travel.relevel_with_doors == config::RelevelDoors::open ||
                         c.travel.relevel_with_doors == config::RelevelDoors::both;
  out.auto_relevel =
      c.sch001.auto_relevel && c.travel.relevel_with_doors != config::RelevelDoors::never;
  out.lift.level_tolerance_mm = static_cast<std::uint32_t>(c.travel.level_tolerance_mm);
  for (const auto& f : c.floors) out.floors_mm.push_back(f.level_mm);
  out.inputs_timeout = std::chrono::milliseconds(c.inputs.timeout_ms);
  out.inspection_hold = std::chrono::milliseconds(c.travel.inspection_hold_ms);
  return out;
}

namespace {

nlohmann::json card_json(const sch001::CardStatus& s, bool single_unit) {
  nlohmann::json j = nlohmann::json::object();
  j["err"] = s.err;
  j["rdy"] = s.rdy;
  j["t1"] = s.t1;
  j["p1"] = s.p1;
  j["p2"] = s.p2;
  j["pnp1"] = s.pnp1;
  // 3b: valid in a single-unit system only.
  j["avv"] = single_unit ? nlohmann::json(s.avv) : nlohmann::json(nullptr);
  j["pnp2"] = single_unit ? nlohmann::json(s.pnp2) : nlohmann::json(nullptr);
  return j;
}

nlohmann::json bits_json(const sch001::CommandBits& b) {
  nlohmann::json j = nlohmann::json::object();
  for (const auto& [key, bit] : {std::pair{"up", b.up},
                                 {"dw", b.dw},
                                 {"hsp", b.hsp},
                                 {"msp", b.msp},
                                 {"sfy", b.sfy},
                                 {"sp1", b.sp1},
                                 {"sp2", b.sp2},
                                 {"sp3", b.sp3}}) {
    j[key] = bit;
  }
  return j;
}

/// "ERR T1" for the journal: the relays that are on, by name; "none" when none.
std::string card_text(const sch001::CardStatus& s, bool single_unit) {
  std::string out;
  const auto add = [&out](bool on, const char* name) {
    if (on) out += (out.empty() ? "" : " ") + std::string(name);
  };
  add(s.err, "ERR");
  add(s.rdy, "RDY");
  add(s.t1, "T1");
  add(s.p1, "P1");
  add(s.p2, "P2");
  add(s.pnp1, "PNP1");
  if (single_unit) {
    add(s.avv, "AVV");
    add(s.pnp2, "PNP2");
  }
  return out.empty() ? "none" : out;
}

}  // namespace

// ---- the simulated card ----

namespace {

sim::CardSimConfig card_sim_config(const config::Config& c) {
  sim::CardSimConfig out;
  out.ids = *sch001::ids_for(static_cast<std::uint32_t>(c.sch001.base),
                             static_cast<std::uint32_t>(c.sch001.controller_node));
  out.fast_down_sp3 = c.sch001.fast_down == config::FastDown::sp3;
  if (!c.floors.empty()) {
    out.start_mm = static_cast<double>(c.floors.front().level_mm);
    out.bottom_mm = static_cast<double>(c.floors.front().level_mm) - 200.0;
    out.top_mm = static_cast<double>(c.floors.back().level_mm) + 300.0;
  }
  return out;
}

}  // namespace

SimulatedCard::SimulatedCard(const config::Config& config, can::CanSocket card_end)
    : socket_(std::move(card_end)),
      card_(card_sim_config(config), mono_now()),
      board_(config, mono_now()) {
  encoder_.set(std::llround(card_.state().position_mm));
}

SimulatedCard::~SimulatedCard() {
  stop();
}

bool SimulatedCard::start() {
  stop_.store(false);
  thread_ = std::thread([this] { loop(); });
  log::event(log::Level::info, "sim", "sim_started", {{"device", "socketpair"}},
             "simulated SCH001 card answering on a CAN socketpair");
  return true;
}

void SimulatedCard::stop() {
  if (!thread_.joinable()) return;
  stop_.store(true);
  thread_.join();
  log_violations();
  std::lock_guard<std::mutex> lock(mutex_);
  log::event(log::Level::info, "sim", "sim_stopped",
             {{"position_mm", std::to_string(std::llround(card_.state().position_mm))},
              {"violations", std::to_string(card_.state().violations)}},
             "simulated SCH001 card stopped: position " +
                 std::to_string(std::llround(card_.state().position_mm)) + " mm, " +
                 std::to_string(card_.state().violations) +
                 " violation(s) of the card document seen");
}

void SimulatedCard::loop() {
  while (!stop_.load()) {
    pollfd p{socket_.fd(), POLLIN, 0};
    (void)::poll(&p, 1, 5);
    const MonoTime now = mono_now();
    std::lock_guard<std::mutex> lock(mutex_);
    for (int i = 0; i < 16; ++i) {
      const can::Received r = socket_.read();
      if (r.kind == can::Received::Kind::Frame) {
        card_.on_frame(r.frame, now);
      } else {
        break;
      }
    }
    if (bus_off_) {
      can::ErrorReport report;
      report.bus_off = true;
      (void)socket_.write_error(report);
      bus_off_ = false;
    }
    if (const auto frame = card_.poll(now)) (void)socket_.write(*frame);
    const auto& s = card_.state();
    encoder_.set(std::llround(s.position_mm));
    board_.io().set_car(s.velocity_mps != 0.0, s.position_mm, now);
  }
}

lift::Inputs SimulatedCard::inputs(MonoTime now) {
  std::lock_guard<std::mutex> lock(mutex_);
  return board_.io().inputs(now);
}

void SimulatedCard::log_violations() {
  std::vector<sim::CardViolation> found;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    found = card_.take_violations();
  }
  for (const auto& v : found) {
    log::event(log::Level::error, "sim", "sim_violation", {{"rule", v.rule}},
               "simulated SCH001 card: the controller broke the card document: " + v.rule);
  }
}

api::Result SimulatedCard::apply(const api::SimRequest& request, MonoTime now) {
  using api::SimAction;
  std::lock_guard<std::mutex> lock(mutex_);
  switch (request.action) {
    case SimAction::GeneralFault:
      card_.set_err(request.on);
      break;
    case SimAction::NotReady:
      card_.set_rdy(!request.on);
      break;
    case SimAction::OilTemperature:
      card_.set_t1(request.on);
      break;
    case SimAction::Pressure:
      card_.set_p1(request.on);
      break;
    case SimAction::Overpressure:
      card_.set_p2(request.on);
      break;
    case SimAction::CardSilence:
      card_.set_silent(request.on);
      break;
    case SimAction::BusOff:
      bus_off_ = true;
      break;
    case SimAction::ColdOil:
      card_.set_cold_oil(request.on);
      break;
    case SimAction::Sink:
      card_.set_sink(request.on ? kSinkMmPerS : 0.0);
      break;
    case SimAction::Drift:
      if (card_.state().velocity_mps != 0.0) {
        return Result::fail(api::ErrorCode::Busy, "the car is moving: drift only at rest");
      }
      card_.drift(request.drift_mm);
      break;
    case SimAction::SafetyChainOpen:
    case SimAction::DoorReversal:
    case SimAction::OpenDoors:
    case SimAction::CloseDoors:
    case SimAction::ObstructDoors:
      (void)board_.apply(request, now);
      break;
    case SimAction::AdvanceWarning:
    case SimAction::ReplyFault:
    case SimAction::ClearReplyFaults:
    case SimAction::ChannelFault:
    case SimAction::RefuseTarget:
      return sim_action_refused(request, "SCH001 (hydraulic)");
  }
  journal_sim_action(request);
  return Result::ok(state_json_locked());
}

nlohmann::json SimulatedCard::state_json() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return state_json_locked();
}

nlohmann::json SimulatedCard::state_json_locked() const {
  const auto& s = card_.state();
  nlohmann::json out = {{"card", card_json(s.status, true)},
                        {"silent", s.silent},
                        {"cold_oil", s.cold_oil},
                        {"sink_mm_per_s", s.sink_mm_per_s},
                        {"position_mm", std::llround(s.position_mm)},
                        {"violations", s.violations}};
  board_.add_state(out);
  return out;
}

// ---- the backend ----

Sch001Backend::Sch001Backend(const config::Config& config, sch001::Sch001Controller& controller,
                             rt::CanRunner& runner, lift::PositionFeed* position_feed,
                             SimulatedCard* sim)
    : config_(config),
      controller_(controller),
      runner_(runner),
      sim_(sim),
      inputs_(config, position_feed, sim != nullptr),
      mono_at_start_(mono_now()),
      wall_at_start_(std::chrono::system_clock::now()) {}

std::chrono::system_clock::time_point Sch001Backend::wall_time(MonoTime at) const {
  return wall_at_start_ +
         std::chrono::duration_cast<std::chrono::system_clock::duration>(at - mono_at_start_);
}

void Sch001Backend::not_offered(api::Responder& done) {
  done(Result::fail(api::ErrorCode::NotOffered, "not offered by drive kind \"sch001\""));
}

api::StatusSnapshot Sch001Backend::status() {
  const sch001::ControllerSnapshot s = controller_.snapshot();
  api::StatusSnapshot out;
  out.drive_kind = drive::Kind::Sch001;
  if (!s.endpoint_up || s.silent) {
    out.link = s.heard || s.silent ? api::LinkState::Fault : api::LinkState::Down;
  } else {
    out.link = s.heard ? api::LinkState::Up : api::LinkState::Init;
  }
  out.faults = active_faults(
      s.faults, s.fault_since, [](lift::FaultCode code) { return sch001::fault_text(code); },
      [this](MonoTime at) { return wall_time(at); });
  out.drive_state = drive::state_of(out.link == api::LinkState::Up,
                                    s.travel_kind != sch001::TravelKind::None, !out.faults.empty());
  nlohmann::json d = nlohmann::json::object();
  d["card"] = s.card ? card_json(*s.card, s.single_unit) : nlohmann::json(nullptr);
  d["timeout_enabled"] = s.timeout_enabled;
  d["commands"] = bits_json(s.bits_sent);
  d["current_floor"] = s.current_floor_sent;
  d["destination_floor"] = s.destination_floor_sent;
  d["motor_on"] = s.motor_on;
  d["phase"] = std::string(sch001::to_string(s.phase));
  out.details = std::move(d);
  out.position_mm = s.position_mm;
  if (s.floor) out.floor = static_cast<int>(*s.floor);
  if (s.travel_kind == sch001::TravelKind::None && s.floor) out.next_possible_stop = out.floor;
  out.contactors_on = s.motor_on;
  out.travel_state = std::string(sch001::to_string(s.travel_kind));
  out.travel_direction = direction_name(s.direction);
  if (s.target_floor) out.target_floor = static_cast<int>(*s.target_floor);
  for (std::size_t i = 0; i < s.call_count; ++i) out.calls.push_back(s.calls[i]);
  out.rt = rt_info(runner_.thread_status(), config_.rt.priority);
  return out;
}

api::StatsSnapshot Sch001Backend::stats() {
  // The DCP-shaped counters of API 2's stats, filled with their CAN meaning (docs/api.md).
  const sch001::ControllerSnapshot s = controller_.snapshot();
  const rt::CanRunnerCounters c = runner_.counters();
  api::StatsSnapshot out;
  out.frames_sent = c.frames_sent;
  out.replies_good = s.counters.status_frames + s.counters.timeout_commands;
  out.decode_errors = s.counters.wrong_length + s.counters.unknown_first_byte + s.counters.own_id;
  out.link_losses = s.counters.timeouts;
  out.channel_resets = c.reopens;
  out.checksum_errors = c.error_frames;
  out.cycles = s.steps;
  out.dropped_events = controller_.dropped_events();
  return out;
}

std::vector<api::TraceEntry> Sch001Backend::trace(std::size_t max_entries) {
  // Each of our frames with the card's frame it answered: identifier (2 bytes) and data.
  const std::vector<rt::FrameRecord> records = runner_.recorder().copy();
  std::vector<api::TraceEntry> out;
  const rt::FrameRecord* card_frame = nullptr;
  for (const rt::FrameRecord& r : records) {
    if (r.direction == rt::Direction::Rx) {
      card_frame = &r;
    } else if (r.direction == rt::Direction::Tx) {
      api::TraceEntry e;
      e.at = r.time;
      e.tx.assign(r.data().begin(), r.data().end());
      if (card_frame != nullptr) e.rx.emplace(card_frame->data().begin(), card_frame->data().end());
      out.push_back(std::move(e));
      card_frame = nullptr;
    }
  }
  if (out.size() > max_entries) {
    out.erase(out.begin(), out.end() - static_cast<std::ptrdiff_t>(max_entries));
  }
  return out;
}

nlohmann::json Sch001Backend::config() {
  return config::to_json(config_);
}

void Sch001Backend::send(sch001::CommandBody body, api::Responder done) {
  (void)post_command<sch001::ControllerCommand>(controller_, pending_, std::move(body),
                                                std::move(done), kCardReplyGrace, "CAN");
}

void Sch001Backend::poll(MonoTime now) {
  sch001::CommandReply r;
  while (controller_.poll_reply(r)) pending_.complete(r.tag, reply_result(r));
  pending_.expire(now, "the CAN thread did not answer; see the journal");
}

void Sch001Backend::update_inputs(const api::InputUpdate& update, api::Responder done) {
  done(inputs_.take(update, [this](const lift::Inputs& now) { send_inputs(now); }));
}

void Sch001Backend::simulated_inputs(const lift::Inputs& sample) {
  inputs_.take_sample(sample, [this](const lift::Inputs& now) { send_inputs(now); });
}

void Sch001Backend::send_inputs(const lift::Inputs& inputs) {
  (void)controller_.post(sch001::ControllerCommand{0, sch001::InputsCommand{inputs}});
}

bool Sch001Backend::send_shutdown(bool force) {
  return controller_.post(sch001::ControllerCommand{0, sch001::ShutdownCommand{force}});
}

void Sch001Backend::travel(const api::TravelArgs& args, api::Responder done) {
  sch001::TravelCommand cmd;
  cmd.floor = static_cast<std::size_t>(args.floor);
  // V4 and V3 where the unit has them (else the next lower), any other name the fast speed.
  cmd.speed = !args.speed || *args.speed == "V4" ? sch001::Speed::V4
              : *args.speed == "V3"              ? sch001::Speed::V3
                                                 : sch001::Speed::Fast;
  send(cmd, std::move(done));
}

void Sch001Backend::stop(api::Responder done) {
  send(sch001::StopCommand{}, std::move(done));
}

void Sch001Backend::relevel(api::Responder done) {
  send(sch001::RelevelCommand{}, std::move(done));
}

void Sch001Backend::inspection(bool on, const std::string& direction, api::Responder done) {
  sch001::InspectionCommand cmd;
  cmd.on = on;
  cmd.direction = direction_of(direction);
  send(cmd, std::move(done));
}

void Sch001Backend::calls(const std::string& action, std::optional<int> floor,
                          api::Responder done) {
  if (action == "list") {
    done(Result::ok({{"calls", calls_list(controller_.snapshot())}}));
    return;
  }
  sch001::CallCommand cmd;
  cmd.add = action == "add";
  cmd.floor = static_cast<std::size_t>(floor.value_or(0));
  send(cmd, std::move(done));
}

void Sch001Backend::sim(const api::SimRequest& request, api::Responder done) {
  if (sim_ == nullptr) {
    api::Backend::sim(request, std::move(done));
    return;
  }
  done(sim_->apply(request, mono_now()));
}

// ---- the lift ----

HydraulicLift::HydraulicLift(Daemon& daemon, const config::Config& config, bool simulate)
    : daemon_(daemon),
      config_(config),
      simulate_(simulate),
      socket_path_(config.api.socket),
      poll_timer_(daemon.io(), kPollPeriod),
      publisher_(config.api.state_rate_hz),
      wind_down_(
          daemon, [this](bool force) { return backend_->send_shutdown(force); }, kShutdownDeadline,
          kCardShutdownGrace) {
  rt::CanRunnerConfig rc;
  rc.endpoint = config.can.interface;
  const sch001::ControllerConfig cc = sch001_controller_config(config);
  rc.ids = {cc.link.ids.from_card};
  rc.rt.priority = config.rt.priority;
  rc.rt.cpu = config.rt.cpu;
  rc.rt.lock_memory = config.rt.lock_memory;
  std::optional<can::CanSocket> controller_end;
  const lift::PositionSource* position = nullptr;
  if (simulate_) {
    auto pair = can::CanSocket::pair();
    if (!pair) {
      throw std::runtime_error("simulated SCH001 card: " + pair.error().what + ": " +
                               std::strerror(pair.error().code));
    }
    controller_end.emplace(std::move(pair.value().first));
    sim_ = std::make_unique<SimulatedCard>(config, std::move(pair.value().second));
    position = &sim_->position();
    rc.endpoint = "socketpair";
  } else if (config.position.source == config::PositionSource::can) {
    // The encoder on the card's bus: its frames are read by the same runner.
    encoder_ = std::make_unique<can::CanEncoder>(
        encoder_format(config), std::chrono::milliseconds(config.position.can_timeout_ms));
    rc.ids.push_back(encoder_->format().id);
    position = encoder_.get();
  } else {
    position_feed_ =
        std::make_unique<lift::PositionFeed>(std::chrono::milliseconds(config.inputs.timeout_ms));
    position = position_feed_.get();
  }
  controller_ = std::make_unique<sch001::Sch001Controller>(cc, *position, mono_now());
  rt::CanEngine* engine = controller_.get();
  if (encoder_) {
    tap_ = std::make_unique<rt::EncoderTap>(*encoder_, controller_.get());
    engine = tap_.get();
  }
  runner_ = std::make_unique<rt::CanRunner>(rc, *engine);
  if (controller_end) runner_->adopt(std::move(*controller_end));
  backend_ = std::make_unique<Sch001Backend>(
      config, *controller_, *runner_,
      config.position.source == config::PositionSource::api ? position_feed_.get() : nullptr,
      sim_.get());
  server_ = std::make_unique<api::Server>(daemon.io(), *backend_, api_server_config(config),
                                          api_log_sink());
  if (sim_) {
    daemon.add_component({"sim", [this] { return sim_->start(); }, [this] { sim_->stop(); }});
  }
  daemon.add_component({"sch001", [this] { return start_runner(); }, [this] { stop_runner(); },
                        [this](std::function<void()> done) { wind_down(std::move(done)); }});
  register_api(daemon, *server_);
  daemon.set_progress_probe(progress_probe([this] { return runner_->progress(); }));
  daemon.set_running_status(simulate_ ? "simulated hydraulic lift running; API on " + socket_path_
                                      : "SCH001 card link starting on " + config.can.interface);
}

HydraulicLift::~HydraulicLift() {
  if (server_) server_->stop();
  stop_runner();
  if (sim_) sim_->stop();
}

void HydraulicLift::check_interface() const {
  const std::string& name = config_.can.interface;
  if (simulate_ || name.rfind("unix:", 0) == 0) return;
  const can::InterfaceInfo info = can::query_interface(name);
  if (!info.found) {
    log::event(log::Level::warn, "sch001", "can_interface_missing", {{"interface", name}},
               "CAN interface " + name + " does not exist (yet); liftd keeps trying to open it");
    return;
  }
  if (!info.up) {
    log::event(log::Level::warn, "sch001", "can_interface_down", {{"interface", name}},
               "CAN interface " + name +
                   " is down: bring it up at 125 kbit/s (systemd-networkd [CAN] BitRate=125000, "
                   "docs/sch001.md)");
  }
  // Card document 3a: 125 kbit/s.
  if (info.bitrate && *info.bitrate != 125000) {
    log::event(log::Level::warn, "sch001", "can_bitrate",
               {{"bitrate", std::to_string(*info.bitrate)}},
               "CAN interface " + name + " runs at " + std::to_string(*info.bitrate) +
                   " bit/s; the SCH001 card talks at 125000 (card document 3a)");
  } else if (!info.bitrate) {
    log::event(log::Level::info, "sch001", "can_bitrate_unknown", {{"interface", name}},
               "the bitrate of " + name + " could not be read" +
                   (info.error.empty() ? std::string() : " (" + info.error + ")") +
                   "; the SCH001 card needs 125 kbit/s");
  }
}

bool HydraulicLift::start_runner() {
  check_interface();
  const int error = runner_->start();
  if (error != 0) {
    log::event(log::Level::error, "sch001", "can_start_failed", {{"errno", std::to_string(error)}},
               std::string("cannot start the CAN thread: ") + std::strerror(error));
    return false;
  }
  if (!accept_rt_thread(config_, runner_->thread_status(), simulate_, "CAN")) {
    runner_->stop();
    return false;
  }
  log::event(log::Level::info, "sch001", "can_started", {{"interface", runner_->config().endpoint}},
             "SCH001 card link running on " + runner_->config().endpoint);
  poll_timer_.start([this] { poll(); });
  return true;
}

void HydraulicLift::stop_runner() {
  if (!poll_timer_.running()) return;
  poll_timer_.stop();
  runner_->stop();
  poll();  // the last events
}

void HydraulicLift::poll() {
  const MonoTime now = mono_now();
  if (sim_ && now - last_sim_inputs_ >= kSimInputsPeriod) {
    backend_->simulated_inputs(sim_->inputs(now));
    last_sim_inputs_ = now;
    sim_->log_violations();
  }
  backend_->poll(now);
  sch001::ControllerEvent event;
  while (controller_->poll_event(event)) handle_event(event);
  // Rejected card frames: counted always, journalled at most every 10 s with what came.
  const sch001::ControllerSnapshot s = controller_->snapshot();
  const auto rejected = [](const sch001::CardLinkCounters& c) {
    return c.wrong_length + c.unknown_first_byte + c.own_id;
  };
  if (rejected(s.counters) != rejected(logged_counters_) &&
      now - last_reject_log_ >= kRejectLogInterval) {
    const auto& c = s.counters;
    const auto& l = logged_counters_;
    log::event(log::Level::warn, "sch001", "card_frames_rejected",
               {{"wrong_length", std::to_string(c.wrong_length - l.wrong_length)},
                {"unknown_first_byte", std::to_string(c.unknown_first_byte - l.unknown_first_byte)},
                {"own_id", std::to_string(c.own_id - l.own_id)}},
               "frames not acted on since the last report: " +
                   std::to_string(c.wrong_length - l.wrong_length) + " of the wrong length, " +
                   std::to_string(c.unknown_first_byte - l.unknown_first_byte) +
                   " with an unknown first byte, " + std::to_string(c.own_id - l.own_id) +
                   " on our own identifier (another node sends on it)");
    logged_counters_ = s.counters;
    last_reject_log_ = now;
  }
  publisher_.publish(*server_, backend_->status(), now);
  const sch001::ControllerSnapshot rest = controller_->snapshot();
  wind_down_.check({rest.shutting_down, rest.quiesced, rest.floor, rest.position_mm}, now);
}

void HydraulicLift::handle_event(const sch001::ControllerEvent& event) {
  using Kind = sch001::ControllerEvent::Kind;
  switch (event.kind) {
    case Kind::Link: {
      const char* state = event.link == sch001::LinkChange::Silent ? "fault" : "up";
      const std::string text =
          event.link == sch001::LinkChange::FirstHeard ? "first frame from the SCH001 card"
          : event.link == sch001::LinkChange::Silent
              ? "no frame from the SCH001 card for 10 s (card document 3f): no travel command"
              : "the SCH001 card is heard again";
      // A silent card is one of the card faults the journal catalog explains (card_fault).
      const bool silent = event.link == sch001::LinkChange::Silent;
      log::event(silent ? log::Level::warn : log::Level::info, "sch001",
                 silent ? "card_fault" : "link_state_changed", {{"state", state}}, text);
      daemon_.report_status(std::string("SCH001 card link ") + state);
      server_->publish("link", {{"kind", "state changed"}, {"state", state}, {"detail", text}});
      break;
    }
    case Kind::Card: {
      const sch001::ControllerSnapshot s = controller_->snapshot();
      const std::string on = card_text(event.card, s.single_unit);
      // ERR or RDY = 0 forbid every travel signal (3d, 3e): the catalog's card_fault.
      const bool fault = event.card.err || !event.card.rdy;
      log::event(fault || event.card.t1 || event.card.p1 || event.card.p2 ? log::Level::warn
                                                                          : log::Level::info,
                 "sch001", fault ? "card_fault" : "card_status", {{"relays", on}},
                 "SCH001 card status: " + on +
                     " (ERR fault, RDY ready, T1 oil temperature, P1 minimum/maximum pressure, "
                     "P2 overpressure)");
      break;
    }
    case Kind::Travel:
      report_travel(*server_, event.travel, *controller_);
      break;
    case Kind::BusError:
      log::event(event.bus_error.is_fault() ? log::Level::error : log::Level::warn, "sch001",
                 "can_error", {{"error", event.bus_error.describe()}},
                 "CAN error frame: " + event.bus_error.describe());
      break;
    case Kind::Endpoint:
      if (event.endpoint_up) {
        log::event(log::Level::info, "sch001", "can_open",
                   {{"interface", runner_->config().endpoint}},
                   "CAN endpoint " + runner_->config().endpoint + " open");
      } else {
        log::event(log::Level::error, "sch001", "can_lost", {{"error", runner_->last_error()}},
                   "CAN endpoint " + runner_->config().endpoint +
                       " failed: " + runner_->last_error() + "; no travel command; reopening");
      }
      break;
    case Kind::FaultRaised:
    case Kind::FaultCleared:
      report_fault(*server_, event.fault, sch001::fault_text(event.fault),
                   event.kind == Kind::FaultRaised);
      break;
    case Kind::CallServed:
      report_call_served(*server_, event.floor);
      break;
  }
}

void HydraulicLift::wind_down(std::function<void()> done) {
  if (!poll_timer_.running()) {
    done();
    return;
  }
  wind_down_.start(std::move(done), controller_->snapshot().travel_kind != sch001::TravelKind::None,
                   mono_now());
}

}  // namespace liftd::daemon
