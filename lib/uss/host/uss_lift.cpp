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
#include "uss/host/sim_actions.hpp"
#include "uss/timing.hpp"

namespace liftd::daemon {
namespace {

using namespace std::chrono_literals;
using api::Result;

constexpr auto kSimSlice = 1ms;  // the simulated bus checks its reply times this often
// The simulated drive's ramp, and the crawl it leaves before the level: its nominal speed is
// sized so that the fastest speed, braked at this ramp from its configured deceleration point,
// crawls this far (as the simulated DCP3 drive does).
constexpr double kSimRampMps2 = 0.5;
constexpr double kSimCrawlApproachM = 0.1;

uss::PkwLength pkw_length_of(config::UssPkw pkw) {
  switch (pkw) {
    case config::UssPkw::none:
      return uss::PkwLength::None;
    case config::UssPkw::three:
      return uss::PkwLength::Three;
    case config::UssPkw::four:
      return uss::PkwLength::Four;
    case config::UssPkw::variable:
      return uss::PkwLength::Variable;
  }
  return uss::PkwLength::Four;
}

/// Every slave on the bus, the drive first.
std::vector<config::UssSlave> bus_slaves(const config::Config& c) {
  std::vector<config::UssSlave> out;
  out.push_back({c.uss.drive_address, c.uss.drive_pkw, c.uss.drive_pzd_words});
  for (const auto& s : c.uss.slaves) out.push_back(s);
  return out;
}

}  // namespace

uss::MasterConfig uss_master_config(const config::Config& c) {
  uss::MasterConfig out;
  out.baud = static_cast<std::uint32_t>(c.uss.baud);
  for (const auto& s : bus_slaves(c)) {
    uss::SlaveConfig slave;
    slave.address = static_cast<std::uint8_t>(s.address);
    slave.pkw = pkw_length_of(s.pkw);
    slave.pzd_words = static_cast<std::uint8_t>(s.pzd_words);
    out.slaves.push_back(slave);
  }
  // USS A 2.1: an empty list polls every slave once per pass, the drive first.
  if (c.uss.polling_list.empty()) {
    for (const auto& s : out.slaves) out.polling_list.push_back(s.address);
  } else {
    for (int a : c.uss.polling_list) out.polling_list.push_back(static_cast<std::uint8_t>(a));
  }
  out.reply_delay = std::chrono::milliseconds(c.uss.reply_delay_ms);
  if (c.uss.cycle_time_ms > 0) out.cycle_time = std::chrono::milliseconds(c.uss.cycle_time_ms);
  out.pkw_repeat_limit = static_cast<std::uint32_t>(c.uss.pkw_repeat_limit);
  out.mirror_at_start = c.uss.mirror_at_start;
  return out;
}

uss::UssControllerConfig uss_controller_config(const config::Config& c) {
  uss::UssControllerConfig out;
  out.drive_address = static_cast<std::uint8_t>(c.uss.drive_address);
  out.drive_pzd_words = static_cast<std::uint8_t>(c.uss.drive_pzd_words);
  // The controller thinks in percent of the drive's full scale (USS C 5.2.2: 0x4000 = 100 %).
  out.normalisation.raw_full_scale = c.uss.full_scale_raw;
  out.normalisation.full_scale = 100.0;
  uss::LiftTravelConfig& t = out.travel;
  t.speed_percent.fill(0.0);
  for (const auto& [name, setpoint] : c.uss.speeds) {
    if (const auto speed = uss::parse_speed(name)) {
      t.speed_percent[uss::speed_index(*speed)] = setpoint * 100.0 / c.uss.full_scale;
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
  t.profile.switch_on_timeout_ms = static_cast<std::uint32_t>(c.uss.profile_timeout_ms);
  out.link_fault_replies = static_cast<std::uint32_t>(c.uss.telegram_failures);
  out.lift.level_tolerance_mm = static_cast<std::uint32_t>(c.travel.level_tolerance_mm);
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

namespace {

/// {"on": true, "no_off2": true, ...}: the bits 0..10 of a control or status word by name.
nlohmann::json word_bits(std::uint16_t word, const std::array<std::string_view, 11>& names) {
  nlohmann::json out = nlohmann::json::object();
  for (std::size_t bit = 0; bit < names.size(); ++bit) {
    out[std::string(names[bit])] = (word & (1U << bit)) != 0;
  }
  return out;
}

}  // namespace

TravelBitNames UssDrive::travel_bit_names() {
  TravelBitNames names;
  for (const std::string_view name : uss::kControlWordBitNames) names.command.emplace_back(name);
  for (const std::string_view name : uss::kStatusWordBitNames) names.status.emplace_back(name);
  return names;
}

// ---- the simulated bus ----

SimulatedUssBus::SimulatedUssBus(const config::Config& config)
    : SimulatorThread(config),
      baud_(static_cast<std::uint32_t>(config.uss.baud)),
      drive_address_(static_cast<std::uint8_t>(config.uss.drive_address)),
      priority_(std::max(1, config.rt.priority - 1)) {
  auto pair = io::PtyPair::create(uss::uss_serial_settings(baud_), true);
  if (!pair) throw std::runtime_error("simulated USS bus: " + pair.error().message());
  pty_ = std::make_unique<io::PtyPair>(std::move(pair).value());
  port_ = pty_->take_master();
  // v^2 = 2 a d: the fastest speed brakes from its deceleration point down to the crawl.
  const std::string fastest = config::dcp3_speeds(config.travel.dcp3_speed_count).front();
  const auto decel = config.travel.dcp3_decel_distance_mm.find(fastest);
  const auto setpoint = config.uss.speeds.find(fastest);
  double nominal_mps = 1.0;
  if (decel != config.travel.dcp3_decel_distance_mm.end() && setpoint != config.uss.speeds.end()) {
    const double braking_m = std::max(0.2, decel->second / 1000.0 - kSimCrawlApproachM);
    const double fraction = setpoint->second / config.uss.full_scale;
    nominal_mps = std::sqrt(2.0 * kSimRampMps2 * braking_m) / std::max(0.05, fraction);
  }
  std::vector<uss::sim::UssSlaveConfig> slaves;
  for (const auto& s : bus_slaves(config)) {
    uss::sim::UssSlaveConfig sc;
    sc.address = static_cast<std::uint8_t>(s.address);
    sc.pkw = pkw_length_of(s.pkw);
    sc.pzd_words = static_cast<std::uint8_t>(s.pzd_words);
    sc.car.nominal_mps = nominal_mps;
    sc.car.accel_mps2 = kSimRampMps2;
    if (!config.floors.empty()) {
      sc.car.start_mm = static_cast<double>(config.floors.front().level_mm);
      sc.car.bottom_mm = shaft_bottom_mm(config);
      sc.car.top_mm = shaft_top_mm(config);
    }
    for (const auto& f : config.floors) sc.car.floors_mm.push_back(f.level_mm);
    slaves.push_back(sc);
  }
  bus_ = std::make_unique<uss::sim::UssBusSim>(slaves, baud_, mono_now());
  encoder_.set(drive().position_mm());
}

SimulatedUssBus::~SimulatedUssBus() {
  stop();
}

bool SimulatedUssBus::start() {
  start_thread([this] { loop(); });
  log::event(log::Level::info, "sim", "sim_started", {{"device", device_path()}},
             "simulated USS bus (" + std::to_string(bus_->slaves().size()) +
                 " slave(s)) answering on " + device_path());
  return true;
}

void SimulatedUssBus::stop() {
  if (!join_thread()) return;
  log_violations();
  std::lock_guard<std::mutex> lock(mutex_);
  std::uint64_t violations = 0;
  std::uint64_t unjudged = 0;
  for (const auto& s : bus_->slaves()) {
    violations += s.stats().violations;
    unjudged += s.stats().unjudged;
  }
  const auto mm = std::llround(drive().position_mm());
  log::event(log::Level::info, "sim", "sim_stopped",
             {{"position_mm", std::to_string(mm)},
              {"violations", std::to_string(violations)},
              {"unjudged", std::to_string(unjudged)}},
             "simulated USS bus stopped: car at " + std::to_string(mm) + " mm, " +
                 std::to_string(violations) + " violation(s) of the USS specification seen, " +
                 std::to_string(unjudged) +
                 " timing check(s) not judged (the master may have given up on a reply the "
                 "machine delivered late)");
}

void SimulatedUssBus::loop() {
  // The simulated slaves stand for separate devices that answer within their reply delay
  // (USS A 5.2.1.1): one step below the master's real-time priority where the system permits
  // it, so a loaded machine delays neither side (as the simulated DCP drive).
  sched_param param{};
  param.sched_priority = priority_;
  (void)::pthread_setschedparam(::pthread_self(), SCHED_FIFO, &param);
  // It never enters poll(2) or read(2) on a tty that holds nothing: both wait there for the
  // tty's flip-buffer worker, a normal-priority kernel thread that other work can keep from a
  // CPU for hundreds of ms (docs/architecture.md, "What the cycle may wait for"). It reads
  // what the line discipline holds (TIOCINQ) and sleeps in an edge-triggered epoll watch,
  // which the tty wakes when bytes arrive and which never looks at an empty tty.
  const int epoll_fd = ::epoll_create1(EPOLL_CLOEXEC);
  if (epoll_fd >= 0) (void)port_.watch_input(epoll_fd);
  std::array<std::uint8_t, 512> buffer{};
  while (!stopping()) {
    const timespec slice{0, std::chrono::nanoseconds(kSimSlice).count()};
    epoll_event ready{};
    if (epoll_fd >= 0) {
      (void)::epoll_pwait2(epoll_fd, &ready, 1, &slice, nullptr);
    } else {
      (void)::clock_nanosleep(CLOCK_MONOTONIC, 0, &slice, nullptr);
    }
    std::size_t got = 0;
    while (got < buffer.size()) {
      const io::IoResult r = port_.read_queued(std::span(buffer).subspan(got));
      got += r.bytes;
      if (r.bytes == 0) break;
    }
    const MonoTime now = mono_now();
    std::lock_guard<std::mutex> lock(mutex_);
    // The pseudo-terminal carries no parity bit: every character arrives clean.
    for (std::size_t i = 0; i < got; ++i) {
      bus_->on_char(uss::RxChar{buffer[i], uss::LineError::None}, now);
    }
    serve(now);
  }
  if (epoll_fd >= 0) ::close(epoll_fd);
}

void SimulatedUssBus::serve(MonoTime now) {
  bus_->on_time(now);
  uss::sim::UssReply reply;
  while (bus_->take_reply(now, reply)) {
    // A pseudo-terminal moves the bytes at once: the reply ends when it is written.
    (void)port_.write_frame(reply.view());
    bus_->reply_sent(now);
  }
  car_moved(drive().position_mm(), drive().velocity_mps() != 0.0, now);
}

void SimulatedUssBus::log_violations() {
  std::vector<uss::sim::UssViolation> found;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    std::array<uss::sim::UssViolation, 16> batch{};
    std::size_t n = 0;
    while ((n = bus_->take_violations(batch)) > 0) {
      found.insert(found.end(), batch.begin(), batch.begin() + static_cast<std::ptrdiff_t>(n));
    }
  }
  for (const auto& v : found) {
    log::event(log::Level::error, "sim", "sim_violation",
               {{"rule", std::string(v.rule)}, {"address", std::to_string(v.address)}},
               "simulated USS slave " + std::to_string(v.address) +
                   ": the master broke the USS specification: " + std::string(v.rule));
  }
}

api::Result SimulatedUssBus::apply(const api::SimRequest& request, MonoTime now) {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto shared = [this, &request](api::SimAction action) -> std::optional<Result> {
    using api::SimAction;
    switch (action) {
      case SimAction::GeneralFault:
        drive().set_drive_fault(request.on);
        break;
      case SimAction::AdvanceWarning:
        drive().set_warning(request.on);
        break;
      case SimAction::NotReady:
        // ZSW bit 9 = 0: the drive is in local control and takes no process data (USS C 5.2.1).
        drive().set_local(request.on);
        break;
      case SimAction::ReplyFault: {
        std::optional<uss::sim::UssReplyFault> fault;
        switch (request.fault) {
          case api::SimReplyFault::NoReply:
            fault = uss::sim::UssReplyFault::Silent;
            break;
          case api::SimReplyFault::BadChecksum:
            fault = uss::sim::UssReplyFault::BadBcc;
            break;
          case api::SimReplyFault::Late:
            fault = uss::sim::UssReplyFault::Late;
            break;
          case api::SimReplyFault::Garbage:
            fault = uss::sim::UssReplyFault::BadLge;
            break;
          case api::SimReplyFault::S7:
            break;
        }
        if (!fault) {
          return Result::fail(api::ErrorCode::BadRequest,
                              "\"s7\" is a DCP reply bit; a USS drive has none", "fault");
        }
        drive().inject(*fault, request.frames);
        break;
      }
      case SimAction::ClearReplyFaults:
        drive().clear_faults();
        break;
      case SimAction::Drift:
        if (drive().velocity_mps() != 0.0) {
          return Result::fail(api::ErrorCode::Busy, "the car is moving: drift only at rest");
        }
        drive().move_car(request.drift_mm);
        break;
      default:  // the board's actions: SimulatedBoard::apply took them
        break;
    }
    return std::nullopt;
  };
  // The USS kind declares no actions of its own, so apply_sim never calls this.
  const auto own = [](std::size_t) -> std::optional<Result> { return std::nullopt; };
  if (auto refused = apply_sim(kUssSimActionTable, request, board_, now, shared, own)) {
    return std::move(*refused);
  }
  return Result::ok(state_json_locked());
}

nlohmann::json SimulatedUssBus::state_json() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return state_json_locked();
}

nlohmann::json SimulatedUssBus::state_json_locked() const {
  const uss::sim::UssDriveView d = drive().drive();
  std::uint64_t violations = 0;
  std::uint64_t unjudged = 0;
  nlohmann::json slaves = nlohmann::json::array();
  for (const auto& s : bus_->slaves()) {
    violations += s.stats().violations;
    unjudged += s.stats().unjudged;
    slaves.push_back({{"address", s.address()},
                      {"telegrams", s.stats().telegrams},
                      {"replies", s.stats().replies}});
  }
  nlohmann::json out = {{"drive_state", std::string(uss::sim::to_string(d.state))},
                        {"control_word", d.stw},
                        {"status_word", d.zsw},
                        {"velocity_mps", d.velocity_mps},
                        {"brake_open", d.brake_open},
                        {"position_mm", std::llround(d.position_mm)},
                        {"slaves", std::move(slaves)},
                        {"violations", violations},
                        {"unjudged_timing", unjudged}};
  board_.add_state(out);
  return out;
}

// ---- the backend ----

api::StatusSnapshot UssBackend::status() {
  const uss::ControllerSnapshot s = controller_.snapshot();
  const api::LinkState link = !s.port_up || !s.drive_heard
                                  ? (s.drive_heard ? api::LinkState::Fault : api::LinkState::Down)
                                  : (s.link_ok ? api::LinkState::Up : api::LinkState::Fault);
  api::StatusSnapshot out = neutral_status(s, link);
  nlohmann::json d = nlohmann::json::object();
  d["drive_address"] = s.drive_address;
  d["profile_state"] = std::string(uss::to_string(s.drive_state));
  d["wish"] = std::string(uss::to_string(s.wish));
  d["supervision"] = std::string(uss::to_string(s.supervision));
  d["control_word"] = s.stw_sent;
  d["status_word"] = s.zsw;
  d["control_bits"] = word_bits(s.stw_sent, uss::kControlWordBitNames);
  d["status_bits"] = word_bits(s.zsw, uss::kStatusWordBitNames);
  d["setpoint"] = {{"raw", s.setpoint_raw}, {"percent", s.setpoint_percent}};
  d["actual"] = {{"raw", s.actual_raw}, {"percent", std::round(s.actual_percent * 10.0) / 10.0}};
  d["phase"] = std::string(uss::to_string(s.phase));
  d["speed"] = std::string(uss::to_string(s.speed));
  nlohmann::json slaves = nlohmann::json::array();
  for (std::size_t i = 0; i < s.slave_count; ++i) {
    const uss::SlaveSnapshot& sl = s.slaves[i];
    slaves.push_back({{"address", sl.address},
                      {"heard", sl.heard},
                      {"responding", sl.responding},
                      {"pkw_busy", sl.pkw_busy}});
  }
  d["slaves"] = std::move(slaves);
  d["line_echo"] = line_echo_json(runner_.config().echo, runner_.echo_state());
  out.details = std::move(d);
  out.brake_open = s.brake_open;
  out.contactors_on = s.contactors_on;
  return out;
}

api::StatsSnapshot UssBackend::stats() {
  const uss::ControllerSnapshot s = controller_.snapshot();
  const uss::UssRunnerStats r = runner_.stats();
  api::StatsSnapshot out;
  out.drive_kind = drive::Kind::Uss;
  out.frames_sent = r.counters.exchanges;
  out.cycles = r.counters.cycles;
  out.dropped_events = controller_.dropped_events();
  out.dropped_travel_samples = controller_.dropped_travel_samples();
  nlohmann::json rx = {{"good", s.rx.good},
                       {"rejected", s.rx.rejected},
                       {"framing", s.rx.framing},
                       {"overrun", s.rx.overrun},
                       {"parity", s.rx.parity},
                       {"no_stx", s.rx.no_stx},
                       {"residual_time", s.rx.residual_time},
                       {"bcc", s.rx.bcc},
                       {"lge", s.rx.lge},
                       {"reply_timeout", s.rx.reply_timeout},
                       {"error_word", s.rx.error_word}};
  nlohmann::json slaves = nlohmann::json::array();
  for (std::size_t i = 0; i < s.slave_count; ++i) {
    const uss::SlaveSnapshot& sl = s.slaves[i];
    nlohmann::json pzd = nlohmann::json::array();
    for (std::size_t w = 0; w < sl.pzd_in_count; ++w) pzd.push_back(sl.pzd_in[w]);
    slaves.push_back({{"address", sl.address},
                      {"good", sl.good},
                      {"failures", sl.failures},
                      {"consecutive_failures", sl.consecutive_failures},
                      {"pzd_in", std::move(pzd)}});
  }
  const auto us = [](std::chrono::nanoseconds t) {
    return std::chrono::duration_cast<std::chrono::microseconds>(t).count();
  };
  // The bus's own figures (docs/api.md `stats`); a reply timeout and a BCC error are counted in
  // `receive` (USS A 5.2.3), not twice.
  out.details = {{"baud", config_.uss.baud},
                 {"expected_cycle_time_us", us(s.expected_cycle_time)},
                 {"last_cycle_time_us", us(s.last_cycle_time)},
                 {"cycle_time_p99_us", r.cycle_time.percentile_us(0.99)},
                 {"replies_good", r.counters.good_replies},
                 {"replies_rejected", r.counters.bad_replies},
                 {"port_losses", r.counters.port_losses},
                 {"max_lateness_us", static_cast<std::uint64_t>(r.wake_lateness.max_us())},
                 {"lateness_p99_us", r.wake_lateness.percentile_us(0.99)},
                 {"reply_p99_us", r.reply_time.percentile_us(0.99)},
                 {"line_errors", r.counters.line_errors},
                 {"echo_collisions", r.counters.echo_collisions},
                 {"receive", std::move(rx)},
                 {"slaves", std::move(slaves)}};
  return out;
}

std::vector<api::TraceEntry> UssBackend::trace(std::size_t max_entries) {
  // Each telegram of ours with the reply to it (none for a broadcast or a silent slave).
  const std::vector<rt::FrameRecord> records = runner_.recorder().copy();
  std::vector<api::TraceEntry> out;
  for (const rt::FrameRecord& r : records) {
    if (r.direction == rt::Direction::Tx) {
      api::TraceEntry e;
      e.at = r.time;
      e.tx.assign(r.data().begin(), r.data().end());
      out.push_back(std::move(e));
    } else if (r.direction == rt::Direction::Rx && !out.empty() && !out.back().rx) {
      out.back().rx.emplace(r.data().begin(), r.data().end());
    }
  }
  if (out.size() > max_entries) {
    out.erase(out.begin(), out.end() - static_cast<std::ptrdiff_t>(max_entries));
  }
  return out;
}

std::optional<uss::PkwLength> UssBackend::pkw_length(std::uint8_t address) const {
  for (const auto& s : master_.config().slaves) {
    if (s.address == address) return s.pkw;
  }
  return std::nullopt;
}

api::Result UssBackend::parameter_result(const ParameterContext& context,
                                         const uss::PkwResult& r) const {
  const std::string slave = "slave " + std::to_string(context.address);
  switch (r.outcome) {
    case uss::PkwResult::Outcome::Done:
      break;
    case uss::PkwResult::Outcome::Error:
      // USS C 4.2.1.1: reply id 7, the error number in the PWE.
      return Result::fail(api::ErrorCode::BadRequest,
                          slave + " refused the request: error " + std::to_string(r.error_number) +
                              " (" + std::string(uss::error_text(r.error_number)) + ")");
    case uss::PkwResult::Outcome::NoAuthority:
      return Result::fail(api::ErrorCode::NotReady,
                          slave +
                              " gives the master no parameter authority (reply id 8): set "
                              "its parameter authority to this interface");
    case uss::PkwResult::Outcome::Unanswered:
      return Result::fail(api::ErrorCode::NotReady,
                          "no matching reply from " + slave + " after " +
                              std::to_string(config_.uss.pkw_repeat_limit) +
                              " polls (uss.pkw_repeat_limit)");
  }
  const uss::Pkw& reply = r.reply;
  nlohmann::json out = {
      {"address", context.address},
      {"pnu", reply.pnu},
      {"target", std::string(kParameterTargets[static_cast<std::size_t>(context.args.target)])},
      {"index", context.args.index},
      {"reply", std::string(uss::reply_name(reply.id))}};
  nlohmann::json words = nlohmann::json::array();
  for (std::uint16_t w : reply.pwe_words()) words.push_back(w);
  out["words"] = std::move(words);
  if (reply.id == uss::reply::kText) {
    // USS C 4.2.2: two characters per PWE word, high byte first.
    std::string text;
    for (std::uint16_t w : reply.pwe_words()) {
      for (std::uint8_t c : {static_cast<std::uint8_t>(w >> 8), static_cast<std::uint8_t>(w)}) {
        if (c != 0) text += static_cast<char>(c);
      }
    }
    out["text"] = text;
  } else {
    const uss::PkwWidth width = uss::reply_width(reply.id);
    out["width"] = width == uss::PkwWidth::Dword ? "dword" : "word";
    out["value"] = uss::value(reply, context.length, width);
  }
  return Result::ok(std::move(out));
}

void UssBackend::travel(const api::TravelArgs& args, api::Responder done) {
  uss::TravelCommand cmd;
  cmd.floor = static_cast<std::size_t>(args.floor);
  if (args.speed) {
    const auto speed = uss::parse_speed(*args.speed);
    if (!speed || config_.uss.speeds.count(*args.speed) == 0) {
      done(Result::fail(api::ErrorCode::BadRequest,
                        "speed " + *args.speed + " has no setpoint in uss.speeds", "speed"));
      return;
    }
    cmd.speed = *speed;
  } else {
    // The fastest travelling speed of the installation (travel.dcp3_speed_count, fastest first).
    cmd.speed = *uss::parse_speed(config::dcp3_speeds(config_.travel.dcp3_speed_count).front());
  }
  send(cmd, std::move(done));
}

void UssBackend::drive_reset(api::Responder done) {
  // The result has the shape of the DCP drive's reset: {"reset": true, "detail": ...}.
  send(uss::DriveResetCommand{}, [done = std::move(done)](Result r) mutable {
    if (!r.is_ok()) {
      done(std::move(r));
      return;
    }
    nlohmann::json v = r.value();
    v["reset"] = true;
    if (!v.contains("detail")) {
      v["detail"] = "fault acknowledged: control word bit 7 rising edge (USS C 5.2.1)";
    }
    done(Result::ok(std::move(v)));
  });
}

void UssBackend::parameter(const ParameterArgs& args, api::Responder done) {
  const auto address = static_cast<std::uint8_t>(args.address.value_or(config_.uss.drive_address));
  const auto length = pkw_length(address);
  if (!length) {
    done(Result::fail(api::ErrorCode::BadRequest,
                      "slave " + std::to_string(address) +
                          " is not on this bus: it is neither uss.drive_address nor in uss.slaves",
                      "address"));
    return;
  }
  if (*length == uss::PkwLength::None) {
    done(Result::fail(api::ErrorCode::BadRequest,
                      "slave " + std::to_string(address) +
                          " has no PKW area (pkw \"0\", USS C 4.1): its parameters cannot be "
                          "reached",
                      "address"));
    return;
  }
  const uss::PkwTarget target = args.target == ParameterTarget::Array ? uss::PkwTarget::ArrayElement
                                : args.target == ParameterTarget::Description
                                    ? uss::PkwTarget::Description
                                : args.target == ParameterTarget::Text ? uss::PkwTarget::Text
                                                                       : uss::PkwTarget::Value;
  const uss::PkwWidth width = args.dword ? uss::PkwWidth::Dword : uss::PkwWidth::Word;
  uss::Pkw request;
  request.pnu = static_cast<std::uint16_t>(args.pnu);
  request.ind = uss::make_ind(target, static_cast<std::uint8_t>(args.index));
  if (args.write) {
    const auto id = uss::write_request_id(target, width, args.eeprom);
    if (!id) {
      done(Result::fail(api::ErrorCode::BadRequest, "USS has no such change request (C 4.2.1.1)",
                        "target"));
      return;
    }
    // USS C 4.1.1: three PKW words carry one PWE word; a double word needs four (or variable).
    if (width == uss::PkwWidth::Dword && *length == uss::PkwLength::Three) {
      done(Result::fail(api::ErrorCode::BadRequest,
                        "slave " + std::to_string(address) +
                            " has a PKW area of 3 words: one PWE word, no room for a double word",
                        "width"));
      return;
    }
    request.id = *id;
    uss::set_value(request, *length, width, static_cast<std::uint32_t>(args.value));
  } else {
    request.id = *uss::read_request_id(target);
  }
  uss::ParameterCommand cmd;
  cmd.address = address;
  cmd.request = request;
  const ParameterContext context{args, address, *length};
  send(cmd, std::move(done), [this, context](const uss::CommandReply& r) {
    return r.pkw ? parameter_result(context, *r.pkw) : reply_result(r);
  });
}

void UssBackend::mirror(std::optional<int> address, api::Responder done) {
  const auto a = static_cast<std::uint8_t>(address.value_or(config_.uss.drive_address));
  if (!pkw_length(a)) {
    done(Result::fail(api::ErrorCode::BadRequest,
                      "slave " + std::to_string(a) +
                          " is not on this bus: it is neither uss.drive_address nor in uss.slaves",
                      "address"));
    return;
  }
  send(uss::MirrorCommand{a}, std::move(done), [](const uss::CommandReply& r) {
    if (!r.mirror) return reply_result(r);
    const auto us =
        std::chrono::duration_cast<std::chrono::microseconds>(r.mirror->round_trip).count();
    return r.mirror->ok
               ? Result::ok({{"address", r.mirror->address}, {"ok", true}, {"round_trip_us", us}})
               : Result::fail(api::ErrorCode::Fault, "the mirror telegram to slave " +
                                                         std::to_string(r.mirror->address) +
                                                         " did not come back unchanged in time "
                                                         "(USS A 5.3)");
  });
}

// ---- the lift ----

UssLift::UssLift(Host& daemon, const config::Config& config, bool simulate)
    : ControllerLift(daemon, config, simulate, {"actual"}) {
  uss::UssRunnerConfig rc;
  rc.device_path = config.drive.device;
  rc.serial = uss::uss_serial_settings(static_cast<std::uint32_t>(config.uss.baud));
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
                 simulate_ ? "simulated USS lift running; API on " + socket_path()
                           : "USS master starting on " + config.drive.device);
}

UssLift::~UssLift() {
  shut_down();
}

void UssLift::journal_started() {
  // The cycle the polling list should take by the spec's timing rules (USS A 5.1.1, A 6).
  const auto expected =
      std::chrono::duration_cast<std::chrono::microseconds>(master_->expected_cycle_time()).count();
  log::event(log::Level::info, "uss", "uss_started",
             {{"device", runner_->config().device_path},
              {"baud", std::to_string(config_.uss.baud)},
              {"expected_cycle_us", std::to_string(expected)}},
             "USS master running on " + runner_->config().device_path + " at " +
                 std::to_string(config_.uss.baud) + " baud 8E1, " +
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
      const bool drive = event.link.address == config_.uss.drive_address;
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
                  {"address", std::to_string(config_.uss.drive_address)},
                  {"status_word", std::to_string(event.zsw)}},
                 "USS drive: " + std::string(uss::to_string(event.drive_state)) +
                     (event.plc_control ? ""
                                        : ", in local control (status word bit 9 = 0): no "
                                          "travel starts") +
                     " (status word " + std::to_string(event.zsw) + ")",
                 fault ? std::optional(log::Catalogued::UssSlaveFault) : std::nullopt);
      break;
    }
    case Kind::Travel:
    case Kind::FaultRaised:
    case Kind::FaultCleared:
    case Kind::CallServed:
      report_lift_event(event);
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
