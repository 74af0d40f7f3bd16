#include "dcp/host/dcp_lift.hpp"

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <optional>
#include <stdexcept>

#include "common/version.hpp"
#include "dcp/charset.hpp"
#include "dcp/config/section.hpp"
#include "dcp/messages.hpp"
#include "dcp/registry_entry.hpp"
#include "host/lift_common.hpp"
#include "host/lift_core.hpp"
#include "log/log.hpp"

namespace liftd::daemon {
namespace {

using namespace std::chrono_literals;

dcp::Code2 code2(const std::string& s) {
  return {s.at(0), s.at(1)};
}

}  // namespace

control::ControllerConfig dcp_controller_config(const config::Config& c) {
  control::ControllerConfig out;
  out.link.data_info_type = *dcp::data_info_type_from_char(dcp_section(c).data_info_type);
  out.link.extended_position = dcp_section(c).extended_position;
  out.link.fault_after_bad_frames = dcp_section(c).link_fault_frames;
  out.link.recover_after_good_frames = dcp_section(c).link_recover_frames;
  out.link.maker = code2(dcp_section(c).manufacturer);
  out.link.language = code2(dcp_section(c).language);
  out.link.request_timeout = std::chrono::milliseconds(dcp_section(c).request_timeout_ms);
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
  out.lift = lift_config(c);
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
  out.echo = echo_mode(c.drive.echo);
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

DcpLift::DcpLift(Host& daemon, const config::Config& config, bool simulate)
    : ControllerLift(daemon, config, simulate), overruns_(rt::CycleConfig{}.period) {
  std::string device = config.drive.device;
  const PositionSource* position = nullptr;
  if (simulate_) {
    sim_ = std::make_unique<SimulatedLift>(config);
    device = sim_->device_path();
    position = &sim_->position();
  } else if (config.position.source == config::PositionSource::can) {
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
    position = encoder_.get();
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
  } else {
    position = &make_position_feed();
  }
  control::ControllerConfig controller_config = dcp_controller_config(config);
  if (sim_) controller_config.level_zone_source = &sim_->level_zone();
  controller_ = std::make_unique<control::DcpController>(controller_config, *position);
  runner_ = std::make_unique<rt::CycleRunner>(cycle_config(config, device), *controller_);
  register_parts(std::make_unique<DcpBackend>(config, daemon.config_schema(), *controller_,
                                              *runner_, api_position_feed(), sim_.get()),
                 "lift", "drive link", device);
}

DcpLift::~DcpLift() {
  shut_down();
  if (encoder_runner_) encoder_runner_->stop();
}

void DcpLift::before_start() {
  prepare_serial_device(runner_->config().device_path);
}

void DcpLift::journal_started() {
  log::event(log::Level::info, "dcp", "cycle_started",
             {{"device", runner_->config().device_path},
              {"realtime", runner_->thread_status().realtime ? "yes" : "no"}},
             "DCP cycle running every 15 ms on " + runner_->config().device_path);
  last_clock_ = mono_now();
  dcp_backend().send_clock(std::chrono::system_clock::now());
}

void DcpLift::after_events(MonoTime now) {
  if (now - last_clock_ >= 1s) {  // DCP 5.12.5: I3 after I0 and at day change
    last_clock_ = now;
    dcp_backend().send_clock(std::chrono::system_clock::now());
  }
  const control::ControllerSnapshot s = controller_->snapshot();
  if (s.display_version != last_display_version_) {
    last_display_version_ = s.display_version;
    server_->publish("display", to_json(dcp_backend().display()));
  }
}

void DcpLift::handle_runner_event(const rt::CycleEvent& e) {
  if (e.kind != rt::CycleEventKind::SkipRunStarted && e.kind != rt::CycleEventKind::SkipRunEnded) {
    journal_port_event(e);
    return;
  }
  // Rare and meaningful: WARN only when skips threaten the link supervision.
  if (auto line = overruns_.on_event(e)) {
    log::event(line->warn ? log::Level::warn : log::Level::info, "rt", line->event,
               {{"skipped", std::to_string(e.count)},
                {"lateness_us", std::to_string(e.lateness.count() / 1000)}},
               line->text);
  }
}

void DcpLift::handle_event(const control::ControllerEvent& event) {
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
    default:  // every lift's events (with the DCP's own travel kinds): report_lift_event()
      return;
  }
  // What only a DCP drive tells: its link and its error texts (DCP 5.11).
  log::event(level_for(event), "dcp", log_event, fields, text, catalogued);
  server_->publish(name, data);
}

}  // namespace liftd::daemon

// The registry makes this kind's lift through this instance (lib/host/registry_entry.hpp).
template std::unique_ptr<liftd::daemon::LiftRunner> liftd::host::make_lift<liftd::daemon::DcpLift>(
    liftd::daemon::Host&, const liftd::config::Config&, bool);
