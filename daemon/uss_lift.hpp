// The daemon's USS lift (drive.kind "uss"): the USS master and the lift controller on the USS
// runner's real-time thread, the API backend over them and, with --simulate, the simulated USS
// slaves (the lift drive with its car, and every other configured slave) on the far end of a
// pseudo-terminal. The DCP lift is lift_app.*, the hydraulic one hydraulic_lift.*; drives.*
// picks one by drive.kind.
#pragma once

#include <atomic>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <asio.hpp>

#include "api/backend.hpp"
#include "api/server.hpp"
#include "config/config.hpp"
#include "daemon/daemon.hpp"
#include "daemon/drives.hpp"
#include "daemon/lift_common.hpp"
#include "daemon/lift_core.hpp"
#include "io/pty.hpp"
#include "lift/position_source.hpp"
#include "rt/uss_runner.hpp"
#include "sim/sim_io.hpp"
#include "sim/uss_slave_sim.hpp"
#include "uss/drive/controller.hpp"
#include "uss/master/master.hpp"

namespace liftd::daemon {

/// The USS master's settings from the configuration (uss.*).
uss::MasterConfig uss_master_config(const config::Config& config);
/// The USS lift controller's settings from the configuration (uss.*, travel.*, floors).
uss::UssControllerConfig uss_controller_config(const config::Config& config);

/// The simulated USS bus (liftd --simulate, drive.kind "uss") on its own thread: one simulated
/// slave per configured address (the drive moves a car; the others only answer), speaking 8E1
/// telegrams on the master end of a pseudo-terminal; the simulated I/O board.
class SimulatedUssBus {
 public:
  /// Creates the pseudo-terminal; throws std::runtime_error when it cannot.
  explicit SimulatedUssBus(const config::Config& config);
  ~SimulatedUssBus();
  SimulatedUssBus(const SimulatedUssBus&) = delete;
  SimulatedUssBus& operator=(const SimulatedUssBus&) = delete;

  /// The device the master opens (the pseudo-terminal's slave end).
  const std::string& device_path() const { return pty_->slave_path(); }
  bool start();
  void stop();
  /// The simulated encoder on the car (lock-free).
  const lift::PositionSource& position() const { return encoder_; }
  /// The simulated I/O board's inputs now (io thread).
  lift::Inputs inputs(MonoTime now);
  /// A `sim` request; the result is state_json() after it.
  api::Result apply(const api::SimRequest& request, MonoTime now);
  nlohmann::json state_json() const;
  /// Journals what the slaves saw the master do against the USS specification (io thread).
  void log_violations();

 private:
  void loop();
  void serve(MonoTime now);  ///< with mutex_ held
  nlohmann::json state_json_locked() const;
  sim::UssSlaveSim& drive() { return *bus_->slave(drive_address_); }
  const sim::UssSlaveSim& drive() const { return *bus_->slave(drive_address_); }

  std::uint32_t baud_;
  std::uint8_t drive_address_;
  int priority_;  ///< SCHED_FIFO priority of the bus thread, one below the master's
  std::unique_ptr<io::PtyPair> pty_;
  io::SerialPort port_;                  ///< the pseudo-terminal's master end
  mutable std::mutex mutex_;             ///< guards bus_ and board_ (sim thread and io)
  std::unique_ptr<sim::UssBusSim> bus_;  ///< one simulated slave per configured address
  SimulatedBoard board_;
  SimulatedEncoder encoder_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

/// api::Backend over the USS lift controller.
class UssBackend final : public api::Backend {
 public:
  UssBackend(const config::Config& config, uss::UssController& controller, rt::UssRunner& runner,
             uss::Master& master, lift::PositionFeed* position_feed, SimulatedUssBus* sim);

  drive::Kind drive_kind() const override { return drive::Kind::Uss; }
  api::StatusSnapshot status() override;
  api::StatsSnapshot stats() override;
  std::vector<api::TraceEntry> trace(std::size_t max_entries) override;
  api::DisplaySnapshot display() override { return {}; }
  nlohmann::json config() override;
  // Not offered by this drive kind: the dispatcher refuses them before they get here.
  void key(int, api::Responder done) override { not_offered(done); }
  void power(api::PowerSetting, api::Responder done) override { not_offered(done); }
  void load(int, api::Responder done) override { not_offered(done); }
  void drive_reset(api::Responder done) override;
  void update_inputs(const api::InputUpdate& update, api::Responder done) override;
  void travel(const api::TravelArgs& args, api::Responder done) override;
  void stop(api::Responder done) override;
  void relevel(api::Responder done) override;
  void inspection(bool on, const std::string& direction, api::Responder done) override;
  void calls(const std::string& action, std::optional<int> floor, api::Responder done) override;
  void sim(const api::SimRequest& request, api::Responder done) override;
  void parameter(const api::ParameterArgs& args, api::Responder done) override;
  void mirror(std::optional<int> address, api::Responder done) override;

  /// Io thread: replies to their clients, requests the USS thread never answered time out.
  void poll(MonoTime now);
  /// A sample of the simulated machine's inputs (--simulate), sent on with the API's shaft
  /// signals (MachineInputs).
  void simulated_inputs(const lift::Inputs& sample);
  bool send_shutdown(bool force);
  std::chrono::system_clock::time_point wall_time(MonoTime at) const;

 private:
  /// What a reply must turn into: the parameter request's arguments for its result.
  struct ParameterContext {
    api::ParameterArgs args;
    std::uint8_t address = 0;
    uss::PkwLength length = uss::PkwLength::Four;
  };
  static void not_offered(api::Responder& done);
  void send(uss::CommandBody body, api::Responder done);
  void send_inputs(const lift::Inputs& inputs);
  /// The configured slave at `address`: its PKW length, or nullopt when it is not on the bus.
  std::optional<uss::PkwLength> pkw_length(std::uint8_t address) const;
  api::Result parameter_result(const ParameterContext& context, const uss::PkwResult& r) const;

  const config::Config& config_;
  uss::UssController& controller_;
  rt::UssRunner& runner_;
  uss::Master& master_;  ///< its configuration only (the runner's thread owns the rest)
  SimulatedUssBus* sim_;
  MachineInputs inputs_;  ///< the API's and the simulated machine's inputs
  PendingReplies pending_;
  std::map<std::uint32_t, ParameterContext> parameter_requests_;
  MonoTime mono_at_start_{};
  std::chrono::system_clock::time_point wall_at_start_{};
};

/// The USS lift as one piece, registered with the daemon.
class UssLift final : public LiftRunner {
 public:
  UssLift(Daemon& daemon, const config::Config& config, bool simulate);
  ~UssLift() override;
  const std::string& socket_path() const override { return socket_path_; }

 private:
  bool start_runner();
  void stop_runner();
  void poll();
  void handle_event(const uss::ControllerEvent& event);
  void wind_down(std::function<void()> done);

  Daemon& daemon_;
  const config::Config& config_;
  bool simulate_;
  std::string socket_path_;
  std::unique_ptr<SimulatedUssBus> sim_;
  std::unique_ptr<lift::PositionFeed> position_feed_;
  std::unique_ptr<uss::Master> master_;
  std::unique_ptr<uss::UssController> controller_;
  std::unique_ptr<rt::UssRunner> runner_;
  std::unique_ptr<UssBackend> backend_;
  std::unique_ptr<api::Server> server_;
  PollTimer poll_timer_;
  StatePublisher publisher_;
  MonoTime last_sim_inputs_{};
  WindDown wind_down_;
};

}  // namespace liftd::daemon
