#include "dcp/host/lift_app.hpp"

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <stdexcept>

#include <cstring>
#include "api/commands.hpp"
#include "common/mono_time.hpp"
#include "common/version.hpp"
#include "dcp/charset.hpp"
#include "dcp/host/simulated_lift.hpp"
#include "dcp/messages.hpp"
#include "host/learn_report.hpp"
#include "host/lift_common.hpp"
#include "host/lift_core.hpp"
#include "log/log.hpp"

namespace liftd::daemon {
namespace {

using namespace std::chrono_literals;

// After a forced service stop: time for one DCP 7.3 supervision window (10 x 15 ms) of B0-off
// frames.
constexpr auto kDcpShutdownGrace = std::chrono::milliseconds(500);

dcp::Code2 code2(const std::string& s) {
  return {s.at(0), s.at(1)};
}

}  // namespace

control::ControllerConfig dcp_controller_config(const config::Config& c) {
  control::ControllerConfig out;
  out.link.data_info_type = *dcp::data_info_type_from_char(c.dcp.data_info_type);
  out.link.extended_position = c.dcp.extended_position;
  out.link.fault_after_bad_frames = c.dcp.link_fault_frames;
  out.link.recover_after_good_frames = c.dcp.link_recover_frames;
  out.link.maker = code2(c.dcp.manufacturer);
  out.link.language = code2(c.dcp.language);
  out.link.request_timeout = std::chrono::milliseconds(c.dcp.request_timeout_ms);
  {
    // I0 carries our version as four digits (DCP 5.12.2.1): 0.1.0 -> 00.10.
    int major = 0, minor = 0, patch = 0;
    std::sscanf(std::string(kVersion).c_str(), "%d.%d.%d", &major, &minor, &patch);
    out.link.version = static_cast<dcp::VersionCenti>(major * 100 + minor * 10 + patch);
  }
  out.travel.data_info_type = out.link.data_info_type;
  out.travel.use_i7 = c.travel.use_start_parameters;
  out.travel.fast_start_timeout_ms = static_cast<std::uint32_t>(c.travel.fast_start_timeout_ms);
  out.travel.level_tolerance_mm = static_cast<std::uint32_t>(c.travel.level_tolerance_mm);
  out.travel.relevel_threshold_mm = static_cast<std::uint32_t>(c.travel.relevel_threshold_mm);
  out.travel.auto_relevel = c.travel.relevel_with_doors != config::RelevelDoors::never;
  out.travel.relevel_doors_open = c.travel.relevel_with_doors == config::RelevelDoors::open ||
                                  c.travel.relevel_with_doors == config::RelevelDoors::both;
  out.travel.relevel_electric_stop = c.travel.relevel_electric_stop;
  out.travel.dcp3_speed_count = c.travel.dcp3_speed_count;
  out.travel.dcp3_stop_lead_mm = static_cast<std::uint32_t>(c.travel.dcp3_stop_lead_mm);
  out.travel.dcp3_reference = c.travel.dcp3_reference == config::Dcp3Reference::shaft_signals
                                  ? travel::Dcp3Reference::ShaftSignals
                                  : travel::Dcp3Reference::Position;
  for (const auto& [name, mm] : c.travel.dcp3_decel_distance_mm) {
    if (auto speed = dcp::speed_from_string(name)) {
      out.travel.dcp3_decel_distance_mm[travel::speed_index(*speed)] =
          static_cast<std::uint32_t>(mm);
    }
  }
  out.lift.level_tolerance_mm = static_cast<std::uint32_t>(c.travel.level_tolerance_mm);
  for (const auto& f : c.floors) out.floors_mm.push_back(f.level_mm);
  out.inputs_timeout = std::chrono::milliseconds(c.inputs.timeout_ms);
  out.inspection_hold = std::chrono::milliseconds(c.travel.inspection_hold_ms);
  return out;
}

namespace {

rt::CycleConfig cycle_config(const config::Config& c, const std::string& device) {
  rt::CycleConfig out;
  out.device_path = device;
  out.serial.baud = 38400;  // DCP 7.1: 38400 baud, 8 data bits, no parity, 1 stop bit
  out.serial.data_bits = 8;
  out.serial.parity = io::Parity::None;
  out.serial.stop_bits = 1;
  out.serial.rs485 = c.drive.rs485 == config::Rs485Mode::required ? io::Rs485Mode::Required
                     : c.drive.rs485 == config::Rs485Mode::off    ? io::Rs485Mode::Off
                                                                  : io::Rs485Mode::Auto;
  out.thread.priority = c.rt.priority;
  out.thread.cpu = c.rt.cpu;
  out.thread.lock_memory = c.rt.lock_memory;
  out.recorder_span = std::chrono::seconds(c.rt.flight_recorder_s);
  out.send_window = std::chrono::microseconds(c.rt.send_window_us);
  return out;
}

log::Level level_for(const control::ControllerEvent& event) {
  if (event.kind == control::ControllerEvent::Kind::Link &&
      event.link.kind == dcp::LinkEventKind::HandshakeProblem) {
    return log::Level::warn;
  }
  return event.kind == control::ControllerEvent::Kind::DriveError ? log::Level::warn
                                                                  : log::Level::info;
}

}  // namespace

LiftApp::LiftApp(Host& daemon, const config::Config& config, bool simulate)
    : daemon_(daemon),
      config_(config),
      simulate_(simulate),
      socket_path_(config.api.socket),
      runtime_dir_(default_runtime_dir(config)),
      wake_(daemon.io(), kFallbackPoll),
      publisher_(config.api.state_rate_hz),
      overruns_(rt::CycleConfig{}.period),
      wind_down_(
          daemon, [this](bool force) { return backend_->send_shutdown(force); }, kShutdownDeadline,
          kDcpShutdownGrace) {
  std::string device = config.drive.device;
  if (simulate_) {
    sim_ = std::make_unique<SimulatedLift>(config);
    device = sim_->device_path();
    position_ = &sim_->position();
  } else {
    position_feed_ = std::make_unique<control::PositionFeed>(
        std::chrono::milliseconds(config.inputs.timeout_ms));
    position_ = position_feed_.get();
    if (config.position.source == config::PositionSource::can) {
      // An absolute encoder on CAN: a CAN runner of its own feeds it (lib/rt/encoder_tap.hpp).
      encoder_ = std::make_unique<can::CanEncoder>(
          encoder_format(config), std::chrono::milliseconds(config.position.can_timeout_ms));
      encoder_tap_ = std::make_unique<rt::EncoderTap>(*encoder_, nullptr);
      rt::CanRunnerConfig rc;
      rc.endpoint = config.can.interface;
      rc.ids = {encoder_->format().id};
      rc.rt.priority = std::max(1, config.rt.priority - 1);  // below the DCP cycle
      rc.rt.cpu = config.rt.cpu;
      rc.rt.lock_memory = config.rt.lock_memory;
      rc.rt.name = "liftd-encoder";  // as ps -L and chrt -p show it
      encoder_runner_ = std::make_unique<rt::CanRunner>(rc, *encoder_tap_);
      position_ = encoder_.get();
    }
  }
  control::ControllerConfig controller_config = dcp_controller_config(config);
  if (sim_) controller_config.level_zone_source = &sim_->level_zone();
  controller_ = std::make_unique<control::DcpController>(controller_config, *position_);
  runner_ = std::make_unique<rt::CycleRunner>(cycle_config(config, device), *controller_);
  runner_->set_notify_fd(wake_.fd());
  backend_ = std::make_unique<LiftBackend>(
      config, daemon.config_schema(), *controller_, *runner_,
      config.position.source == config::PositionSource::api ? position_feed_.get() : nullptr,
      runtime_dir_, sim_.get());

  server_ = std::make_unique<api::Server>(daemon.io(), *backend_, api_server_config(config),
                                          api_log_sink());
  daemon.add_drive_commands(server_->dispatcher(), *backend_);
  backend_->set_learn_listener(
      [this](const nlohmann::json& result) { report_learn(*server_, result); });

  if (sim_) {
    daemon.add_component({"sim", [this] { return sim_->start(); }, [this] { sim_->stop(); }});
  }
  if (encoder_runner_) {
    daemon.add_component({"can_encoder",
                          [this] {
                            if (const int error = encoder_runner_->start(); error != 0) {
                              log::event(log::Level::error, "position", "can_start_failed", {},
                                         std::string("cannot start the CAN encoder thread: ") +
                                             std::strerror(error));
                              return false;
                            }
                            return true;
                          },
                          [this] { encoder_runner_->stop(); }});
  }
  daemon.add_component({"dcp", [this] { return start_cycle(); }, [this] { stop_cycle(); },
                        [this](std::function<void()> done) { wind_down(std::move(done)); }});
  daemon.add_component({"api", [this] { return start_api(); }, [this] { stop_api(); }});
  daemon.set_progress_probe([this] {
    const std::uint64_t p = runner_->progress();
    const bool advanced = p != last_progress_;
    last_progress_ = p;
    return advanced;
  });
  daemon.set_config_applier([this](const config::Config& next) { return apply_config(next); });
  daemon.set_dump_handler([this] { dump_flight_recorder("SIGUSR1"); });
  daemon.set_running_status(simulate_ ? "simulated lift running; API on " + socket_path_
                                      : "drive link starting on " + device);
}

LiftApp::~LiftApp() {
  stop_api();
  stop_cycle();
  if (sim_) sim_->stop();
}

bool LiftApp::start_cycle() {
  const int error = runner_->start();
  if (error != 0) {
    log::event(log::Level::error, "dcp", "cycle_start_failed", {{"errno", std::to_string(error)}},
               std::string("cannot start the cycle thread: ") + std::strerror(error));
    return false;
  }
  if (config_.rt.require_realtime && !runner_->thread_status().realtime) {
    // main() checked this before starting; a refusal only now is still no cycle to run a car on.
    log::event(log::Level::error, "rt", "realtime_refused", {},
               "rt.require_realtime is true but the cycle thread runs without real time: " +
                   runner_->thread_status().describe());
    runner_->stop();
    return false;
  }
  for (const std::string& line : {runner_->thread_status().describe()}) {
    if (!line.empty()) log::event(log::Level::warn, "rt", "rt_degraded", {}, line);
  }
  log::event(log::Level::info, "dcp", "cycle_started",
             {{"device", runner_->config().device_path},
              {"realtime", runner_->thread_status().realtime ? "yes" : "no"}},
             "DCP cycle running every 15 ms on " + runner_->config().device_path);
  running_ = true;
  backend_->send_clock(std::chrono::system_clock::now());
  wake_.start([this] { poll(); });
  return true;
}

void LiftApp::wind_down(std::function<void()> done) {
  if (!running_) {
    done();
    return;
  }
  // The controller stops the travel the way `stop` does and refuses new ones; it reports
  // "quiesced" once the car is at rest and a DCP 7.3 supervision window of frames without B0 has
  // gone out.
  const control::ControllerSnapshot s = controller_->snapshot();
  const bool moving = s.travel_kind != travel::TravelKind::None ||
                      (s.status_byte && (*s.status_byte & dcp::status_bit::kTravelActive) != 0);
  wind_down_.start(std::move(done), moving, s.target_floor, mono_now());
}

void LiftApp::check_wind_down(MonoTime now) {
  const control::ControllerSnapshot s = controller_->snapshot();
  wind_down_.check({s.shutting_down, s.quiesced, s.floor, s.position_mm}, now);
}

void LiftApp::stop_cycle() {
  if (!running_) return;
  running_ = false;
  wake_.stop();
  runner_->stop();
}

bool LiftApp::start_api() {
  try {
    server_->start();
  } catch (const std::exception& e) {
    log::event(log::Level::error, "api", "api_start_failed", {{"socket", socket_path_}}, e.what());
    return false;
  }
  log::event(log::Level::info, "api", "api_listening", {{"socket", socket_path_}},
             "API listening on " + socket_path_);
  return true;
}

void LiftApp::stop_api() {
  if (server_) server_->stop();
}

void LiftApp::poll() {
  const MonoTime now = mono_now();
  if (sim_ && now - last_sim_inputs_ >= kSimInputsPeriod) {
    last_sim_inputs_ = now;
    backend_->simulated_inputs(sim_->inputs(now));
    sim_->log_events();
  }
  if (now - last_clock_ >= 1s) {  // DCP 5.12.5: I3 after I0 and at day change
    last_clock_ = now;
    backend_->send_clock(std::chrono::system_clock::now());
  }
  backend_->poll(now);
  control::ControllerEvent event;
  while (controller_->poll_event(event)) handle_event(event);
  log_cycle_events();
  publish_state_if_changed(now);
  check_wind_down(now);
}

void LiftApp::log_cycle_events() {
  rt::CycleEvent e;
  while (runner_->poll_event(e)) {
    if (e.kind == rt::CycleEventKind::SkipRunStarted ||
        e.kind == rt::CycleEventKind::SkipRunEnded) {
      // Rare and meaningful: WARN only when skips threaten the link supervision.
      if (auto line = overruns_.on_event(e)) {
        log::event(line->warn ? log::Level::warn : log::Level::info, "rt", line->event,
                   {{"skipped", std::to_string(e.count)},
                    {"lateness_us", std::to_string(e.lateness.count() / 1000)}},
                   line->text);
      }
      continue;
    }
    journal_port_event(e);
  }
}

void LiftApp::handle_event(const control::ControllerEvent& event) {
  using Kind = control::ControllerEvent::Kind;
  nlohmann::json data;
  std::string name;
  std::string text;
  std::string log_event;
  log::Fields fields;
  std::optional<log::Catalogued> catalogued;  // gives the record its journal MESSAGE_ID
  switch (event.kind) {
    case Kind::Link: {
      name = "link";
      log_event = "link_" + snake(dcp::to_string(event.link.kind));
      text = std::string(dcp::to_string(event.link.kind)) + ": " + std::string(event.link.detail);
      if (event.link.kind == dcp::LinkEventKind::StateChanged) {
        text = "link " + std::string(dcp::to_string(event.link.from)) + " -> " +
               std::string(dcp::to_string(event.link.state)) + ": " +
               std::string(event.link.detail);
        daemon_.report_status("drive link " + std::string(dcp::to_string(event.link.state)));
      }
      data = {{"kind", std::string(dcp::to_string(event.link.kind))},
              {"state", std::string(dcp::to_string(event.link.state))},
              {"detail", std::string(event.link.detail)}};
      break;
    }
    case Kind::Travel: {
      // As every lift reports its travels (host/lift_core); a DCP travel also tells its
      // target changes, fast start and drive faults (DCP 4.1, 12, 9.1.6).
      const travel::Event& t = event.travel;
      if (t.type == travel::Event::Type::Finished || t.type == travel::Event::Type::Aborted) {
        backend_->record_travel_end(event.at, t.type == travel::Event::Type::Aborted, t.cause);
      }
      report_travel(*server_, travel::to_string(t.type), travel::to_string(t.kind), t.cause,
                    t.type == travel::Event::Type::Aborted, t.target_mm, t.position_mm);
      return;
    }
    case Kind::DriveError: {
      name = "drive_error";
      log_event = "drive_error";
      catalogued = log::Catalogued::DriveErrorLog;
      text = "drive error: " + dcp::to_utf8(event.drive_error.chars());
      fields.push_back({"drive_text", dcp::to_utf8(event.drive_error.chars())});
      data = {{"text", dcp::to_utf8(event.drive_error.chars())},
              {"at", api::format_utc(backend_->wall_time(event.at))}};
      break;
    }
    case Kind::FaultRaised:
    case Kind::FaultCleared: {
      const bool active = event.kind == Kind::FaultRaised;
      report_fault(*server_, event.fault, control::fault_text(event.fault), active);
      if (active && event.fault == control::FaultCode::LinkFault) {
        dump_flight_recorder("link fault");
      }
      return;
    }
    case Kind::CallServed:
      report_call_served(*server_, event.floor);
      return;
  }
  // What only a DCP drive tells: its link and its error texts (DCP 5.11).
  log::event(level_for(event), "dcp", log_event, fields, text, catalogued);
  server_->publish(name, data);
}

void LiftApp::publish_state_if_changed(MonoTime now) {
  const control::ControllerSnapshot s = controller_->snapshot();
  if (s.display_version != last_display_version_) {
    last_display_version_ = s.display_version;
    server_->publish("display", to_json(backend_->display()));
  }
  publisher_.publish(*server_, backend_->status(), now);
}

std::string LiftApp::apply_config(const config::Config& next) {
  const api::ServerConfig server = api_reload_config(next);
  try {
    server_->reconfigure(server);
  } catch (const std::exception& e) {
    return e.what();
  }
  return {};
}

void LiftApp::dump_flight_recorder(std::string_view why) {
  (void)backend_->write_flight_recorder(why);
}

}  // namespace liftd::daemon
