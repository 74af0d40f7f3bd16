#include "host/lift_common.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <vector>

#include "api/commands.hpp"
#include "lift/calls.hpp"
#include "lift/floors.hpp"
#include "log/log.hpp"
#include "service/notify.hpp"

namespace liftd::daemon {

// The API's limits are the lift's (lib/api sits below lib/lift and cannot name them): a `calls`
// request never holds more floors than lift::CallQueue stores, nor names a floor the floor table
// cannot have.
static_assert(api::kMaxCallsQueued == static_cast<std::int64_t>(lift::kMaxFloors),
              "api::kMaxCallsQueued is lift::CallQueue's capacity");
static_assert(api::kMaxFloorIndex < static_cast<std::int64_t>(lift::kMaxFloors),
              "api::kMaxFloorIndex names a floor lift::FloorTable can hold");

namespace {

// The API socket systemd passed (socket activation, FileDescriptorName=api), or -1 when systemd
// passed none: then the server creates it as without systemd. Other passed descriptors are
// closed. Throws when systemd passed sockets but none that liftd can serve on api.socket: liftd
// must neither listen where no client looks nor create (and later unlink) a socket file beside
// the one the socket unit owns.
int take_listen_fd(const std::string& socket_path) {
  const std::vector<service::ListenFd> fds = service::listen_fds_from_environment();
  if (fds.empty()) return -1;
  const int fd = service::pick_listen_fd(fds, "api");
  service::close_unused_listen_fds(fds, fd);
  if (fd < 0) {
    std::string names;
    for (const auto& f : fds) names += (names.empty() ? "\"" : ", \"") + f.name + "\"";
    throw std::runtime_error(
        "systemd passed " + std::to_string(fds.size()) + " socket(s) (" + names +
        ") but none is a listening Unix stream socket named \"api\" (FileDescriptorName=api in "
        "liftd.socket), and liftd does not create its own socket beside the socket unit's: fix "
        "liftd.socket so that it passes one socket for the API");
  }
  const std::optional<std::string> bound = service::unix_socket_path(fd);
  if (!bound || *bound != socket_path) {
    ::close(fd);
    throw std::runtime_error("the API socket systemd passed is bound to " +
                             (bound ? (bound->empty() ? "no path (unnamed)" : *bound)
                                    : std::string("an unknown address")) +
                             " but api.socket is " + socket_path +
                             ": clients would look where nothing listens; make ListenStream= in "
                             "liftd.socket and api.socket in the configuration the same path");
  }
  log::event(log::Level::info, "api", "socket_passed", {{"socket", socket_path}},
             "using the API socket systemd passed (socket activation); connections wait in its "
             "queue while liftd restarts");
  return fd;
}

}  // namespace

config::Config simulation_defaults() {
  config::Config cfg;
  cfg.position.source = config::PositionSource::sim;
  const char* runtime = std::getenv("XDG_RUNTIME_DIR");
  cfg.api.socket =
      std::string(runtime != nullptr && *runtime != '\0' ? runtime : ".") + "/liftd-sim.sock";
  cfg.api.socket_group.clear();
  cfg.api.read_group.clear();
  cfg.api.control_group.clear();
  cfg.api.inputs_group.clear();
  cfg.rt.lock_memory = false;       // an ordinary user may not lock memory; say nothing about it
  cfg.rt.require_realtime = false;  // nor get SCHED_FIFO: the simulation runs anyway, warned
  return cfg;
}

std::string default_runtime_dir(const config::Config& c) {
  if (const char* dir = std::getenv("RUNTIME_DIRECTORY")) return dir;  // systemd RuntimeDirectory
  return std::filesystem::path(c.api.socket).parent_path().string();
}

api::ServerConfig api_reload_config(const config::Config& c) {
  api::ServerConfig server;
  server.read_group = c.api.read_group;
  server.control_group = c.api.control_group;
  server.inputs_group = c.api.inputs_group;
  server.max_clients = static_cast<std::size_t>(c.api.max_clients);
  server.max_requests_per_second = c.api.max_requests_per_s;
  server.idle_timeout = std::chrono::seconds(c.api.idle_timeout_s);
  server.max_clients_per_uid = static_cast<std::size_t>(c.api.max_clients_per_uid);
  server.reserved_clients = static_cast<std::size_t>(c.api.reserved_clients);
  server.stalled_reader_timeout = std::chrono::seconds(c.api.stalled_reader_timeout_s);
  return server;
}

api::ServerConfig api_server_config(const config::Config& c) {
  api::ServerConfig server = api_reload_config(c);
  server.socket_path = c.api.socket;
  server.socket_group = c.api.socket_group;
  server.listen_fd = take_listen_fd(c.api.socket);
  // hello's car: a dispatcher of a group tells its cars apart by it and learns their floors
  // without a `config` request.
  nlohmann::json floors = nlohmann::json::array();
  for (const auto& f : c.floors) floors.push_back({{"name", f.name}, {"level_mm", f.level_mm}});
  server.car = {
      {"name", c.api.car_name.empty() ? nlohmann::json(nullptr) : nlohmann::json(c.api.car_name)},
      {"drive_kind", std::string(drive::to_string(c.drive.kind))},
      {"floors", std::move(floors)}};
  return server;
}

api::LogFn api_log_sink() {
  return [](api::LogLevel level, std::string_view text) {
    const log::Level l = level == api::LogLevel::Error  ? log::Level::error
                         : level == api::LogLevel::Warn ? log::Level::warn
                         : level == api::LogLevel::Info ? log::Level::info
                                                        : log::Level::debug;
    log::write(l, "api", std::string(text));
  };
}

lift::LiftConfig lift_config(const config::Config& c) {
  lift::LiftConfig out;
  out.level_tolerance_mm = static_cast<std::uint32_t>(c.travel.level_tolerance_mm);
  out.call_stop_ms = static_cast<std::uint32_t>(c.travel.call_stop_ms);
  return out;
}

namespace {

// The boolean inputs the API and the cycle both name, each pair once (to_lift and from_lift are
// each other's inverse). The shaft's deceleration points are arrays on the cycle's side.
struct InputPair {
  bool api::Inputs::*api;
  bool lift::Inputs::*lift;
};
constexpr InputPair kInputPairs[] = {
    {&api::Inputs::safety_chain, &lift::Inputs::safety_chain_closed},
    {&api::Inputs::doors_closed, &lift::Inputs::doors_closed},
    {&api::Inputs::doors_locked, &lift::Inputs::doors_locked},
    {&api::Inputs::inspection, &lift::Inputs::inspection},
    {&api::Inputs::recall, &lift::Inputs::recall},
    {&api::Inputs::button_up, &lift::Inputs::button_up},
    {&api::Inputs::button_down, &lift::Inputs::button_down},
    {&api::Inputs::end_zone_top, &lift::Inputs::end_zone_top},
    {&api::Inputs::end_zone_bottom, &lift::Inputs::end_zone_bottom},
    {&api::Inputs::zone_door, &lift::Inputs::door_zone_bridge},
    {&api::Inputs::door_reversal, &lift::Inputs::door_reversal},
    // Shaft signals: the level zone and the relevelling zones.
    {&api::Inputs::zone_level, &lift::Inputs::level_zone},
    {&api::Inputs::relevel_up, &lift::Inputs::relevel_up},
    {&api::Inputs::relevel_down, &lift::Inputs::relevel_down},
};
// Every speed's deceleration points by direction, V1..V7 (a travel at Vn looks only at Vn's
// point for its direction).
constexpr bool api::Inputs::*kDecelUp[] = {&api::Inputs::decel_v1_up, &api::Inputs::decel_v2_up,
                                           &api::Inputs::decel_v3_up, &api::Inputs::decel_v4_up,
                                           &api::Inputs::decel_v5_up, &api::Inputs::decel_v6_up,
                                           &api::Inputs::decel_v7_up};
constexpr bool api::Inputs::*kDecelDown[] = {
    &api::Inputs::decel_v1_down, &api::Inputs::decel_v2_down, &api::Inputs::decel_v3_down,
    &api::Inputs::decel_v4_down, &api::Inputs::decel_v5_down, &api::Inputs::decel_v6_down,
    &api::Inputs::decel_v7_down};

}  // namespace

lift::Inputs to_lift(const api::Inputs& in) {
  lift::Inputs out;
  out.valid = true;
  for (const InputPair& p : kInputPairs) out.*(p.lift) = in.*(p.api);
  for (std::size_t i = 0; i < std::size(kDecelUp); ++i) {
    out.decel_up[i] = in.*(kDecelUp[i]);
    out.decel_down[i] = in.*(kDecelDown[i]);
  }
  return out;
}

api::Inputs from_lift(const lift::Inputs& in) {
  api::Inputs out;
  for (const InputPair& p : kInputPairs) out.*(p.api) = in.*(p.lift);
  for (std::size_t i = 0; i < std::size(kDecelUp); ++i) {
    out.*(kDecelUp[i]) = in.decel_up[i];
    out.*(kDecelDown[i]) = in.decel_down[i];
  }
  return out;
}

api::Inputs MachineInputs::seen() const {
  const std::optional<lift::Inputs> now = simulated_ ? current() : std::nullopt;
  if (!now) return api_;
  api::Inputs out = from_lift(*now);
  out.position_mm = api_.position_mm;
  return out;
}

std::optional<api::Result> MachineInputs::update(const api::InputUpdate& update) {
  if (update.position_mm && config_.position.source != config::PositionSource::api) {
    return api::Result::fail(api::ErrorCode::BadRequest,
                             "position_mm is only accepted when position.source is \"api\"",
                             "position_mm");
  }
  update.apply_to(api_);
  if (update.position_mm && feed_ != nullptr) feed_->set(*update.position_mm, mono_now());
  return std::nullopt;
}

std::optional<lift::Inputs> MachineInputs::current() const {
  if (!simulated_) return to_lift(api_);
  if (!sample_) return std::nullopt;
  const lift::Inputs api = to_lift(api_);
  lift::Inputs out = *sample_;
  out.door_reversal = out.door_reversal || api.door_reversal;
  // The switches and buttons of the simulated board have nobody to turn them: the API's turn
  // them on (the recall key switch, the car roof's inspection switch, their buttons).
  out.inspection = out.inspection || api.inspection;
  out.recall = out.recall || api.recall;
  out.button_up = out.button_up || api.button_up;
  out.button_down = out.button_down || api.button_down;
  // The door zone's bridge is the I/O board's safety circuit, which the simulated machine does
  // not model, as it does not model the shaft's zones.
  out.door_zone_bridge = api.door_zone_bridge;
  out.level_zone = api.level_zone;
  out.relevel_up = api.relevel_up;
  out.relevel_down = api.relevel_down;
  out.end_zone_top = out.end_zone_top || api.end_zone_top;
  out.end_zone_bottom = out.end_zone_bottom || api.end_zone_bottom;
  out.decel_up = api.decel_up;
  out.decel_down = api.decel_down;
  return out;
}

can::EncoderFormat encoder_format(const config::Config& c) {
  can::EncoderFormat f;
  f.id = static_cast<std::uint32_t>(c.position.can_id);
  f.offset = static_cast<std::uint8_t>(c.position.can_offset);
  f.length = static_cast<std::uint8_t>(c.position.can_length);
  f.big_endian = c.position.can_big_endian;
  f.is_signed = c.position.can_signed;
  f.um_per_count = c.position.can_um_per_count;
  f.offset_mm = c.position.can_offset_mm;
  return f;
}

std::string snake(std::string_view text) {
  std::string out(text);
  for (char& c : out) {
    if (c == ' ' || c == '/' || c == '-') c = '_';
  }
  return out;
}

namespace {

sim::SimIoConfig board_config(const config::Config& c) {
  sim::SimIoConfig out;
  if (!c.floors.empty()) {
    out.shaft_bottom_mm = static_cast<double>(c.floors.front().level_mm);
    out.shaft_top_mm = static_cast<double>(c.floors.back().level_mm);
  }
  return out;
}

std::string action_name(const api::SimRequest& request) {
  return std::string(request.name);
}

}  // namespace

lift::Inputs SimulatorThread::inputs(MonoTime now) {
  std::lock_guard<std::mutex> lock(mutex_);
  return board_.io().inputs(now);
}

void SimulatorThread::start_thread(std::function<void()> loop) {
  stop_.store(false);
  thread_ = std::thread(std::move(loop));
}

bool SimulatorThread::join_thread() {
  if (!thread_.joinable()) return false;
  stop_.store(true);
  thread_.join();
  return true;
}

void SimulatorThread::car_moved(double position_mm, bool moving, MonoTime now) {
  encoder_.set(position_mm);
  board_.io().set_car(moving, position_mm, now);
}

SimulatedBoard::SimulatedBoard(const config::Config& config, MonoTime now)
    : io_(board_config(config), now) {}

bool SimulatedBoard::apply(const api::SimRequest& request, MonoTime now) {
  using api::SimAction;
  if (!request.shared) return false;
  switch (*request.shared) {
    case SimAction::SafetyChainOpen:
      chain_open_ = request.on;
      io_.set_safety_chain_open(request.on);
      break;
    case SimAction::DoorReversal:
      io_.inject_door_reversal(now);
      break;
    case SimAction::OpenDoors:
      io_.open_doors(now);
      break;
    case SimAction::CloseDoors:
      io_.close_doors(now);
      break;
    case SimAction::ObstructDoors:
      obstructed_ = request.on;
      io_.set_door_obstructed(request.on, now);
      break;
    default:
      return false;
  }
  io_.advance(now);
  return true;
}

void SimulatedBoard::add_state(nlohmann::json& out) const {
  out["safety_chain_open"] = chain_open_;
  out["doors"] = sim::to_string(io_.door_state());
  out["door_obstructed"] = obstructed_;
}

void journal_sim_action(const api::SimRequest& request) {
  log::event(log::Level::info, "sim", "sim_injected", {{"action", action_name(request)}},
             "simulated lift: " + action_name(request));
}

namespace {
// The buffer and the shaft's top lie this far beyond the terminal levels: room for the learning
// travel's approach (lift::kLearnApproachMm, 300 mm) and the run-out of a stop there.
constexpr double kShaftEndBeyondLevelMm = 500.0;
}  // namespace

double shaft_bottom_mm(const config::Config& c) {
  double lowest = c.floors.empty() ? 0.0 : static_cast<double>(c.floors.front().level_mm);
  if (!c.sim.shaft_levels_mm.empty()) {
    lowest = std::min(lowest, static_cast<double>(c.sim.shaft_levels_mm.front()));
  }
  return lowest - kShaftEndBeyondLevelMm;
}

double shaft_top_mm(const config::Config& c) {
  double highest = c.floors.empty() ? 0.0 : static_cast<double>(c.floors.back().level_mm);
  if (!c.sim.shaft_levels_mm.empty()) {
    highest = std::max(highest, static_cast<double>(c.sim.shaft_levels_mm.back()));
  }
  return highest + kShaftEndBeyondLevelMm;
}

sim::SimulatedShaft simulated_shaft(const config::Config& c) {
  std::vector<std::int64_t> levels = c.sim.shaft_levels_mm;
  if (levels.empty()) {
    for (const auto& floor : c.floors) levels.push_back(floor.level_mm);
  }
  return sim::SimulatedShaft(levels, c.sim.level_zone_mm);
}

}  // namespace liftd::daemon
