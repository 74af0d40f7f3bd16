#include "daemon/simulated_lift.hpp"

#include <cmath>
#include <stdexcept>
#include <vector>

#include "log/log.hpp"
#include "travel/types.hpp"

namespace liftd::daemon {

/// The drive simulator's car position as the cycle's absolute encoder. A position older than
/// `kMaxAge` means the simulator stalled: the encoder reports invalid, as a real one would.
class SimulatedLift::Encoder final : public control::PositionSource {
 public:
  explicit Encoder(const sim::SerialDriveRunner& drive) : drive_(drive) {}
  std::optional<std::int64_t> position_mm(MonoTime now) const noexcept override {
    if (now - drive_.position_at() > kMaxAge) return std::nullopt;
    return std::llround(drive_.position_mm());
  }

 private:
  static constexpr MonoTime kMaxAge = std::chrono::milliseconds(200);
  const sim::SerialDriveRunner& drive_;
};

namespace {

sim::SimIoConfig io_config(const config::Config& c) {
  sim::SimIoConfig out;
  if (!c.floors.empty()) {
    out.shaft_bottom_mm = c.floors.front().level_mm;
    out.shaft_top_mm = c.floors.back().level_mm;
  }
  return out;
}

}  // namespace

SimulatedLift::SimulatedLift(const config::Config& config) : io_(io_config(config), mono_now()) {
  io::SerialSettings settings;  // DCP 7.1: 38400 8N1 (a pty ignores the rate)
  auto pair = io::PtyPair::create(settings, true);
  if (!pair) throw std::runtime_error("simulated drive: " + pair.error().message());
  pty_ = std::make_unique<io::PtyPair>(std::move(pair).value());
  device_path_ = pty_->slave_path();

  sim::DriveConfig drive;
  drive.protocol = config.sim.dcp == 3 ? dcp::Protocol::Dcp3 : dcp::Protocol::Dcp4;
  if (!config.floors.empty()) drive.start_position_mm = config.floors.front().level_mm;
  for (const auto& [name, mm] : config.travel.dcp3_decel_distance_mm) {
    if (auto speed = dcp::speed_from_string(name)) {
      drive.dcp3_decel_mm[travel::speed_index(*speed)] = static_cast<std::uint32_t>(mm);
    }
  }
  sim::RunnerOptions options;
  options.fd = pty_->take_master().release();
  drive_ = std::make_unique<sim::SerialDriveRunner>(drive, options);
  position_ = std::make_unique<Encoder>(*drive_);
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
  drive_->stop();
}

lift::Inputs SimulatedLift::inputs(MonoTime now) {
  const double v = drive_->velocity_mps();
  io_.set_car(std::abs(v) > 0.001, drive_->position_mm(), now);
  return io_.inputs(now);
}

void SimulatedLift::log_events() {
  std::vector<std::string> lines;
  drive_->drain_event_lines(lines);
  for (const auto& line : lines) log::write(log::Level::debug, "sim", line);
}

}  // namespace liftd::daemon
