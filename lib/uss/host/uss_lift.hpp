// The daemon's USS lift (drive.kind "uss"): the USS master and the lift controller on the USS
// runner's real-time thread, the API backend over them and, with --simulate, the simulated USS
// slaves (the lift drive with its car, and every other configured slave) on the far end of a
// pseudo-terminal. The DCP lift is lib/dcp/host/dcp_lift.*, the hydraulic one
// lib/sch001/host/hydraulic_lift.*; lib/kinds/lifts.cpp picks one by drive.kind.
#pragma once

#include <atomic>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <asio.hpp>

#include "api/backend.hpp"
#include "api/server.hpp"
#include "common/position_source.hpp"
#include "config/config.hpp"
#include "host/controller_lift.hpp"
#include "host/host.hpp"
#include "host/lift_common.hpp"
#include "host/lift_core.hpp"
#include "io/pty.hpp"
#include "log/throttle.hpp"
#include "sim/sim_io.hpp"
#include "uss/drive/controller.hpp"
#include "uss/host/commands.hpp"
#include "uss/master/master.hpp"
#include "uss/runner/uss_runner.hpp"
#include "uss/sim/uss_slave_sim.hpp"

namespace liftd::daemon {

/// The USS master's settings from the configuration (uss.*).
uss::MasterConfig uss_master_config(const config::Config& config);
/// The USS lift controller's settings from the configuration (uss.*, travel.*, floors).
uss::UssControllerConfig uss_controller_config(const config::Config& config);

/// The simulated USS bus (liftd --simulate, drive.kind "uss") on its own thread: one simulated
/// slave per configured address (the drive moves a car; the others only answer), speaking 8E1
/// telegrams on the master end of a pseudo-terminal; the simulated I/O board.
class SimulatedUssBus final : public SimulatorThread {
 public:
  /// Creates the pseudo-terminal; throws std::runtime_error when it cannot.
  explicit SimulatedUssBus(const config::Config& config);
  ~SimulatedUssBus();

  /// The device the master opens (the pseudo-terminal's slave end).
  const std::string& device_path() const { return pty_->slave_path(); }
  bool start();
  void stop();
  /// A `sim` request; the result is state_json() after it.
  api::Result apply(const api::SimRequest& request, MonoTime now);
  /// Journals what the slaves saw the master do against the USS specification (io thread).
  void log_violations();

 private:
  void loop();
  void serve(MonoTime now);  ///< with mutex_ held
  nlohmann::json state_json_locked() const override;
  uss::sim::UssSlaveSim& drive() { return *bus_->slave(drive_address_); }
  const uss::sim::UssSlaveSim& drive() const { return *bus_->slave(drive_address_); }

  std::uint32_t baud_;
  std::uint8_t drive_address_;
  int priority_;  ///< SCHED_FIFO priority of the bus thread, one below the master's
  std::unique_ptr<io::PtyPair> pty_;
  io::SerialPort port_;  ///< the pseudo-terminal's master end
  std::unique_ptr<uss::sim::UssBusSim>
      bus_;  ///< one simulated slave per configured address (mutex_)
};

/// The USS lift as controller_lift.hpp names its parts.
struct UssDrive : DriveParts<uss::UssController, uss::UssRunner, SimulatedUssBus> {
  /// A parameter request may wait uss.pkw_repeat_limit polls of a long polling list: 30 s only
  /// catches a stalled USS thread. After a forced end, telegrams with OFF2 go out for 300 ms.
  static constexpr DriveFacts kFacts{drive::Kind::Uss, "USS", std::chrono::seconds(30),
                                     std::chrono::milliseconds(300), &uss::kFaultTexts};
  /// The control and status words' bits (C 5.1), as status names them.
  static TravelBitNames travel_bit_names();
  /// A learning leg's limit is the run-time limiter's (the longer of the two a leg has) plus the
  /// crawl's allowance.
  static std::uint32_t learn_leg_base_ms(const config::Config&) {
    return uss::LiftTravelConfig{}.max_travel_ms;
  }
};

/// api::Backend and the USS parameter commands over the USS lift controller.
class UssBackend final : public ControllerBackend<UssDrive>, public UssCommandBackend {
 public:
  UssBackend(const config::Config& config, const config::Schema& schema,
             uss::UssController& controller, uss::UssRunner& runner, uss::Master& master,
             PositionFeed* position_feed, SimulatedUssBus* sim)
      : ControllerBackend(config, schema, controller, runner, position_feed, sim),
        master_(master) {}

  api::StatusSnapshot status() override;
  api::StatsSnapshot stats() override;
  std::vector<api::TraceEntry> trace(std::size_t max_entries) override;
  void drive_reset(api::Responder done) override;
  void travel(const api::TravelArgs& args, api::Responder done) override;

  // ---- UssCommandBackend ----
  void parameter(const ParameterArgs& args, api::Responder done) override;
  void mirror(std::optional<int> address, api::Responder done) override;

 private:
  /// What a reply must turn into: the parameter request's arguments for its result.
  struct ParameterContext {
    ParameterArgs args;
    std::uint8_t address = 0;
    uss::PkwLength length = uss::PkwLength::Four;
  };
  /// The configured slave at `address`: its PKW length, or nullopt when it is not on the bus.
  std::optional<uss::PkwLength> pkw_length(std::uint8_t address) const;
  api::Result parameter_result(const ParameterContext& context, const uss::PkwResult& r) const;

  uss::Master& master_;  ///< its configuration only (the runner's thread owns the rest)
};

/// The USS lift as one piece, registered with the daemon.
class UssLift final : public ControllerLift<UssDrive> {
 public:
  UssLift(Host& daemon, const config::Config& config, bool simulate);
  ~UssLift() override;

 private:
  /// The serial device's driver and settings, a USB adapter's latency timer.
  void before_start() override;
  void journal_started() override;
  void handle_event(const uss::ControllerEvent& event) override;
  /// The count of drive state lines the throttle held back, once its interval ends.
  void after_events(MonoTime now) override;

  std::unique_ptr<uss::Master> master_;
  /// A status word flapping at the bus's rate: at most a few lines per interval, then a count.
  log::Throttle drive_state_lines_{5, std::chrono::seconds(10)};
  uss::ProfileState last_drive_state_{};
  // A slave's link flapping (answers / does not send) likewise: a few lines in full, then a count.
  log::Throttle link_lines_{5, std::chrono::seconds(10)};
  std::string last_link_line_;
};

}  // namespace liftd::daemon
