#include "sch001/host/hydraulic_lift.hpp"

#include <poll.h>

#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <utility>

#include "api/commands.hpp"
#include "can/interface_info.hpp"
#include "host/lift_common.hpp"
#include "log/log.hpp"
#include "sch001/config/section.hpp"
#include "sch001/host/sim_actions.hpp"
#include "sch001/registry_entry.hpp"

namespace liftd::daemon {
namespace {

using namespace std::chrono_literals;
using api::Result;

constexpr auto kRejectLogInterval = 10s;  // rejected card frames are journalled at most this often
// Card status changes and error frames: this many lines in full per interval, then a count.
constexpr std::uint64_t kBurstLines = 5;
constexpr auto kBurstInterval = 10s;
constexpr double kSinkMmPerS = 2.0;  // `sim sink`: a leaking valve or cooling oil

}  // namespace

sch001::ControllerConfig sch001_controller_config(const config::Config& c) {
  sch001::ControllerConfig out;
  std::string why;
  const auto ids =
      sch001::ids_for(static_cast<std::uint32_t>(sch001_section(c).base),
                      static_cast<std::uint32_t>(sch001_section(c).controller_node), &why);
  if (!ids) throw std::invalid_argument("sch001: " + why);
  out.link.ids = *ids;
  out.link.single_unit = sch001_section(c).single_unit;
  sch001::HydraulicConfig& h = out.hydraulic;
  h.has_v3 = sch001_section(c).has_v3;
  h.has_v4 = sch001_section(c).has_v4;
  h.fast_down = sch001_section(c).fast_down == config::FastDown::sp3 ? sch001::FastDown::Sp3
                                                                     : sch001::FastDown::Hsp;
  h.star_delta_ms = static_cast<std::uint32_t>(sch001_section(c).star_delta_ms);
  h.slowdown_up_mm = static_cast<std::uint32_t>(sch001_section(c).slowdown_up_mm);
  h.slowdown_down_mm = static_cast<std::uint32_t>(sch001_section(c).slowdown_down_mm);
  h.slowdown_v3_mm = static_cast<std::uint32_t>(sch001_section(c).slowdown_v3_mm);
  h.slowdown_v4_mm = static_cast<std::uint32_t>(sch001_section(c).slowdown_v4_mm);
  h.stop_tolerance_mm = static_cast<std::uint32_t>(sch001_section(c).stop_tolerance_mm);
  h.relevel_start_mm = static_cast<std::uint32_t>(sch001_section(c).relevel_start_mm);
  h.max_travel_ms = static_cast<std::uint32_t>(sch001_section(c).max_travel_ms);
  h.relevel_doors_open = c.travel.relevel_with_doors == config::RelevelDoors::open ||
                         c.travel.relevel_with_doors == config::RelevelDoors::both;
  out.auto_relevel =
      sch001_section(c).auto_relevel && c.travel.relevel_with_doors != config::RelevelDoors::never;
  out.lift = lift_config(c);
  for (const auto& f : c.floors) out.floors_mm.push_back(f.level_mm);
  out.inputs_timeout = std::chrono::milliseconds(c.inputs.timeout_ms);
  out.inspection_hold = std::chrono::milliseconds(c.travel.inspection_hold_ms);
  return out;
}

TravelBitNames Sch001Drive::travel_bit_names() {
  // 3c: SP3 SP2 SP1 SFY MSP HSP DW UP, MSB first; 3b: ERR PNP2 AVV T1 P1 P2 RDY PNP1.
  return {{"up", "dw", "hsp", "msp", "sfy", "sp1", "sp2", "sp3"},
          {"pnp1", "rdy", "p2", "p1", "t1", "avv", "pnp2", "err"}};
}

namespace {

nlohmann::json card_json(const sch001::CardStatus& s, bool single_unit) {
  nlohmann::json j = api::flags_object(
      {{"err", s.err}, {"rdy", s.rdy}, {"t1", s.t1}, {"p1", s.p1}, {"p2", s.p2}, {"pnp1", s.pnp1}});
  // 3b: valid in a single-unit system only.
  j["avv"] = single_unit ? nlohmann::json(s.avv) : nlohmann::json(nullptr);
  j["pnp2"] = single_unit ? nlohmann::json(s.pnp2) : nlohmann::json(nullptr);
  return j;
}

nlohmann::json bits_json(const sch001::CommandBits& b) {
  return api::flags_object({{"up", b.up},
                            {"dw", b.dw},
                            {"hsp", b.hsp},
                            {"msp", b.msp},
                            {"sfy", b.sfy},
                            {"sp1", b.sp1},
                            {"sp2", b.sp2},
                            {"sp3", b.sp3}});
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

sch001::sim::CardSimConfig card_sim_config(const config::Config& c) {
  sch001::sim::CardSimConfig out;
  out.ids = *sch001::ids_for(static_cast<std::uint32_t>(sch001_section(c).base),
                             static_cast<std::uint32_t>(sch001_section(c).controller_node));
  out.fast_down_sp3 = sch001_section(c).fast_down == config::FastDown::sp3;
  if (!c.floors.empty()) {
    out.start_mm = static_cast<double>(c.floors.front().level_mm);
    out.bottom_mm = shaft_bottom_mm(c);
    out.top_mm = shaft_top_mm(c);
  }
  out.slow_mps = c.sim.slow_mm_per_s / 1000.0;
  return out;
}

}  // namespace

SimulatedCard::SimulatedCard(const config::Config& config, const std::string& socket_path)
    : SimulatorThread(config),
      socket_path_(socket_path),
      card_(card_sim_config(config), mono_now()) {
  auto listener = can::listen_unix(socket_path);
  if (!listener) {
    throw std::runtime_error("simulated SCH001 card: " + listener.error().what + ": " +
                             std::strerror(listener.error().code));
  }
  listener_ = listener.value();
  encoder_.set(card_.state().position_mm);
}

SimulatedCard::~SimulatedCard() {
  stop();
  peer_.reset();
  if (listener_ >= 0) ::close(listener_);
  ::unlink(socket_path_.c_str());
}

bool SimulatedCard::start() {
  start_thread([this] { loop(); });
  log::event(log::Level::info, "sim", "sim_started", {{"device", socket_path_}},
             "simulated SCH001 card listening on " + socket_path_);
  return true;
}

void SimulatedCard::stop() {
  if (!join_thread()) return;
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
  while (!stopping()) {
    std::array<pollfd, 2> fds{};
    fds[0] = {listener_, POLLIN, 0};
    fds[1] = {peer_ ? peer_->fd() : -1, POLLIN, 0};
    (void)::poll(fds.data(), fds.size(), 5);
    const MonoTime now = mono_now();
    if ((fds[0].revents & POLLIN) != 0) {  // the controller (re)connects: the newest counts
      const int fd = ::accept4(listener_, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
      if (fd >= 0) peer_.emplace(can::CanSocket::adopt(fd));
    }
    std::lock_guard<std::mutex> lock(mutex_);
    if (drop_) {  // `sim card_reconnect`: the card's connection drops; the controller reopens
      drop_ = false;
      peer_.reset();
      card_.connection_lost();
    }
    for (int i = 0; peer_ && i < 16; ++i) {
      const can::Received r = peer_->read();
      if (r.kind == can::Received::Kind::Frame) {
        card_.on_frame(r.frame, now);
      } else if (r.kind == can::Received::Kind::Closed || r.kind == can::Received::Kind::Failed) {
        peer_.reset();
        card_.connection_lost();
      } else if (r.kind != can::Received::Kind::Error) {
        break;
      }
    }
    if (bus_off_ && peer_) {
      can::ErrorReport report;
      report.bus_off = true;
      (void)peer_->write_error(report);
      bus_off_ = false;
    }
    // The car moves whether or not a controller is connected; the card talks only to one.
    if (const auto frame = card_.poll(now)) {
      if (peer_) {
        (void)peer_->write(*frame);
      } else {
        card_.connection_lost();
      }
    }
    car_moved(card_.state().position_mm, card_.state().velocity_mps != 0.0, now);
  }
}

void SimulatedCard::log_violations() {
  std::vector<sch001::sim::CardViolation> found;
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
  std::lock_guard<std::mutex> lock(mutex_);
  const auto shared = [this, &request](api::SimAction action) -> std::optional<Result> {
    using api::SimAction;
    switch (action) {
      case SimAction::GeneralFault:
        card_.set_err(request.on);
        break;
      case SimAction::NotReady:
        card_.set_rdy(!request.on);
        break;
      case SimAction::Drift:
        if (card_.state().velocity_mps != 0.0) {
          return Result::fail(api::ErrorCode::Busy, "the car is moving: drift only at rest");
        }
        card_.drift(request.drift_mm);
        break;
      default:  // the board's actions: SimulatedBoard::apply took them; apply_sim refused the rest
        break;
    }
    return std::nullopt;
  };
  const auto own = [this, &request](std::size_t index) -> std::optional<Result> {
    switch (static_cast<Sch001SimAction>(index)) {
      case Sch001SimAction::OilTemperature:
        card_.set_t1(request.on);
        break;
      case Sch001SimAction::Pressure:
        card_.set_p1(request.on);
        break;
      case Sch001SimAction::Overpressure:
        card_.set_p2(request.on);
        break;
      case Sch001SimAction::CardSilence:
        card_.set_silent(request.on);
        break;
      case Sch001SimAction::BusOff:
        bus_off_ = true;
        break;
      case Sch001SimAction::CardReconnect:
        drop_ = true;
        break;
      case Sch001SimAction::ColdOil:
        card_.set_cold_oil(request.on);
        break;
      case Sch001SimAction::Sink:
        card_.set_sink(request.on ? kSinkMmPerS : 0.0);
        break;
    }
    return std::nullopt;
  };
  return apply_sim(kSch001SimActionTable, request, board_, now, shared, own,
                   [this] { return state_json_locked(); });
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

api::StatusSnapshot Sch001Backend::status() {
  const sch001::ControllerSnapshot s = controller_.snapshot();
  // After any (re)open the card's status is unknown: init until its first frame there.
  const api::LinkState link =
      !s.endpoint_up || s.silent
          ? (s.ever_heard || s.silent || s.endpoint_lost ? api::LinkState::Fault
                                                         : api::LinkState::Down)
          : (s.heard ? api::LinkState::Up : api::LinkState::Init);
  api::StatusSnapshot out = neutral_status(s, link);
  nlohmann::json d = nlohmann::json::object();
  d["card"] = s.card ? card_json(*s.card, s.single_unit) : nlohmann::json(nullptr);
  d["timeout_enabled"] = s.timeout_enabled;
  d["commands"] = bits_json(s.bits_sent);
  d["current_floor"] = s.current_floor_sent;
  d["destination_floor"] = s.destination_floor_sent;
  d["motor_on"] = s.motor_on;
  d["phase"] = std::string(sch001::to_string(s.phase));
  d["send_failing"] = s.send_failing;
  d["foreign_sender"] = s.foreign_sender;
  out.details = std::move(d);
  out.contactors_on = s.motor_on;
  return out;
}

api::StatsSnapshot Sch001Backend::stats() {
  const sch001::ControllerSnapshot s = controller_.snapshot();
  const rt::CanRunnerCounters c = runner_.counters();
  api::StatsSnapshot out = neutral_stats(c.frames_sent, s.steps);
  nlohmann::json& d = out.details;
  // The card's frames by kind (card document 3b, 3f, 1.6) and the CAN endpoint's own counters.
  d["frames_received"] = c.frames_received;
  d["status_frames"] = s.counters.status_frames;
  d["timeout_commands"] = s.counters.timeout_commands;
  d["wrong_length"] = s.counters.wrong_length;
  d["unknown_first_byte"] = s.counters.unknown_first_byte;
  d["own_id_frames"] = s.counters.own_id;
  d["other_id_frames"] = s.counters.other_id;
  d["card_silences"] = s.counters.timeouts;
  d["error_frames"] = c.error_frames;
  d["send_errors"] = c.send_errors;
  d["reopens"] = c.reopens;
  d["dropped_records"] = c.dropped;
  d["overflowed_frames"] = c.overflowed;
  return out;
}

std::vector<api::TraceEntry> Sch001Backend::trace(std::size_t max_entries) {
  // Each of our frames with the card's frame it answered (card document 3c): identifier (2
  // bytes) and data.
  return trace_exchanges(runner_.recorder().copy(), max_entries, {.we_answer = true});
}

void Sch001Backend::travel(const api::TravelArgs& args, api::Responder done) {
  note_travel_asked();
  sch001::TravelCommand cmd;
  cmd.floor = static_cast<std::size_t>(args.floor);
  // V4 and V3 where the unit has them (else the next lower), any other name the fast speed.
  cmd.speed = !args.speed || *args.speed == "V4" ? sch001::Speed::V4
              : *args.speed == "V3"              ? sch001::Speed::V3
                                                 : sch001::Speed::Fast;
  send(cmd, std::move(done));
}

// ---- the lift ----

HydraulicLift::HydraulicLift(Host& daemon, const config::Config& config, bool simulate)
    : ControllerLift(daemon, config, simulate),
      card_status_lines_(kBurstLines, kBurstInterval),
      bus_error_lines_(kBurstLines, kBurstInterval) {
  rt::CanRunnerConfig rc;
  rc.endpoint = config.can.interface;
  sch001::ControllerConfig cc = sch001_controller_config(config);
  // Our own identifier too: nobody else may send on it (card document 1.6), so a frame there
  // is another node commanding the card, counted and reported (the socket never hands us our
  // own frames).
  rc.ids = {cc.link.ids.from_card, cc.link.ids.to_card};
  rc.rt.priority = config.rt.priority;
  rc.rt.cpu = config.rt.cpu;
  rc.rt.lock_memory = config.rt.lock_memory;
  rc.rt.name = "liftd-sch001";  // the card's loop, as ps -L and chrt -p show it
  const PositionSource* position = nullptr;
  if (simulate_) {
    // Beside the API socket, in the daemon's own runtime directory.
    const std::string card_socket =
        (std::filesystem::path(config.api.socket).parent_path() / "sch001-card.sock").string();
    sim_ = std::make_unique<SimulatedCard>(config, card_socket);
    position = &sim_->position();
    cc.level_zone_source = &sim_->level_zone();
    rc.endpoint = "unix:" + card_socket;
  } else if (config.position.source == config::PositionSource::can) {
    // The encoder on the card's bus: its frames are read by the same runner.
    encoder_ = std::make_unique<can::CanEncoder>(
        encoder_format(config), std::chrono::milliseconds(config.position.can_timeout_ms));
    rc.ids.push_back(encoder_->format().id);
    position = encoder_.get();
  } else {
    position = &make_position_feed();
  }
  controller_ = std::make_unique<sch001::Sch001Controller>(cc, *position, mono_now());
  rt::CanEngine* engine = controller_.get();
  if (encoder_) {
    tap_ = std::make_unique<rt::EncoderTap>(*encoder_, controller_.get());
    engine = tap_.get();
  }
  runner_ = std::make_unique<rt::CanRunner>(rc, *engine);
  register_parts(std::make_unique<Sch001Backend>(config, daemon.config_schema(), *controller_,
                                                 *runner_, api_position_feed(), sim_.get()),
                 "hydraulic lift", "SCH001 card link", config.can.interface);
}

HydraulicLift::~HydraulicLift() {
  shut_down();
}

void HydraulicLift::before_start() {
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

void HydraulicLift::journal_started() {
  log::event(log::Level::info, "sch001", "can_started", {{"interface", runner_->config().endpoint}},
             "SCH001 card link running on " + runner_->config().endpoint);
}

void HydraulicLift::after_events(MonoTime now) {
  const sch001::ControllerSnapshot s = controller_->snapshot();
  journal_card_status(s, now);
  journal_bus_errors(s, now);
  journal_link_conditions(s);
  // Rejected card frames: counted always, journalled at most every 10 s with what came.
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
}

void HydraulicLift::journal_card_status(const sch001::ControllerSnapshot& s, MonoTime now) {
  const std::uint64_t changes = card_status_lines_.growth(s.status_changes);
  if (s.card && card_status_lines_.admit(changes, now)) {
    const std::string on = card_text(*s.card, s.single_unit);
    // ERR or RDY = 0 forbid every travel signal (3d, 3e): the catalog's card_fault.
    const bool fault = s.card->err || !s.card->rdy;
    log::event(
        fault || s.card->t1 || s.card->p1 || s.card->p2 ? log::Level::warn : log::Level::info,
        "sch001", fault ? "card_fault" : "card_status", {{"relays", on}},
        "SCH001 card status: " + on +
            " (ERR fault, RDY ready, T1 oil temperature, P1 minimum/maximum pressure, "
            "P2 overpressure)" +
            (changes > 1 ? "; " + std::to_string(changes) + " changes since the last poll"
                         : std::string()),
        fault ? std::optional(log::Catalogued::CardFault) : std::nullopt);
  }
  if (const auto n = card_status_lines_.suppressed(now)) {
    log::event(log::Level::warn, "sch001", "card_status_flapping",
               {{"changes", std::to_string(*n)},
                {"relays", s.card ? card_text(*s.card, s.single_unit) : "unknown"}},
               "SCH001 card status changed " + std::to_string(*n) + " more times in the last " +
                   std::to_string(kBurstInterval.count()) + " s without a line each; now: " +
                   (s.card ? card_text(*s.card, s.single_unit) : "unknown"));
  }
}

void HydraulicLift::journal_bus_errors(const sch001::ControllerSnapshot& s, MonoTime now) {
  const std::uint64_t frames = bus_error_lines_.growth(s.bus_errors);
  if (bus_error_lines_.admit(frames, now)) {
    const can::ErrorReport& e = s.last_bus_error;
    log::event(
        e.is_fault() ? log::Level::error : log::Level::warn, "sch001", "can_error",
        {{"error", e.describe()}, {"frames", std::to_string(frames)}},
        "CAN error frame: " + e.describe() +
            (frames > 1 ? " (" + std::to_string(frames) + " since the last poll)" : std::string()));
  }
  if (const auto n = bus_error_lines_.suppressed(now)) {
    log::event(log::Level::warn, "sch001", "can_errors_suppressed",
               {{"frames", std::to_string(*n)}, {"last", s.last_bus_error.describe()}},
               std::to_string(*n) + " more CAN error frames in the last " +
                   std::to_string(kBurstInterval.count()) +
                   " s without a line each; the last: " + s.last_bus_error.describe());
  }
}

void HydraulicLift::journal_link_conditions(const sch001::ControllerSnapshot& s) {
  // Each once when it begins and once when it ends (the link fault carries the rest).
  if (s.foreign_sender != foreign_sender_logged_) {
    foreign_sender_logged_ = s.foreign_sender;
    log::event(s.foreign_sender ? log::Level::error : log::Level::info, "sch001",
               s.foreign_sender ? "own_id_in_use" : "own_id_free", {},
               s.foreign_sender
                   ? "another node sends on liftd's CAN identifier: it commands the SCH001 card "
                     "beside liftd (card document 1.6: the card's 96 identifiers are for it "
                     "alone); check the bus wiring and the other nodes' addresses; no travel "
                     "command goes out"
                   : "no frame on liftd's CAN identifier for 10 s",
               s.foreign_sender ? std::optional(log::Catalogued::CanOwnIdInUse) : std::nullopt);
  }
  if (s.send_failing != send_failing_logged_) {
    send_failing_logged_ = s.send_failing;
    log::event(s.send_failing ? log::Level::error : log::Level::info, "sch001",
               s.send_failing ? "can_send_failing" : "can_send_ok", {},
               s.send_failing ? "answers to the SCH001 card cannot be sent (the CAN socket's "
                                "queue stays full: is anything taking our frames?)"
                              : "answers to the SCH001 card go out again");
  }
}

void HydraulicLift::journal_endpoint(bool up, MonoTime now) {
  const std::string& endpoint = runner_->config().endpoint;
  if (!up) {
    if (lost_since_) {  // the same episode: the reopened endpoint failed again
      ++lost_failures_;
      log::event(log::Level::debug, "sch001", "can_lost_again", {{"error", runner_->last_error()}},
                 "CAN endpoint " + endpoint + " failed again: " + runner_->last_error());
      return;
    }
    lost_since_ = now;
    lost_failures_ = 1;
    log::event(log::Level::error, "sch001", "can_lost", {{"error", runner_->last_error()}},
               "CAN endpoint " + endpoint + " failed: " + runner_->last_error() +
                   "; no travel command; reopening (100 ms, doubling up to 5 s) until the card "
                   "is heard again");
    return;
  }
  log::event(lost_since_ ? log::Level::debug : log::Level::info, "sch001", "can_open",
             {{"interface", endpoint}}, "CAN endpoint " + endpoint + " open");
}

void HydraulicLift::handle_event(const sch001::ControllerEvent& event) {
  using Kind = sch001::ControllerEvent::Kind;
  switch (event.kind) {
    case Kind::Link: {
      const char* state = event.link == sch001::LinkChange::Silent ? "fault" : "up";
      std::string text =
          event.link == sch001::LinkChange::FirstHeard ? "first frame from the SCH001 card"
          : event.link == sch001::LinkChange::Silent
              ? "no frame from the SCH001 card for 10 s (card document 3f): no travel command"
              : "the SCH001 card is heard again";
      if (event.link == sch001::LinkChange::FirstHeard && lost_since_) {
        const auto lasted =
            std::chrono::duration_cast<std::chrono::milliseconds>(event.at - *lost_since_);
        text = "the SCH001 card is heard again on a reopened CAN endpoint, " +
               std::to_string(lasted.count()) + " ms and " + std::to_string(lost_failures_) +
               " endpoint failure(s) after it was lost";
        lost_since_.reset();
        lost_failures_ = 0;
      }
      // A silent card is one of the card faults the journal catalog explains (card_fault).
      const bool silent = event.link == sch001::LinkChange::Silent;
      log::event(silent ? log::Level::warn : log::Level::info, "sch001",
                 silent ? "card_fault" : "link_state_changed", {{"state", state}}, text,
                 silent ? std::optional(log::Catalogued::CardFault) : std::nullopt);
      daemon_.report_status(std::string("SCH001 card link ") + state);
      server_->publish("link", {{"kind", "state changed"}, {"state", state}, {"detail", text}});
      break;
    }
    case Kind::Endpoint:
      journal_endpoint(event.endpoint_up, event.at);
      break;
    default:  // every lift's events: report_lift_event()
      break;
  }
}

}  // namespace liftd::daemon

// The registry makes this kind's lift through this instance (lib/host/registry_entry.hpp).
template std::unique_ptr<liftd::daemon::LiftRunner>
liftd::host::make_lift<liftd::daemon::HydraulicLift>(liftd::daemon::Host&,
                                                     const liftd::config::Config&, bool);
