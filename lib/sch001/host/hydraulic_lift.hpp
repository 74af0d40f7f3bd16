// The daemon's hydraulic lift (drive.kind "sch001"): the SCH001 controller on its CAN runner, the
// API backend over it, and with --simulate the simulated card, hydraulic car and I/O board on the
// other end of a socketpair. The DCP lift is lib/dcp/host/dcp_lift.*; lib/kinds/lifts.cpp picks one
// by drive.kind.
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
#include "common/position_source.hpp"
#include "config/config.hpp"
#include "host/controller_lift.hpp"
#include "host/host.hpp"
#include "host/lift_common.hpp"
#include "host/lift_core.hpp"
#include "log/throttle.hpp"
#include "rt/can_runner.hpp"
#include "rt/encoder_tap.hpp"
#include "sch001/config/section.hpp"
#include "sch001/controller.hpp"
#include "sch001/sim/sch001_card_sim.hpp"
#include "sim/sim_io.hpp"

namespace liftd::daemon {

/// The SCH001 controller's settings from the configuration; throws std::invalid_argument when
/// the card identifiers do not fit (config validation refuses that first).
sch001::ControllerConfig sch001_controller_config(const config::Config& config);

/// The simulated card and hydraulic car (liftd --simulate, drive.kind "sch001") on its own
/// thread, listening for the controller on a Unix socket as `sch001-sim --socket` does (liftd
/// opens it as can.interface "unix:PATH", and reopens it as it would a real bus); the
/// simulated I/O board.
class SimulatedCard final : public SimulatorThread {
 public:
  /// Listens on `socket_path` (replacing a stale file); throws std::runtime_error if it cannot.
  SimulatedCard(const config::Config& config, const std::string& socket_path);
  ~SimulatedCard();

  bool start();
  void stop();
  /// A `sim` request; the result is state_json() after it.
  api::Result apply(const api::SimRequest& request, MonoTime now);
  /// Logs what the card saw the controller do against its document (io thread).
  void log_violations();

 private:
  void loop();
  nlohmann::json state_json_locked() const override;

  std::string socket_path_;
  int listener_ = -1;
  std::optional<can::CanSocket> peer_;  ///< the controller's connection (simulator's thread)
  sch001::sim::Sch001CardSim card_;     ///< guarded by mutex_
  bool bus_off_ = false;  ///< inject one bus-off error frame (then back to normal; mutex_)
  bool drop_ = false;     ///< close the controller's connection once (mutex_)
};

/// The SCH001 card's lift as controller_lift.hpp names its parts.
struct Sch001Drive : DriveParts<sch001::Sch001Controller, rt::CanRunner, SimulatedCard> {
  /// The CAN thread answers within a tick: 3 s catches a stall. After a forced end it sends the
  /// card three answers without a signal (100 ms apart, card document 3b).
  static constexpr DriveFacts kFacts{drive::Kind::Sch001, "CAN", std::chrono::seconds(3),
                                     std::chrono::milliseconds(300), &sch001::kFaultTexts};
  /// The command byte's bits (3c) and the card status byte's (3b), as status names them.
  static TravelBitNames travel_bit_names();
  /// A learning leg's limit is the motor run-time limiter's plus the slow run's allowance.
  static std::uint32_t learn_leg_base_ms(const config::Config& config) {
    return static_cast<std::uint32_t>(sch001_section(config).max_travel_ms);
  }
};

/// api::Backend over the SCH001 controller.
class Sch001Backend final : public ControllerBackend<Sch001Drive> {
 public:
  using ControllerBackend::ControllerBackend;

  api::StatusSnapshot status() override;
  api::StatsSnapshot stats() override;
  std::vector<api::TraceEntry> trace(std::size_t max_entries) override;
  // Not offered by this drive kind: the dispatcher refuses it before it gets here.
  void drive_reset(api::Responder done) override { not_offered(done); }
  void travel(const api::TravelArgs& args, api::Responder done) override;
};

/// The hydraulic lift as one piece, registered with the daemon.
class HydraulicLift final : public ControllerLift<Sch001Drive> {
 public:
  HydraulicLift(Host& daemon, const config::Config& config, bool simulate);
  ~HydraulicLift() override;

 private:
  /// Warns when the CAN interface is missing, down or not at 125 kbit/s (card document 3a).
  void before_start() override;
  void journal_started() override;
  void handle_event(const sch001::ControllerEvent& event) override;
  /// What the controller counts instead of queueing (card status changes, error frames,
  /// frames on our identifier, rejected frames, failed sends), journalled through throttles.
  void after_events(MonoTime now) override;
  void journal_card_status(const sch001::ControllerSnapshot& s, MonoTime now);
  void journal_bus_errors(const sch001::ControllerSnapshot& s, MonoTime now);
  void journal_link_conditions(const sch001::ControllerSnapshot& s);
  void journal_endpoint(bool up, MonoTime now);

  std::unique_ptr<can::CanEncoder> encoder_;  ///< position.source "can"
  std::unique_ptr<rt::EncoderTap> tap_;       ///< encoder frames to the encoder, the rest on
  sch001::CardLinkCounters logged_counters_{};
  MonoTime last_reject_log_{};
  log::Throttle card_status_lines_;
  log::Throttle bus_error_lines_;
  bool foreign_sender_logged_ = false;
  bool send_failing_logged_ = false;
  /// A lost endpoint: from its first failure until the card is heard on a new one.
  std::optional<MonoTime> lost_since_;
  std::uint64_t lost_failures_ = 0;
};

}  // namespace liftd::daemon
