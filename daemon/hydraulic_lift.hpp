// The daemon's hydraulic lift (drive.kind "sch001"): the SCH001 controller on its CAN runner, the
// API backend over it, and with --simulate the simulated card, hydraulic car and I/O board on the
// other end of a socketpair. The DCP lift is lift_app.*; drives.* picks one by drive.kind.
#pragma once

#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include <asio.hpp>

#include "api/backend.hpp"
#include "api/server.hpp"
#include "can/socket.hpp"
#include "config/config.hpp"
#include "daemon/daemon.hpp"
#include "daemon/drives.hpp"
#include "daemon/lift_common.hpp"
#include "daemon/lift_core.hpp"
#include "lift/position_source.hpp"
#include "rt/can_runner.hpp"
#include "rt/encoder_tap.hpp"
#include "sch001/controller.hpp"
#include "sim/sch001_card_sim.hpp"
#include "sim/sim_io.hpp"

namespace liftd::daemon {

/// The SCH001 controller's settings from the configuration; throws std::invalid_argument when
/// the card identifiers do not fit (config validation refuses that first).
sch001::ControllerConfig sch001_controller_config(const config::Config& config);

/// The simulated card and hydraulic car (liftd --simulate, drive.kind "sch001") on its own
/// thread, speaking CAN frames over one end of a socketpair; the simulated I/O board.
class SimulatedCard {
 public:
  SimulatedCard(const config::Config& config, can::CanSocket card_end);
  ~SimulatedCard();
  SimulatedCard(const SimulatedCard&) = delete;
  SimulatedCard& operator=(const SimulatedCard&) = delete;

  bool start();
  void stop();
  /// The simulated encoder on the car (lock-free).
  const lift::PositionSource& position() const { return encoder_; }
  /// The simulated I/O board's inputs now (io thread).
  lift::Inputs inputs(MonoTime now);
  /// A `sim` request; the result is state_json() after it.
  api::Result apply(const api::SimRequest& request, MonoTime now);
  nlohmann::json state_json() const;
  /// Logs what the card saw the controller do against its document (io thread).
  void log_violations();

 private:
  void loop();
  nlohmann::json state_json_locked() const;  ///< state_json() with mutex_ held

  can::CanSocket socket_;
  mutable std::mutex mutex_;  ///< guards card_, board_ and bus_off_ (the simulator's thread and io)
  sim::Sch001CardSim card_;
  SimulatedBoard board_;
  SimulatedEncoder encoder_;
  bool bus_off_ = false;  ///< inject one bus-off error frame (then back to normal)
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

/// api::Backend over the SCH001 controller.
class Sch001Backend final : public api::Backend {
 public:
  Sch001Backend(const config::Config& config, sch001::Sch001Controller& controller,
                rt::CanRunner& runner, lift::PositionFeed* position_feed, SimulatedCard* sim);

  drive::Kind drive_kind() const override { return drive::Kind::Sch001; }
  api::StatusSnapshot status() override;
  api::StatsSnapshot stats() override;
  std::vector<api::TraceEntry> trace(std::size_t max_entries) override;
  api::DisplaySnapshot display() override { return {}; }
  nlohmann::json config() override;
  // Not offered by this drive kind: the dispatcher refuses them before they get here.
  void key(int, api::Responder done) override { not_offered(done); }
  void drive_reset(api::Responder done) override { not_offered(done); }
  void power(api::PowerSetting, api::Responder done) override { not_offered(done); }
  void load(int, api::Responder done) override { not_offered(done); }
  void update_inputs(const api::InputUpdate& update, api::Responder done) override;
  void travel(const api::TravelArgs& args, api::Responder done) override;
  void stop(api::Responder done) override;
  void relevel(api::Responder done) override;
  void inspection(bool on, const std::string& direction, api::Responder done) override;
  void calls(const std::string& action, std::optional<int> floor, api::Responder done) override;
  void sim(const api::SimRequest& request, api::Responder done) override;

  /// Io thread: replies to their clients, requests the CAN thread never answered time out.
  void poll(MonoTime now);
  /// A sample of the simulated machine's inputs (--simulate), sent on with the API's shaft
  /// signals (MachineInputs).
  void simulated_inputs(const lift::Inputs& sample);
  bool send_shutdown(bool force);
  std::chrono::system_clock::time_point wall_time(MonoTime at) const;

 private:
  static void not_offered(api::Responder& done);
  void send(sch001::CommandBody body, api::Responder done);
  void send_inputs(const lift::Inputs& inputs);

  const config::Config& config_;
  sch001::Sch001Controller& controller_;
  rt::CanRunner& runner_;
  SimulatedCard* sim_;
  MachineInputs inputs_;  ///< the API's and the simulated machine's inputs
  PendingReplies pending_;
  MonoTime mono_at_start_{};
  std::chrono::system_clock::time_point wall_at_start_{};
};

/// The hydraulic lift as one piece, registered with the daemon.
class HydraulicLift final : public LiftRunner {
 public:
  HydraulicLift(Daemon& daemon, const config::Config& config, bool simulate);
  ~HydraulicLift() override;
  const std::string& socket_path() const override { return socket_path_; }

 private:
  /// Warns when the CAN interface is missing, down or not at 125 kbit/s (card document 3a).
  void check_interface() const;
  bool start_runner();
  void stop_runner();
  void poll();
  void handle_event(const sch001::ControllerEvent& event);
  void wind_down(std::function<void()> done);

  Daemon& daemon_;
  const config::Config& config_;
  bool simulate_;
  std::string socket_path_;
  std::unique_ptr<SimulatedCard> sim_;
  std::unique_ptr<lift::PositionFeed> position_feed_;
  std::unique_ptr<can::CanEncoder> encoder_;  ///< position.source "can"
  std::unique_ptr<sch001::Sch001Controller> controller_;
  std::unique_ptr<rt::EncoderTap> tap_;  ///< encoder frames to the encoder, the rest on
  std::unique_ptr<rt::CanRunner> runner_;
  std::unique_ptr<Sch001Backend> backend_;
  std::unique_ptr<api::Server> server_;
  PollTimer poll_timer_;
  StatePublisher publisher_;
  MonoTime last_sim_inputs_{};
  sch001::CardLinkCounters logged_counters_{};
  MonoTime last_reject_log_{};
  WindDown wind_down_;
};

}  // namespace liftd::daemon
