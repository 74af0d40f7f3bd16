#include "dcp/host/simulated_lift.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <optional>
#include <stdexcept>
#include <utility>
#include <vector>

#include "dcp/host/sim_actions.hpp"
#include "dcp/travel/types.hpp"
#include "log/log.hpp"

namespace liftd::daemon {

/// The drive simulator's car position as the cycle's absolute encoder. A position older than
/// `kMaxAge` means the simulator stalled: the encoder reports invalid, as a real one would.
///
/// A real encoder is read when asked. The simulator publishes the drive's motion plan each time
/// its loop runs, and this encoder evaluates that plan at `now` (EncoderSample::position_at_mm),
/// so the position is where the drive's own model has the car at that moment however long ago
/// the simulator's thread last ran. Carrying a sampled speed and acceleration forward instead
/// missed the jerk-limited end of a stop by up to 10 mm when that thread was held up on a loaded
/// machine, and the drive refused the distance as implausible.
class SimulatedLift::Encoder final : public control::PositionSource {
 public:
  explicit Encoder(const dcp::sim::SerialDriveRunner& drive) : drive_(drive) {}
  std::optional<std::int64_t> position_mm(MonoTime now) const noexcept override {
    const dcp::sim::EncoderSample sample = drive_.encoder_sample();
    if (now - sample.at > kMaxAge) return std::nullopt;
    return std::llround(sample.position_at_mm(now));
  }

 private:
  static constexpr MonoTime kMaxAge = std::chrono::milliseconds(200);
  const dcp::sim::SerialDriveRunner& drive_;
};

/// The simulated shaft's level switch: the drive's motion plan evaluated at `now`, as the
/// encoder evaluates it, against the shaft's true levels.
class SimulatedLift::ZoneSwitch final : public LevelZoneSource {
 public:
  ZoneSwitch(const dcp::sim::SerialDriveRunner& drive, const sim::SimulatedShaft& shaft)
      : drive_(drive), shaft_(shaft) {}
  bool level_zone(MonoTime now) const noexcept override {
    return shaft_.level_zone(drive_.encoder_sample().position_at_mm(now));
  }

