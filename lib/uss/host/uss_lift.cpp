#include "uss/host/uss_lift.hpp"

#include <pthread.h>
#include <sched.h>
#include <sys/epoll.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <optional>
#include <stdexcept>
#include <utility>

#include "api/commands.hpp"
#include "log/log.hpp"
#include "uss/config/section.hpp"
#include "uss/host/sim_actions.hpp"
#include "uss/host/uss_bus_slaves.hpp"
#include "uss/registry_entry.hpp"
#include "uss/timing.hpp"

namespace liftd::daemon {

uss::MasterConfig uss_master_config(const config::Config& c) {
  uss::MasterConfig out;
  out.baud = static_cast<std::uint32_t>(uss_section(c).baud);
  for (const auto& s : bus_slaves(c)) {
    uss::SlaveConfig slave;
    slave.address = static_cast<std::uint8_t>(s.address);
    slave.pkw = pkw_length_of(s.pkw);
    slave.pzd_words = static_cast<std::uint8_t>(s.pzd_words);
    out.slaves.push_back(slave);
  }
  // USS A 2.1: an empty list polls every slave once per pass, the drive first.
  if (uss_section(c).polling_list.empty()) {
    for (const auto& s : out.slaves) out.polling_list.push_back(s.address);
  } else {
    for (int a : uss_section(c).polling_list)
      out.polling_list.push_back(static_cast<std::uint8_t>(a));
  }
  out.reply_delay = std::chrono::milliseconds(uss_section(c).reply_delay_ms);
  if (uss_section(c).cycle_time_ms > 0)
    out.cycle_time = std::chrono::milliseconds(uss_section(c).cycle_time_ms);
  out.pkw_repeat_limit = static_cast<std::uint32_t>(uss_section(c).pkw_repeat_limit);
  out.mirror_at_start = uss_section(c).mirror_at_start;
  return out;
}

uss::UssControllerConfig uss_controller_config(const config::Config& c) {
  uss::UssControllerConfig out;
  out.drive_address = static_cast<std::uint8_t>(uss_section(c).drive_address);
  out.drive_pzd_words = static_cast<std::uint8_t>(uss_section(c).drive_pzd_words);
  // The controller thinks in percent of the drive's full scale (USS C 5.2.2: 0x4000 = 100 %).
  out.normalisation.raw_full_scale = uss_section(c).full_scale_raw;
  out.normalisation.full_scale = 100.0;
  uss::LiftTravelConfig& t = out.travel;
  t.speed_percent.fill(0.0);
  for (const auto& [name, setpoint] : uss_section(c).speeds) {
    if (const auto speed = uss::parse_speed(name)) {
      t.speed_percent[uss::speed_index(*speed)] = setpoint * 100.0 / uss_section(c).full_scale;
    }
  }
  t.slowdown_mm.fill(0);
  for (const auto& [name, mm] : c.travel.dcp3_decel_distance_mm) {
    if (const auto speed = uss::parse_speed(name)) {
      t.slowdown_mm[uss::speed_index(*speed)] = static_cast<std::uint32_t>(mm);
    }
  }
  t.reference = c.travel.dcp3_reference == config::Dcp3Reference::shaft_signals
                    ? uss::Reference::ShaftSignals
                    : uss::Reference::Position;
  t.stop_lead_mm = static_cast<std::uint32_t>(c.travel.dcp3_stop_lead_mm);
  t.level_tolerance_mm = static_cast<std::uint32_t>(c.travel.level_tolerance_mm);
  t.relevel_doors_open = c.travel.relevel_with_doors == config::RelevelDoors::open ||
                         c.travel.relevel_with_doors == config::RelevelDoors::both;
  t.profile.switch_on_timeout_ms = static_cast<std::uint32_t>(uss_section(c).profile_timeout_ms);
  out.link_fault_replies = static_cast<std::uint32_t>(uss_section(c).telegram_failures);
  out.lift = lift_config(c);
  for (const auto& f : c.floors) out.floors_mm.push_back(f.level_mm);
  out.inputs_timeout = std::chrono::milliseconds(c.inputs.timeout_ms);
  out.inspection_hold = std::chrono::milliseconds(c.travel.inspection_hold_ms);
  out.auto_relevel = c.travel.relevel_with_doors != config::RelevelDoors::never;
  out.relevel_threshold_mm = static_cast<std::uint32_t>(c.travel.relevel_threshold_mm);
  if (const auto why = uss::validate(out.travel)) {
    throw std::invalid_argument("uss: " + std::string(*why));
  }
  return out;
}

TravelBitNames UssDrive::travel_bit_names() {
  TravelBitNames names;
  for (const std::string_view name : uss::kControlWordBitNames) names.command.emplace_back(name);
  for (const std::string_view name : uss::kStatusWordBitNames) names.status.emplace_back(name);
  return names;
}

UssLift::UssLift(Host& daemon, const config::Config& config, bool simulate)
    : ControllerLift(daemon, config, simulate, {"actual"}) {
  uss::UssRunnerConfig rc;
  rc.device_path = config.drive.device;
  rc.serial = uss::uss_serial_settings(static_cast<std::uint32_t>(uss_section(config).baud));
  rc.serial.rs485 = config.drive.rs485 == config::Rs485Mode::required ? io::Rs485Mode::Required
                    : config.drive.rs485 == config::Rs485Mode::off    ? io::Rs485Mode::Off
                                                                      : io::Rs485Mode::Auto;
  rc.echo = echo_mode(config.drive.echo);
  rc.thread.priority = config.rt.priority;
  rc.thread.cpu = config.rt.cpu;
  rc.thread.lock_memory = config.rt.lock_memory;
  rc.recorder_span = std::chrono::seconds(config.rt.flight_recorder_s);
  const PositionSource* position = nullptr;
  if (simulate_) {
    sim_ = std::make_unique<SimulatedUssBus>(config);
    rc.device_path = sim_->device_path();
    rc.serial.rs485 = io::Rs485Mode::Off;  // a pseudo-terminal has no RS485 mode
    position = &sim_->position();
  } else {
    position = &make_position_feed();
  }
  master_ = std::make_unique<uss::Master>(uss_master_config(config));
  uss::UssControllerConfig cc = uss_controller_config(config);
  if (sim_) cc.level_zone_source = &sim_->level_zone();
  controller_ = std::make_unique<uss::UssController>(cc, *master_, *position, mono_now());
  runner_ = std::make_unique<uss::UssRunner>(rc, *master_, *controller_);
  register_parts(std::make_unique<UssBackend>(config, daemon.config_schema(), *controller_,
                                              *runner_, *master_, api_position_feed(), sim_.get()),
                 "USS lift", "USS master", config.drive.device);
}

UssLift::~UssLift() {
  shut_down();
}

void UssLift::before_start() {
  prepare_serial_device(runner_->config().device_path);
}

void UssLift::journal_started() {
  // The cycle the polling list should take by the spec's timing rules (USS A 5.1.1, A 6).
  const auto expected =
      std::chrono::duration_cast<std::chrono::microseconds>(master_->expected_cycle_time()).count();
  log::event(log::Level::info, "uss", "uss_started",
             {{"device", runner_->config().device_path},
              {"baud", std::to_string(uss_section(config_).baud)},
              {"expected_cycle_us", std::to_string(expected)}},
             "USS master running on " + runner_->config().device_path + " at " +
                 std::to_string(uss_section(config_).baud) + " baud 8E1, " +
                 std::to_string(master_->config().polling_list.size()) +
                 " telegram(s) per pass: expected cycle time " + std::to_string(expected) +
                 " us (start pauses, telegrams, reply delays)");
}

void UssLift::handle_event(const uss::ControllerEvent& event) {
  using Kind = uss::ControllerEvent::Kind;
  switch (event.kind) {
    case Kind::Link: {
      const bool up = event.link.responding;
      const std::string address = std::to_string(event.link.address);
      const bool drive = event.link.address == uss_section(config_).drive_address;
      const std::string text =
          up ? "USS slave " + address + " answers" + (drive ? " (the drive)" : "")
             : "USS slave " + address + " does not send (no good reply in time, USS A 5.2.1.1)" +
                   (drive ? ": the drive; no travel" : "");
      // A slave that does not send is the catalog's uss_slave_fault. A flapping link journals
      // a few lines, then one count per 10 s (after_events); watchers get every change.
      last_link_line_ = text;
      if (link_lines_.admit(1, event.at)) {
        log::event(up ? log::Level::info : log::Level::warn, "uss",
                   up ? "link_state_changed" : "uss_slave_fault",
                   {{"state", up ? "up" : "fault"}, {"address", address}}, text,
                   up ? std::nullopt : std::optional(log::Catalogued::UssSlaveFault));
      }
      if (drive) daemon_.report_status(std::string("USS drive link ") + (up ? "up" : "fault"));
      server_->publish("link", {{"kind", "state changed"},
                                {"state", up ? "up" : "fault"},
                                {"address", event.link.address},
                                {"detail", text}});
      break;
    }
    case Kind::Port:
      log::event(event.port_up ? log::Level::info : log::Level::error, "uss",
                 event.port_up ? "port_opened" : "port_lost",
                 {{"device", runner_->config().device_path}},
                 "USS port " + runner_->config().device_path +
                     (event.port_up ? " open" : " lost: no travel; reopening"),
                 event.port_up ? std::nullopt : std::optional(log::Catalogued::SerialPortLost));
      break;
    case Kind::Spontaneous: {
      const uss::Pkw& p = event.spontaneous.report;
      const std::string text = "USS slave " + std::to_string(event.spontaneous.address) +
                               " reports parameter " + std::to_string(p.pnu) + " changed (" +
                               std::string(uss::reply_name(p.id)) + ")";
      log::event(
          log::Level::info, "uss", "spontaneous_report",
          {{"address", std::to_string(event.spontaneous.address)}, {"pnu", std::to_string(p.pnu)}},
          text);
      nlohmann::json words = nlohmann::json::array();
      for (std::uint16_t w : p.pwe_words()) words.push_back(w);
      server_->publish("parameter_changed", {{"address", event.spontaneous.address},
                                             {"pnu", p.pnu},
                                             {"index", uss::ind_element(p.ind)},
                                             {"reply", std::string(uss::reply_name(p.id))},
                                             {"words", std::move(words)}});
      break;
    }
    case Kind::Mirror:
      log::event(event.mirror.ok ? log::Level::info : log::Level::warn, "uss", "mirror_test",
                 {{"address", std::to_string(event.mirror.address)},
                  {"ok", event.mirror.ok ? "true" : "false"}},
                 "mirror telegram to USS slave " + std::to_string(event.mirror.address) +
                     (event.mirror.ok ? " came back unchanged (USS A 5.3)"
                                      : " did not come back unchanged in time (USS A 5.3)"));
      break;
    case Kind::DriveState: {
      last_drive_state_ = event.drive_state;
      if (!drive_state_lines_.admit(1, event.at)) break;
      // A drive that reports a fault is the catalog's uss_slave_fault.
      const bool fault = event.drive_state == uss::ProfileState::Fault;
      // Local control (status word bit 9 = 0): whatever its state, the drive takes no travel
      // (status drive.state not_ready).
      log::event(fault ? log::Level::warn : log::Level::info, "uss",
                 fault ? "uss_slave_fault" : "drive_state",
                 {{"state", std::string(uss::to_string(event.drive_state))},
                  {"control", event.plc_control ? "plc" : "local"},
                  {"address", std::to_string(uss_section(config_).drive_address)},
                  {"status_word", std::to_string(event.zsw)}},
                 "USS drive: " + std::string(uss::to_string(event.drive_state)) +
                     (event.plc_control ? ""
                                        : ", in local control (status word bit 9 = 0): no "
                                          "travel starts") +
                     " (status word " + std::to_string(event.zsw) + ")",
                 fault ? std::optional(log::Catalogued::UssSlaveFault) : std::nullopt);
      break;
    }
    default:  // every lift's events: report_lift_event()
      break;
  }
}

void UssLift::after_events(MonoTime now) {
  if (const auto n = link_lines_.suppressed(now)) {
    log::event(
        log::Level::warn, "uss", "link_flapping", {{"changes", std::to_string(*n)}},
        "USS slave links changed " + std::to_string(*n) +
            " more times in the last 10 s without a line each; the last: " + last_link_line_);
  }
  if (const auto n = drive_state_lines_.suppressed(now)) {
    log::event(log::Level::warn, "uss", "drive_state_flapping",
               {{"changes", std::to_string(*n)},
                {"state", std::string(uss::to_string(last_drive_state_))}},
               "USS drive state changed " + std::to_string(*n) +
                   " more times in the last 10 s without a line each; now: " +
                   std::string(uss::to_string(last_drive_state_)));
  }
}

}  // namespace liftd::daemon

// The registry makes this kind's lift through this instance (lib/host/registry_entry.hpp).
template std::unique_ptr<liftd::daemon::LiftRunner> liftd::host::make_lift<liftd::daemon::UssLift>(
    liftd::daemon::Host&, const liftd::config::Config&, bool);
