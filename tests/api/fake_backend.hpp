// A scripted Backend for the API tests, the fuzz targets and the benchmark: the common commands
// (lib/api) on a lift of any drive kind. Its status at rest is a DCP lift's (StatusSnapshot's
// default kind), as JSON; a test sets another kind in status_snapshot. A kind's own commands are
// known to every dispatcher (the registry adds them) and served by the kind's fake in its own
// tests, which derives from this one (tests/dcp/api/fake_dcp_backend.hpp,
// tests/uss/api/fake_uss_backend.hpp); this fake serves none of them.
#pragma once

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "api/backend.hpp"
#include "api/commands.hpp"
#include "api/dispatcher.hpp"
#include "kinds/commands.hpp"

namespace liftd::api::testing {

/// Answers from fixed snapshots; control commands succeed, fail with `control_result`, or are
/// held in `deferred` until the test answers them.
class FakeBackend : public Backend {
 public:
  FakeBackend() {
    status_snapshot.drive_state = drive::State::Ready;
    status_snapshot.link = LinkState::Up;
    status_snapshot.details = {{"mode", "DCP4"},
                               {"status", ready_status()},
                               {"extended", quiet_extended_status()},
                               {"handshake_problem", nullptr}};
    status_snapshot.position_mm = 3000;
    status_snapshot.floor = 1;
    status_snapshot.rt = RtInfo{true, "SCHED_FIFO", 80, true};
    config_json = {{"serial", {{"device", "/dev/ttyS1"}}}};
  }

  /// The S0..S7 object of a DCP drive that is ready (S0 only).
  static nlohmann::json ready_status() {
    nlohmann::json j = nlohmann::json::object();
    for (const char* bit : {"ready", "travel_active", "advance_warning", "general_fault",
                            "below_levelling", "accepted", "brake_open", "message_error"}) {
      j[bit] = false;
    }
    j["ready"] = true;
    return j;
  }
  /// A DCP extended status with every bit 0.
  static nlohmann::json quiet_extended_status() {
    nlohmann::json j = nlohmann::json::object();
    for (const char* bit : {"below_unlocking_speed", "below_border_speed", "below_overspeed",
                            "emergency_reduced_voltage", "emergency_direction_down",
                            "motor_temperature_limit", "drive_temperature_limit"}) {
      j[bit] = false;
    }
    j["weight_bits"] = 0;
    return j;
  }

  drive::Kind drive_kind() const override { return status_snapshot.drive_kind; }
  StatusSnapshot status() override { return status_snapshot; }
  StatsSnapshot stats() override { return stats_snapshot; }
  std::vector<TraceEntry> trace(std::size_t max_entries) override {
    const std::size_t n = std::min(max_entries, trace_entries.size());
    return {trace_entries.end() - static_cast<std::ptrdiff_t>(n), trace_entries.end()};
  }
  Result travels(std::size_t last) override {
    travels_asked = last;
    return Result::ok(travels_result);
  }
  nlohmann::json config() override { return config_json; }
  void drive_reset(Responder done) override {
    answer("drive_reset", Result::ok(), std::move(done));
  }
  void calls(const CallsArgs& args, Responder done) override {
    std::string call = "calls " + args.action;
    if (args.floor) call += " " + std::to_string(*args.floor);
    if (args.position) call += " @" + std::to_string(*args.position);
    for (const int floor : args.floors) call += " " + std::to_string(floor);
    // No travel control unless the test says what control commands answer.
    answer(std::move(call), Result::fail(ErrorCode::NotReady, kNoTravelControl), std::move(done));
  }
  void update_inputs(const InputUpdate& update, Responder done) override {
    update.apply_to(inputs_state);
    answer("inputs", Result::ok(to_json(inputs_state)), std::move(done));
  }

  StatusSnapshot status_snapshot;         ///< what status() returns
  StatsSnapshot stats_snapshot;           ///< what stats() returns
  std::vector<TraceEntry> trace_entries;  ///< what trace() picks from
  nlohmann::json travels_result = {{"travels", nlohmann::json::array()}, {"dropped_samples", 0}};
  std::size_t travels_asked = 0;           ///< the `last` travels() was called with
  nlohmann::json config_json;              ///< what config() returns
  Inputs inputs_state;                     ///< updated by update_inputs()
  std::optional<Result> control_result;    ///< set: control commands answer this
  bool defer = false;                      ///< true: hold control responders in `deferred`
  std::vector<Responder> deferred;         ///< held responders
  std::vector<std::string> requests_seen;  ///< control requests seen, e.g. "drive_reset"

 protected:
  /// How a travel command is refused: this fake has no travel control (as the defaults of the
  /// common travel commands).
  static constexpr const char* kNoTravelControl = "this daemon has no travel control for its drive";

  /// A control request: noted in requests_seen as `call`, then answered with control_result if
  /// the test set one, else `fallback`, or held in `deferred`.
  void answer(std::string call, Result fallback, Responder done) {
    requests_seen.push_back(std::move(call));
    if (defer) {
      deferred.push_back(std::move(done));
      return;
    }
    done(control_result ? *control_result : std::move(fallback));
  }
};

/// A connection that only runs requests: no event stream, one request in flight.
class QuietSession : public SessionControl {
 public:
  void set_watching(bool) override {}
  bool watching() const override { return false; }
  void send_event(std::string) override {}
  std::size_t requests_in_flight() const override { return 1; }
};

/// Every drive kind's own commands and `sim` on `dispatcher`, served by `backend` (a kind's own
/// only by that kind's fake), as the daemon's registry of drive kinds adds them to a lift's
/// server.
inline void add_drive_kind_commands(Dispatcher& dispatcher, FakeBackend& backend) {
  kinds::add_drive_kind_commands(dispatcher, backend);
}

/// Every command of the daemon on `dispatcher`: the common ones and every drive kind's own.
inline void add_every_command(Dispatcher& dispatcher, FakeBackend& backend) {
  add_builtin_commands(dispatcher, backend);
  add_drive_kind_commands(dispatcher, backend);
}

}  // namespace liftd::api::testing
