// The USS lift's simulated bus: the simulated slaves on a pseudo-terminal, on their own thread.
#include "uss/config/section.hpp"
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
#include "uss/host/uss_bus_slaves.hpp"
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

}  // namespace

SimulatedUssBus::SimulatedUssBus(const config::Config& config)
    : SimulatorThread(config),
      baud_(static_cast<std::uint32_t>(uss_section(config).baud)),
      drive_address_(static_cast<std::uint8_t>(uss_section(config).drive_address)),
      priority_(std::max(1, config.rt.priority - 1)) {
  auto pair = io::PtyPair::create(uss::uss_serial_settings(baud_), true);
  if (!pair) throw std::runtime_error("simulated USS bus: " + pair.error().message());
  pty_ = std::make_unique<io::PtyPair>(std::move(pair).value());
  port_ = pty_->take_master();
  // v^2 = 2 a d: the fastest speed brakes from its deceleration point down to the crawl.
  const std::string fastest = config::dcp3_speeds(config.travel.dcp3_speed_count).front();
  const auto decel = config.travel.dcp3_decel_distance_mm.find(fastest);
  const auto setpoint = uss_section(config).speeds.find(fastest);
  double nominal_mps = 1.0;
  if (decel != config.travel.dcp3_decel_distance_mm.end() &&
      setpoint != uss_section(config).speeds.end()) {
    const double braking_m = std::max(0.2, decel->second / 1000.0 - kSimCrawlApproachM);
    const double fraction = setpoint->second / uss_section(config).full_scale;
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
  return apply_sim(kUssSimActionTable, request, board_, now, shared, own,
                   [this] { return state_json_locked(); });
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

}  // namespace liftd::daemon
