#include <array>
#include <ctime>
#include <span>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include "dcp/charset.hpp"
#include "dcp/config/section.hpp"
#include "dcp/host/dcp_lift.hpp"
#include "dcp/trace.hpp"

namespace liftd::daemon {
namespace {

using api::Result;

api::LinkState to_api(dcp::LinkState state) {
  switch (state) {
    case dcp::LinkState::Down:
      return api::LinkState::Down;
    case dcp::LinkState::Init:
    case dcp::LinkState::Resetting:
      return api::LinkState::Init;
    case dcp::LinkState::Up:
      return api::LinkState::Up;
    case dcp::LinkState::Fault:
      return api::LinkState::Fault;
  }
  return api::LinkState::Down;
}

}  // namespace

/// The spec's label with the name the status JSON (and the trace) gives the bit.
TravelBitNames DcpDrive::travel_bit_names() {
  return {{"B0_enable", "B1_travel", "B2_stop", "B3_speed", "B4_down", "B5_change", "B6_desired",
           "B7_reply_error"},
          {"S0_ready", "S1_travel_active", "S2_advance_warning", "S3_general_fault",
           "S4_below_levelling", "S5_accepted", "S6_brake_open", "S7_message_error"}};
}

namespace {

std::string utf8_row(const std::array<std::uint8_t, dcp::kDisplayColumns>& row) {
  return dcp::to_utf8(std::span<const std::uint8_t>(row.data(), row.size()));
}

}  // namespace

DcpBackend::DcpBackend(const config::Config& config, const config::Schema& schema,
                       control::DcpController& controller, rt::CycleRunner& runner,
                       PositionFeed* position_feed, SimulatedLift* sim)
    : ControllerBackend(
          config, schema, controller, runner, position_feed, sim, [&controller, &config] {
            // The decoded column of the protocol the drive speaks now (DCP 3.5).
            dcp::TraceOptions options;
            options.protocol = controller.snapshot().protocol.value_or(dcp::Protocol::Dcp4);
            options.data_info = *dcp::data_info_type_from_char(dcp_section(config).data_info_type);
            return dcp::trace_decoder(options);
          }) {}

// ---- reads ----

api::StatusSnapshot DcpBackend::status() {
  const control::ControllerSnapshot s = controller_.snapshot();
  api::StatusSnapshot out = neutral_status(s, to_api(s.link));
  const DcpStatusFacts facts{s.protocol,          s.status_byte,         s.extended,
                             s.handshake_problem, runner_.config().echo, runner_.echo_state()};
  if (!(facts == dcp_facts_)) {  // built again only when it changed: status is asked often
    dcp_facts_ = facts;
    dcp_details_ = dcp_status_json(facts);
  }
  out.details = dcp_details_;
  if (s.travel_kind == travel::TravelKind::None) out.travel_state = "idle";
  if (s.fast_start_armed) out.travel_state = "fast_start";  // DCP 12: held on an open brake
  out.brake_open = s.brake_open;
  out.contactors_on = s.contactors_on;
  out.last_travel_slip_mm = s.last_travel_slip_mm;
  return out;
}

api::StatsSnapshot DcpBackend::stats() {
  const rt::CycleStats cycle = runner_.stats();
  const dcp::LinkCounters link = controller_.snapshot().link_counters;
  api::StatsSnapshot out = neutral_stats(cycle.counters.frames_sent, cycle.counters.cycles);
  nlohmann::json& d = out.details;
  // The link (DCP 6, 7) and the 15 ms cycle's timing (DCP 7.2): docs/api.md `stats`.
  d["replies_good"] = link.good_replies;
  d["checksum_errors"] = link.bad_checksum;
  d["echo_collisions"] = cycle.counters.echo_collisions;
  d["missing_replies"] = link.missing_replies;
  d["repeats"] = link.s7_seen;
  d["link_losses"] = link.link_faults;
  d["b7_sent"] = link.b7_sent;
  d["channel_resets"] = link.channel_resets;
  d["decode_errors"] = link.decode_errors;
  d["request_timeouts"] = link.request_timeouts;
  d["longest_error_run"] = link.longest_error_run;
  d["late_sends"] = cycle.counters.late_sends;
  d["overruns"] = cycle.counters.overruns;
  d["skipped_cycles"] = cycle.counters.skipped_cycles;
  d["max_lateness_us"] = static_cast<std::uint64_t>(cycle.wake_lateness.max_us());
  d["lateness_p99_us"] = cycle.wake_lateness.percentile_us(0.99);
  d["reply_p99_us"] = cycle.reply_latency.percentile_us(0.99);
  d["reply_looks"] = cycle.counters.reply_looks;
  d["max_work_us"] = static_cast<std::uint64_t>(cycle.work_time.max_us());
  add_serial_device(d);
  return out;
}

std::vector<api::TraceEntry> DcpBackend::trace(std::size_t max_entries) {
  // Each master frame with the drive's reply in its cycle (DCP 7.2), a bad one included.
  static constexpr TracePairing kPairing{
      .we_answer = false,
      .ours = [](const rt::FrameRecord& r) { return r.length == dcp::kFrameSize; },
      .theirs =
          [](const rt::FrameRecord& r) {
            return r.length == dcp::kFrameSize &&
                   (r.flags & (rt::record_flag::kReply | rt::record_flag::kBad)) != 0;
          },
  };
  return trace_exchanges(runner_.recorder().copy(), max_entries, kPairing);
}

DisplaySnapshot DcpBackend::display() {
  const control::ControllerSnapshot s = controller_.snapshot();
  DisplaySnapshot out;
  for (const auto& row : s.display) out.lines.push_back(utf8_row(row));
  return out;
}

// ---- commands through the cycle ----

void DcpBackend::key(int button, api::Responder done) {
  // DCP 5.6.3: button n is bit 0x04 << (n - 1).
  const auto bits = static_cast<std::uint8_t>(0x04U << (button - 1));
  send(control::LinkCommand{dcp::KeypadPress{bits}}, std::move(done));
}

void DcpBackend::drive_reset(api::Responder done) {
  if (controller_.snapshot().travel_kind != travel::TravelKind::None) {
    done(Result::fail(api::ErrorCode::Busy, "a travel is running: no drive reset during travel"));
    return;
  }
  send(control::LinkCommand{dcp::SwitchRequest{dcp::SwitchFunction::Reset}}, std::move(done),
       [](const control::CommandReply& r) {
         // DCP 5.12.4.2: 'R' = reset follows within 1000 ms; '0' = the drive cannot reset.
         const auto* reply =
             r.drive_reply ? std::get_if<dcp::SwitchReply>(&*r.drive_reply) : nullptr;
         if (reply && reply->function != dcp::SwitchFunction::Reset) {
           return Result::fail(api::ErrorCode::Fault, "the drive answered that it cannot reset");
         }
         return Result::ok(
             {{"reset", true},
              {"detail", "reset within 1000 ms; link re-initialises about 5 s later"}});
       });
}

void DcpBackend::power(PowerSetting setting, api::Responder done) {
  dcp::PowerRequest request;
  request.supply = setting.emergency ? dcp::PowerSupply::Emergency : dcp::PowerSupply::Mains;
  request.saving = static_cast<dcp::EnergySaving>('0' + setting.saving);
  send(control::LinkCommand{request}, std::move(done), [](const control::CommandReply& r) {
    PowerSetting actual;
    if (const auto* reply =
            r.drive_reply ? std::get_if<dcp::PowerReply>(&*r.drive_reply) : nullptr) {
      actual.emergency = reply->supply == dcp::PowerSupply::Emergency;
      actual.saving = static_cast<int>(reply->saving) - '0';
    }
    return Result::ok(to_json(actual));
  });
}

void DcpBackend::load(int percent, api::Responder done) {
  send(control::LinkCommand{dcp::LoadRequest{static_cast<std::uint16_t>(percent)}},
       std::move(done));
}

void DcpBackend::send_clock(std::chrono::system_clock::time_point now) {
  const std::time_t t = std::chrono::system_clock::to_time_t(now);
  std::tm local{};
  localtime_r(&t, &local);
  dcp::CivilTime time;
  time.year = static_cast<std::uint16_t>(local.tm_year + 1900);
  time.month = static_cast<std::uint8_t>(local.tm_mon + 1);
  time.day = static_cast<std::uint8_t>(local.tm_mday);
  time.hour = static_cast<std::uint8_t>(local.tm_hour);
  time.minute = static_cast<std::uint8_t>(local.tm_min);
  time.second = static_cast<std::uint8_t>(local.tm_sec);
  (void)controller_.post(control::Command{0, control::ClockCommand{time}});
}

// ---- travel commands ----

namespace {

control::TravelCommand travel_command(const api::TravelArgs& args) {
  control::TravelCommand cmd;
  cmd.floor = static_cast<std::size_t>(args.floor);
  if (args.speed) cmd.speed = dcp::speed_from_string(*args.speed);
  if (args.load_percent) cmd.load_percent = static_cast<std::uint8_t>(*args.load_percent);
  return cmd;
}

}  // namespace

void DcpBackend::travel(const api::TravelArgs& args, api::Responder done) {
  note_travel_asked();
  send(travel_command(args), std::move(done));
}

void DcpBackend::fast_stop(api::Responder done) {
  send(control::FastStopCommand{}, std::move(done));
}

void DcpBackend::fast_start(const std::string& action, const api::TravelArgs& args,
                            api::Responder done) {
  if (action == "arm") {
    control::TravelCommand cmd = travel_command(args);
    cmd.fast_start = true;
    send(cmd, std::move(done));
    return;
  }
  send(control::FastStartCommand{action == "go" ? control::FastStartCommand::Action::Go
                                                : control::FastStartCommand::Action::Abort},
       std::move(done));
}

}  // namespace liftd::daemon
