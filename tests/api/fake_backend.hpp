// A scripted Backend for the API tests, the fuzz target and the benchmark: the common commands
// and every drive kind's own (DCP's and USS's: it implements each kind's command backend), so
// one fake serves a lift of any kind. A kind with commands of its own adds its interface here.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "api/backend.hpp"
#include "api/commands.hpp"
#include "api/dispatcher.hpp"
#include "dcp/host/commands.hpp"
#include "kinds/commands.hpp"
#include "uss/host/commands.hpp"

namespace liftd::api::testing {

/// Answers from fixed snapshots; control commands succeed, fail with `control_result`, or are
/// held in `deferred` until the test answers them.
class FakeBackend : public Backend,
                    public daemon::DcpCommandBackend,
                    public daemon::UssCommandBackend {
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
    display_snapshot.lines = {"Speed    0.00 m/s", "Menu 1", "", ""};
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
  daemon::DisplaySnapshot display() override { return display_snapshot; }
  nlohmann::json config() override { return config_json; }
  void key(int button, Responder done) override {
    answer("key " + std::to_string(button), Result::ok(), std::move(done));
  }
  void drive_reset(Responder done) override {
    answer("drive_reset", Result::ok(), std::move(done));
  }
  void parameter(const daemon::ParameterArgs& a, Responder done) override {
    answer("parameter " + std::to_string(a.address.value_or(-1)) + " " + std::to_string(a.pnu) +
               " " + std::string(daemon::kParameterTargets[static_cast<std::size_t>(a.target)]) +
               " " + std::to_string(a.index) +
               (a.write ? " write " + std::to_string(a.value) : "") + (a.dword ? " dword" : "") +
               (a.eeprom ? " eeprom" : ""),
           Result::ok({{"pnu", a.pnu}}), std::move(done));
  }
  void mirror(std::optional<int> address, Responder done) override {
    answer("mirror " + std::to_string(address.value_or(-1)), Result::ok(), std::move(done));
  }
  void power(daemon::PowerSetting setting, Responder done) override {
    answer(std::string("power ") + (setting.emergency ? "emergency " : "mains ") +
               std::to_string(setting.saving),
           Result::ok(daemon::to_json(setting)), std::move(done));
  }
  void load(int percent, Responder done) override {
    answer("load " + std::to_string(percent), Result::ok(), std::move(done));
  }
  void calls(const CallsArgs& args, Responder done) override {
    std::string call = "calls " + args.action;
    if (args.floor) call += " " + std::to_string(*args.floor);
    if (args.position) call += " @" + std::to_string(*args.position);
    for (const int floor : args.floors) call += " " + std::to_string(floor);
    // No travel control unless the test says what control commands answer.
    answer(std::move(call),
           Result::fail(ErrorCode::NotReady, "this daemon has no travel control for its drive"),
           std::move(done));
  }
  // No travel control, as the defaults of the common travel commands.
  void fast_stop(Responder done) override { no_travel(done); }
  void fast_start(const std::string&, const TravelArgs&, Responder done) override {
    no_travel(done);
  }
  void update_inputs(const InputUpdate& update, Responder done) override {
    update.apply_to(inputs_state);
    answer("inputs", Result::ok(to_json(inputs_state)), std::move(done));
  }

  StatusSnapshot status_snapshot;            ///< what status() returns
  StatsSnapshot stats_snapshot;              ///< what stats() returns
  std::vector<TraceEntry> trace_entries;     ///< what trace() picks from
  daemon::DisplaySnapshot display_snapshot;  ///< what display() returns
  nlohmann::json travels_result = {{"travels", nlohmann::json::array()}, {"dropped_samples", 0}};
  std::size_t travels_asked = 0;           ///< the `last` travels() was called with
  nlohmann::json config_json;              ///< what config() returns
  Inputs inputs_state;                     ///< updated by update_inputs()
  std::optional<Result> control_result;    ///< set: control commands answer this
  bool defer = false;                      ///< true: hold control responders in `deferred`
  std::vector<Responder> deferred;         ///< held responders
  std::vector<std::string> requests_seen;  ///< control requests seen, e.g. "load 50"

 private:
  static void no_travel(Responder& done) {
    done(Result::fail(ErrorCode::NotReady, "this daemon has no travel control for its drive"));
  }
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

/// Every drive kind's own commands and `sim` on `dispatcher`, served by `backend`, as the
/// daemon's registry of drive kinds adds them to a lift's server.
inline void add_drive_kind_commands(Dispatcher& dispatcher, FakeBackend& backend) {
  kinds::add_drive_kind_commands(dispatcher, backend);
}

/// Every command of the daemon on `dispatcher`: the common ones and every drive kind's own.
inline void add_every_command(Dispatcher& dispatcher, FakeBackend& backend) {
  add_builtin_commands(dispatcher, backend);
  add_drive_kind_commands(dispatcher, backend);
}

}  // namespace liftd::api::testing
