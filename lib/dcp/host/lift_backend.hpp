// The API's view of the lift: turns DcpController snapshots into API results and API requests
// into controller commands, matching each reply to its waiting client by tag. Runs on the io
// thread only; the controller is reached through its lock-free queues.
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <string_view>

#include "api/backend.hpp"
#include "api/dispatcher.hpp"
#include "config/config.hpp"
#include "dcp/control/dcp_controller.hpp"
#include "dcp/host/commands.hpp"
#include "dcp/host/dcp_status.hpp"
#include "host/lift_common.hpp"
#include "host/lift_core.hpp"
#include "host/trace_files.hpp"
#include "host/travel_log.hpp"
#include "rt/cycle_runner.hpp"

namespace liftd::daemon {

class SimulatedLift;

/// api::Backend and the DCP commands over a DcpController and its CycleRunner.
class LiftBackend final : public api::Backend, public DcpCommandBackend {
 public:
  /// `position_feed` is written by `inputs` when position.source is "api" (else nullptr);
  /// `sim` is the simulated lift with --simulate (else nullptr: the `sim` command is refused).
  LiftBackend(const config::Config& config, const config::Schema& schema,
              control::DcpController& controller, rt::CycleRunner& runner,
              control::PositionFeed* position_feed, std::string runtime_dir, SimulatedLift* sim);

  // ---- api::Backend ----
  drive::Kind drive_kind() const override { return drive::Kind::Dcp; }
  api::StatusSnapshot status() override;
  api::StatsSnapshot stats() override;
  std::vector<api::TraceEntry> trace(std::size_t max_entries) override;
  api::Result save_trace() override;
  api::Result travels(std::size_t last) override;
  nlohmann::json config() override;
  void drive_reset(api::Responder done) override;
  void update_inputs(const api::InputUpdate& update, api::Responder done) override;

  void travel(const api::TravelArgs& args, api::Responder done) override;
  void stop(api::Responder done) override;
  void relevel(api::Responder done) override;
  void inspection(bool on, const std::string& direction, api::Responder done) override;
  void calls(const std::string& action, std::optional<int> floor, api::Responder done) override;
  void learn(api::Responder done) override;
  /// Called with each learning travel's result (the lift reports it to the journal and watchers).
  void set_learn_listener(std::function<void(const nlohmann::json&)> listener) {
    learn_listener_ = std::move(listener);
  }
  /// Served by the process's SimulatedLift (liftd --simulate); refused without one.
  void sim(const api::SimRequest& request, api::Responder done) override;

  // ---- DcpCommandBackend ----
  DisplaySnapshot display() override;
  void key(int button, api::Responder done) override;
  void power(PowerSetting setting, api::Responder done) override;
  void load(int percent, api::Responder done) override;
  void fast_stop(api::Responder done) override;
  void fast_start(const std::string& action, const api::TravelArgs& args,
                  api::Responder done) override;

  /// Io thread, every few ms: hands controller replies to their waiting clients and times out
  /// requests the cycle never answered (it stopped).
  void poll(MonoTime now);
  /// A sample of the simulated machine's inputs (--simulate): goes to the cycle with the API's
  /// shaft signals (MachineInputs).
  void simulated_inputs(const lift::Inputs& sample);
  /// Service stop: no new travel, the running one stops at the next possible floor; `force`
  /// withdraws drive enable at once. False when the command queue was full (send again).
  bool send_shutdown(bool force);
  /// Sends the wall clock to the cycle for I3.
  void send_clock(std::chrono::system_clock::time_point now);

  /// Writes the flight recorder, decoded, to `<runtime dir>/liftd-trace-<UTC time>.txt` and logs
  /// it with `why`. Returns the path and record count, or the error text.
  api::Result write_flight_recorder(std::string_view why);

  /// A travel that finished or was aborted at `at` ends its curve (`travels`).
  void record_travel_end(MonoTime at, bool aborted, lift::Cause cause);

  /// Wall-clock time of a monotonic instant (for fault "since" fields).
  std::chrono::system_clock::time_point wall_time(MonoTime at) const;

 private:
  using Pending = PendingReplies<control::CommandReply>;

  /// Posts a command; an ok reply answers through `complete` (none: reply_result).
  void send(control::CommandBody body, api::Responder done, Pending::Completion complete = {});
  void send_inputs(const lift::Inputs& inputs);

  const config::Config& config_;
  const config::Schema& schema_;  ///< the configuration file's, for the `config` dump
  control::DcpController& controller_;
  rt::CycleRunner& runner_;
  FlightRecorderFiles flight_recorder_;  ///< its files in the runtime directory
  SimulatedLift* sim_;                   ///< the simulated lift (liftd --simulate), else nullptr
  MachineInputs inputs_;                 ///< the API's and the simulated machine's inputs
  DcpStatusFacts dcp_facts_{};           ///< what dcp_details_ was built from
  api::SharedJson dcp_details_{dcp_status_json({})};  ///< status.dcp, shared by the snapshots
  Pending pending_;                                   ///< requests waiting for the cycle's reply
  TravelLog travel_log_;  ///< the last travels and their curves (`travels`)
  std::function<void(const nlohmann::json&)> learn_listener_;
  MonoTime mono_at_start_{};
  std::chrono::system_clock::time_point wall_at_start_{};
};

}  // namespace liftd::daemon
