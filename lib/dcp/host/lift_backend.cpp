#include "dcp/host/lift_backend.hpp"

#include <algorithm>
#include <ctime>

#include "common/mono_time.hpp"
#include "dcp/charset.hpp"
#include "dcp/host/simulated_lift.hpp"
#include "dcp/trace.hpp"
#include "host/learn_report.hpp"
#include "host/lift_common.hpp"
#include "host/lift_core.hpp"
#include "log/log.hpp"

#include <cstring>

namespace liftd::daemon {
namespace {

using api::Result;

// How long a client waits for the cycle to answer a command. The cycle answers travel
// commands within a cycle and I-messages within dcp.request_timeout_ms; this only catches a
// cycle that stopped.
constexpr std::chrono::seconds kDcpReplyGrace{3};
// The thread as the busy and expiry answers name it.
constexpr std::string_view kCycleThread = "cycle";

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

/// The command bits B0..B7 and status bits S0..S7 (DCP 4.1) of a travel's curve: the spec's
/// label with the name the status JSON (and the trace) gives the bit.
TravelBitNames dcp_travel_bit_names() {
  return {{"B0_enable", "B1_travel", "B2_stop", "B3_speed", "B4_down", "B5_change", "B6_desired",
           "B7_reply_error"},
          {"S0_ready", "S1_travel_active", "S2_advance_warning", "S3_general_fault",
           "S4_below_levelling", "S5_accepted", "S6_brake_open", "S7_message_error"}};
}

std::string utf8_row(const std::array<std::uint8_t, dcp::kDisplayColumns>& row) {
  return dcp::to_utf8(std::span<const std::uint8_t>(row.data(), row.size()));
}

}  // namespace

LiftBackend::LiftBackend(const config::Config& config, const config::Schema& schema,
                         control::DcpController& controller, rt::CycleRunner& runner,
                         control::PositionFeed* position_feed, std::string runtime_dir,
                         SimulatedLift* sim)
    : config_(config),
      schema_(schema),
      controller_(controller),
      runner_(runner),
      flight_recorder_(
          runner.recorder(), std::move(runtime_dir),
          static_cast<std::size_t>(config.rt.trace_files_kept), "dcp",
          [this] {
            // The decoded column of the protocol the drive speaks now (DCP 3.5).
            dcp::TraceOptions options;
            options.protocol = controller_.snapshot().protocol.value_or(dcp::Protocol::Dcp4);
            options.data_info = *dcp::data_info_type_from_char(config_.dcp.data_info_type);
            return dcp::trace_decoder(options);
          }),
      sim_(sim),
      inputs_(config, position_feed, sim != nullptr),
      travel_log_(dcp_travel_bit_names(), floor_levels_mm(config)),
      mono_at_start_(mono_now()),
      wall_at_start_(std::chrono::system_clock::now()) {}

std::chrono::system_clock::time_point LiftBackend::wall_time(MonoTime at) const {
  return wall_at_start_ +
         std::chrono::duration_cast<std::chrono::system_clock::duration>(at - mono_at_start_);
}

// ---- reads ----

api::StatusSnapshot LiftBackend::status() {
  const control::ControllerSnapshot s = controller_.snapshot();
  api::StatusSnapshot out;
  out.drive_kind = drive::Kind::Dcp;
  out.link = to_api(s.link);
  const DcpStatusFacts facts{s.protocol,          s.status_byte,         s.extended,
                             s.handshake_problem, runner_.config().echo, runner_.echo_state()};
  if (!(facts == dcp_facts_)) {  // built again only when it changed: status is asked often
    dcp_facts_ = facts;
    dcp_details_ = dcp_status_json(facts);
  }
  out.details = dcp_details_;
  out.position_mm = s.position_mm;
  if (s.floor) out.floor = static_cast<int>(*s.floor);
  if (s.next_possible_stop) out.next_possible_stop = static_cast<int>(*s.next_possible_stop);
  out.travel_state = s.travel_kind == travel::TravelKind::None
                         ? (s.fast_start_armed ? "fast_start" : "idle")
                         : std::string(travel::to_string(s.travel_kind));
  if (s.fast_start_armed) out.travel_state = "fast_start";
  out.travel_direction = direction_name(s.direction);
  if (s.target_floor) out.target_floor = static_cast<int>(*s.target_floor);
  for (std::size_t i = 0; i < s.call_count; ++i) out.calls.push_back(s.calls[i]);
  out.brake_open = s.brake_open;
  out.contactors_on = s.contactors_on;
  out.last_travel_slip_mm = s.last_travel_slip_mm;
  for (std::size_t i = 0; i < s.faults.size(); ++i) {
    if (!s.faults[i]) continue;
    const auto code = static_cast<control::FaultCode>(i);
    out.faults.push_back({std::string(control::fault_code_name(code)),
                          std::string(control::fault_text(code)), wall_time(s.fault_since[i])});
  }
  out.drive_state =
      drive::state_of(s.link == dcp::LinkState::Up, s.travel_kind != travel::TravelKind::None,
                      !out.faults.empty(), s.drive_allows_travel);
  const rt::RtThreadStatus& rt = runner_.thread_status();
  out.rt.realtime = rt.realtime;
  out.rt.policy = rt.realtime ? "SCHED_FIFO" : "SCHED_OTHER";
  out.rt.priority = rt.realtime ? config_.rt.priority : 0;
  out.rt.memory_locked = rt.memory_locked;
  return out;
}

api::StatsSnapshot LiftBackend::stats() {
  const rt::CycleStats cycle = runner_.stats();
  const dcp::LinkCounters link = controller_.snapshot().link_counters;
  api::StatsSnapshot out;
  out.drive_kind = drive::Kind::Dcp;
  out.frames_sent = cycle.counters.frames_sent;
  out.cycles = cycle.counters.cycles;
  out.dropped_events = controller_.dropped_events();
  out.dropped_travel_samples = controller_.dropped_travel_samples();
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
  d["max_work_us"] = static_cast<std::uint64_t>(cycle.work_time.max_us());
  return out;
}

std::vector<api::TraceEntry> LiftBackend::trace(std::size_t max_entries) {
  const std::vector<rt::FrameRecord> records = runner_.recorder().copy();
  std::vector<api::TraceEntry> out;
  for (const rt::FrameRecord& r : records) {
    if (r.direction == rt::Direction::Tx && r.length == dcp::kFrameSize) {
      api::TraceEntry e;
      e.at = r.time;
      e.tx.assign(r.bytes.begin(), r.bytes.begin() + dcp::kFrameSize);
      out.push_back(std::move(e));
    } else if (r.direction == rt::Direction::Rx && !out.empty() && r.length == dcp::kFrameSize &&
               (r.flags & (rt::record_flag::kReply | rt::record_flag::kBad)) != 0) {
      out.back().rx.emplace(r.bytes.begin(), r.bytes.begin() + dcp::kFrameSize);
    }
  }
  if (out.size() > max_entries) {
    out.erase(out.begin(), out.end() - static_cast<std::ptrdiff_t>(max_entries));
  }
  return out;
}

api::Result LiftBackend::save_trace() {
  return flight_recorder_.save_requested(std::chrono::steady_clock::now());
}

api::Result LiftBackend::travels(std::size_t last) {
  return api::Result::ok(travel_log_.to_json(last, [this](MonoTime at) { return wall_time(at); }));
}

void LiftBackend::record_travel_end(MonoTime at, bool aborted, lift::Cause cause) {
  travel_log_.end(at, travel_end_cause(aborted, lift::to_string(cause)));
}

api::Result LiftBackend::write_flight_recorder(std::string_view why) {
  return flight_recorder_.write(why);
}

DisplaySnapshot LiftBackend::display() {
  const control::ControllerSnapshot s = controller_.snapshot();
  DisplaySnapshot out;
  for (const auto& row : s.display) out.lines.push_back(utf8_row(row));
  return out;
}

nlohmann::json LiftBackend::config() {
  return config::to_json(config_, schema_);
}

// ---- commands through the cycle ----

void LiftBackend::send(control::CommandBody body, api::Responder done,
                       Pending::Completion complete) {
  (void)post_command<control::Command>(controller_, pending_, std::move(body), std::move(done),
                                       kDcpReplyGrace, kCycleThread, std::move(complete));
}

void LiftBackend::poll(MonoTime now) {
  control::CommandReply r;
  while (controller_.poll_reply(r)) pending_.answer(r);
  travel_log_.drain(controller_);  // before the events: a travel's end finds its samples
  pending_.expire(now,
                  "the " + std::string(kCycleThread) + " thread did not answer; see the journal");
}

void LiftBackend::key(int button, api::Responder done) {
  // DCP 5.6.3: button n is bit 0x04 << (n - 1).
  const auto bits = static_cast<std::uint8_t>(0x04U << (button - 1));
  send(control::LinkCommand{dcp::KeypadPress{bits}}, std::move(done));
}

void LiftBackend::drive_reset(api::Responder done) {
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

void LiftBackend::power(PowerSetting setting, api::Responder done) {
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

void LiftBackend::load(int percent, api::Responder done) {
  send(control::LinkCommand{dcp::LoadRequest{static_cast<std::uint16_t>(percent)}},
       std::move(done));
}

void LiftBackend::update_inputs(const api::InputUpdate& update, api::Responder done) {
  done(inputs_.take(update, [this](const lift::Inputs& now) { send_inputs(now); }));
}

void LiftBackend::simulated_inputs(const lift::Inputs& sample) {
  inputs_.take_sample(sample, [this](const lift::Inputs& now) { send_inputs(now); });
}

void LiftBackend::send_inputs(const lift::Inputs& inputs) {
  (void)controller_.post(control::Command{0, control::InputsCommand{inputs}});
}

bool LiftBackend::send_shutdown(bool force) {
  return controller_.post(control::Command{0, control::ShutdownCommand{force}});
}

void LiftBackend::send_clock(std::chrono::system_clock::time_point now) {
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

void LiftBackend::travel(const api::TravelArgs& args, api::Responder done) {
  send(travel_command(args), std::move(done));
}

void LiftBackend::stop(api::Responder done) {
  send(control::StopCommand{}, std::move(done));
}

void LiftBackend::fast_stop(api::Responder done) {
  send(control::FastStopCommand{}, std::move(done));
}

void LiftBackend::relevel(api::Responder done) {
  send(control::RelevelCommand{}, std::move(done));
}

void LiftBackend::learn(api::Responder done) {
  // Answered when the learning ends: both legs at the crawl limit the controller gives them,
  // and the grace of every reply.
  std::int64_t bottom_mm = 0;
  std::int64_t top_mm = 0;
  if (!config_.floors.empty()) {
    bottom_mm = config_.floors.front().level_mm;
    top_mm = config_.floors.back().level_mm;
  }
  const auto longest =
      lift::learn_longest(travel::TravelConfig{}.crawl_timeout_ms, bottom_mm, top_mm);
  (void)post_command<control::Command>(
      controller_, pending_, control::LearnCommand{}, std::move(done), longest + kDcpReplyGrace,
      kCycleThread, [this](const control::CommandReply&) {
        nlohmann::json result = learn_result_json(config_, controller_.learn_record());
        if (learn_listener_) learn_listener_(result);
        return api::Result::ok(std::move(result));
      });
}

void LiftBackend::inspection(bool on, const std::string& direction, api::Responder done) {
  control::InspectionCommand cmd;
  cmd.on = on;
  cmd.direction = direction == "up"     ? lift::Direction::Up
                  : direction == "down" ? lift::Direction::Down
                                        : lift::Direction::None;
  send(cmd, std::move(done));
}

void LiftBackend::fast_start(const std::string& action, const api::TravelArgs& args,
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

void LiftBackend::calls(const std::string& action, std::optional<int> floor, api::Responder done) {
  if (action == "list") {
    const auto s = controller_.snapshot();
    nlohmann::json list = nlohmann::json::array();
    for (std::size_t i = 0; i < s.call_count; ++i) list.push_back(s.calls[i]);
    done(Result::ok({{"calls", list}}));
    return;
  }
  control::CallCommand cmd;
  cmd.add = action == "add";
  cmd.floor = static_cast<std::size_t>(floor.value_or(0));
  send(cmd, std::move(done));
}

void LiftBackend::sim(const api::SimRequest& request, api::Responder done) {
  if (sim_ == nullptr) {
    api::Backend::sim(request, std::move(done));
    return;
  }
  done(sim_->apply(request, mono_now()));
}

}  // namespace liftd::daemon