 private:
  const dcp::sim::SerialDriveRunner& drive_;
  sim::SimulatedShaft shaft_;
};

namespace {

// Crawl distance of the simulated DCP3 installation: the drive's SVx is this much shorter than
// the controller's configured deceleration distance.
constexpr int kCrawlApproachMm = 100;

dcp::sim::ReplyFault to_sim(api::SimReplyFault fault) {
  switch (fault) {
    case api::SimReplyFault::NoReply:
      return dcp::sim::ReplyFault::NoReply;
    case api::SimReplyFault::BadChecksum:
      return dcp::sim::ReplyFault::BadChecksum;
    case api::SimReplyFault::S7:
      return dcp::sim::ReplyFault::MessageError;
    case api::SimReplyFault::Late:
      return dcp::sim::ReplyFault::Late;
    case api::SimReplyFault::Garbage:
      return dcp::sim::ReplyFault::Garbage;
  }
  return dcp::sim::ReplyFault::NoReply;
}

dcp::sim::ChannelFault to_sim(SimChannelFault fault) {
  switch (fault) {
    case SimChannelFault::Partial:
      return dcp::sim::ChannelFault::Partial;
    case SimChannelFault::Garbage:
      return dcp::sim::ChannelFault::Garbage;
    case SimChannelFault::Silence:
      return dcp::sim::ChannelFault::Silence;
  }
  return dcp::sim::ChannelFault::Partial;
}

}  // namespace

SimulatedLift::SimulatedLift(const config::Config& config) : board_(config, mono_now()) {
  io::SerialSettings settings;  // DCP 7.1: 38400 8N1 (a pty ignores the rate)
  auto pair = io::PtyPair::create(settings, true);
  if (!pair) throw std::runtime_error("simulated drive: " + pair.error().message());
  pty_ = std::make_unique<io::PtyPair>(std::move(pair).value());
  device_path_ = pty_->slave_path();

  dcp::sim::DriveConfig drive;
  drive.protocol = config.sim.dcp == 3 ? dcp::Protocol::Dcp3 : dcp::Protocol::Dcp4;
  drive.speeds.v0_mps = config.sim.slow_mm_per_s / 1000.0;  // crawl V0 (DCP 10.3)
  if (!config.floors.empty()) drive.start_position_mm = config.floors.front().level_mm;
  for (const auto& [name, mm] : config.travel.dcp3_decel_distance_mm) {
    if (auto speed = dcp::speed_from_string(name)) {
      // DCP 10.1.1: the drive reaches crawl within SVx and the controller positions with B2.
      // As in a real shaft, the deceleration point lies a crawl distance before the drive's
      // ramp ends, so the car arrives at crawl and B2 stops it precisely, whatever a cycle's
      // lateness at full speed.
      const int ramp_mm = mm > 2 * kCrawlApproachMm ? mm - kCrawlApproachMm : mm;
      drive.dcp3_decel_mm[travel::speed_index(*speed)] = static_cast<std::uint32_t>(ramp_mm);
    }
  }
  dcp::sim::RunnerOptions options;
  options.fd = pty_->take_master().release();
  // The simulated drive stands for a separate device that answers on time (DCP 7.2): one step
  // below the cycle's real-time priority where the system permits it, so a loaded machine
  // delays neither the master's frames nor the drive's replies.
  options.priority = std::max(1, config.rt.priority - 1);
  drive_ = std::make_unique<dcp::sim::SerialDriveRunner>(drive, options);
  position_ = std::make_unique<Encoder>(*drive_);
  zone_ = std::make_unique<ZoneSwitch>(*drive_, simulated_shaft(config));
}

const LevelZoneSource& SimulatedLift::level_zone() const {
  return *zone_;
}

SimulatedLift::~SimulatedLift() {
  stop();
}

const control::PositionSource& SimulatedLift::position() const {
  return *position_;
}

bool SimulatedLift::start() {
  if (!drive_->start()) {
    log::event(log::Level::error, "sim", "sim_start_failed", {}, drive_->last_error());
    return false;
  }
  started_ = true;
  log::event(log::Level::info, "sim", "sim_started", {{"device", device_path_}},
             "simulated drive answering on " + device_path_);
  return true;
}

void SimulatedLift::stop() {
  if (!started_) return;
  started_ = false;
  log_violations();
  drive_->stop();
  // What the drive saw, as the drive side of the link: a technician (and the process tests) can
  // tell from this line whether the master left the car to the drive's own link timeout.
  const dcp::sim::RunnerStatus s = drive_->status();
  const bool faulted = (s.status_byte & dcp::status_bit::kGeneralFault) != 0;
  log::event(log::Level::info, "sim", "sim_stopped",
             {{"position_mm", std::to_string(std::llround(s.position_mm))},
              {"violations", std::to_string(s.sim.violations)}},
             "simulated drive stopped: phase " + std::string(dcp::sim::to_string(s.phase)) +
                 ", position " + std::to_string(std::llround(s.position_mm)) + " mm, " +
                 (faulted ? "in fault" : "no fault") + ", " + std::to_string(s.sim.violations) +
                 " spec violation(s) seen");
}

lift::Inputs SimulatedLift::inputs(MonoTime now) {
  const double v = drive_->velocity_mps();
  board_.io().set_car(std::abs(v) > 0.001, drive_->position_mm(), now);
  return board_.io().inputs(now);
}

void SimulatedLift::log_violations() {
  std::vector<std::string> lines;
  drive_->drain_event_lines(lines);
  for (const auto& line : lines) log::write(log::Level::debug, "sim", line);
}

api::Result SimulatedLift::apply(const api::SimRequest& request, MonoTime now) {
  const auto shared = [this, &request](api::SimAction action) -> std::optional<api::Result> {
    using api::SimAction;
    switch (action) {
      case SimAction::GeneralFault:
        general_fault_ = request.on;
        drive_->set_general_fault(request.on);
        break;
      case SimAction::AdvanceWarning:
        advance_warning_ = request.on;
        drive_->set_advance_warning(request.on);
        break;
      case SimAction::NotReady:
        not_ready_ = request.on;
        drive_->set_not_ready(request.on);
        break;
      case SimAction::ReplyFault:
        drive_->inject(to_sim(request.fault), request.frames);
        break;
      case SimAction::ClearReplyFaults:
        drive_->clear_reply_faults();
        break;
      case SimAction::Drift: {
        const dcp::sim::RunnerStatus s = drive_->status();
        // The simulator moves a car only while its drive is idle; a moving car would not drift.
        if (s.phase != dcp::sim::Phase::Idle || std::abs(s.velocity_mps) > 0.0) {
          return api::Result::fail(api::ErrorCode::Busy,
                                   "the car is moving: drift only while the drive is idle");
        }
        drive_->set_position_mm(s.position_mm + request.drift_mm);
        break;
      }
      default:  // the board's actions: SimulatedBoard::apply took them
        break;
    }
    return std::nullopt;
  };
  const auto own = [this, &request](std::size_t) -> std::optional<api::Result> {
    const DcpSimRequest dcp = dcp_sim_request(request);
    switch (dcp.action) {
      case DcpSimAction::ChannelFault:
        drive_->inject_channel(to_sim(dcp.channel));
        break;
      case DcpSimAction::RefuseTarget:
        drive_->refuse_next_target();
        break;
    }
    return std::nullopt;
  };
  return apply_sim(kDcpSimActionTable, request, board_, now, shared, own,
                   [this] { return state_json(); });
}

nlohmann::json SimulatedLift::state_json() const {
  nlohmann::json out = {{"general_fault", general_fault_},
                        {"advance_warning", advance_warning_},
                        {"not_ready", not_ready_},
                        {"position_mm", std::llround(drive_->position_mm())},
                        {"violations", drive_->status().sim.violations},
                        {"implausible", drive_->status().sim.implausible}};
  board_.add_state(out);
  return out;
}

}  // namespace liftd::daemon
