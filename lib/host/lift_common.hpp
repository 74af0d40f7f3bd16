// What the daemon's lift of every drive kind sets up alike: the runtime directory, the API
// server's configuration and its socket (systemd socket activation), the journal sink of the
// API server, and applying a reloaded configuration to the server.
#pragma once

#include <atomic>
#include <cmath>
#include <cstdint>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <thread>

#include "api/result.hpp"
#include "api/server.hpp"
#include "api/sim.hpp"
#include "can/encoder.hpp"
#include "common/level_zone_source.hpp"
#include "common/position_source.hpp"
#include "config/config.hpp"
#include "lift/inputs.hpp"
#include "lift/lift_model.hpp"
#include "sim/shaft.hpp"
#include "sim/sim_io.hpp"

namespace liftd::daemon {

/// The configuration of `liftd --simulate` without a config file: the defaults, the API socket in
/// $XDG_RUNTIME_DIR (else the current directory) as liftd-sim.sock, no access groups (root and
/// the user who started it may do everything), no memory locking.
config::Config simulation_defaults();

/// systemd's RuntimeDirectory, else the API socket's directory.
std::string default_runtime_dir(const config::Config& config);
/// The API server's configuration, with the socket systemd passed (or -1: created here).
api::ServerConfig api_server_config(const config::Config& config);
/// The settings a reload may change on a running server (groups, limits, timeouts).
api::ServerConfig api_reload_config(const config::Config& config);
/// Where the API server's log lines go (the journal, component "api").
api::LogFn api_log_sink();
/// The CAN encoder's frame format from position.can_* (position.source "can").
can::EncoderFormat encoder_format(const config::Config& config);
/// The machine inputs a backend hands its cycle. On a real lift they are the API's `inputs`
/// (the I/O board's daemon), merged update by update. Under --simulate the simulated machine
/// supplies them, and the API adds what that machine does not model: the shaft signals (level and
/// relevelling zones, every speed's deceleration points), and an end zone or a door reversal from
/// either side. Never a mix in which an API default such as "safety chain open" overrides the
/// simulated machine.
class MachineInputs {
 public:
  /// `feed` takes the API's position (position.source "api"; nullptr otherwise).
  MachineInputs(const config::Config& config, PositionFeed* feed, bool simulated)
      : config_(config), feed_(feed), simulated_(simulated) {}
  /// Takes an `inputs` update (partial updates keep the rest); a refusal, changing nothing, when
  /// it carries a position the configured source does not take.
  std::optional<api::Result> update(const api::InputUpdate& update);
  /// A new sample from the simulated machine (--simulate).
  void simulated_sample(const lift::Inputs& sample) { sample_ = sample; }
  /// What the cycle should see now; nullopt under --simulate before the machine's first sample.
  std::optional<lift::Inputs> current() const;
  /// The `inputs` command's result: the inputs the cycle sees. On a real lift the API's as
  /// merged so far; under --simulate the simulated machine's with the API's shaft signals (an
  /// API value the machine overrides, such as a safety chain it keeps closed, is not shown).
  api::Inputs seen() const;
  /// The `inputs` command of every backend: takes the update, hands `send` what the controller
  /// should see now, and gives the command's result (or the refusal, changing nothing).
  template <typename Send>
  api::Result take(const api::InputUpdate& update, Send&& send) {
    if (auto refused = this->update(update)) return std::move(*refused);
    if (const auto now = current()) send(*now);
    return api::Result::ok(api::to_json(seen()));
  }
  /// A sample of the simulated machine, handed to `send` with the API's shaft signals at once.
  template <typename Send>
  void take_sample(const lift::Inputs& sample, Send&& send) {
    simulated_sample(sample);
    if (const auto now = current()) send(*now);
  }

 private:
  const config::Config& config_;
  PositionFeed* feed_;
  bool simulated_;
  api::Inputs api_{};
  std::optional<lift::Inputs> sample_;
};
/// A simulated car's encoder: the simulator's thread stores the position, the controller's thread
/// reads it (lock-free).
class SimulatedEncoder final : public PositionSource {
 public:
  std::optional<std::int64_t> position_mm(MonoTime) const noexcept override {
    return mm_.load(std::memory_order_relaxed);
  }
  /// The car is at `mm`: the encoder reads it to the millimetre.
  void set(double mm) noexcept {
    exact_mm_.store(mm, std::memory_order_relaxed);
    mm_.store(std::llround(mm), std::memory_order_relaxed);
  }
  /// Where the car is, unrounded: what a switch in the shaft sees (SimulatedZoneSwitch).
  double exact_mm() const noexcept { return exact_mm_.load(std::memory_order_relaxed); }

 private:
  std::atomic<std::int64_t> mm_{0};
  std::atomic<double> exact_mm_{0.0};
};

/// The simulated shaft of --simulate: sim.shaft_levels_mm (else the floors' levels), each with a
/// level zone of sim.level_zone_mm.
sim::SimulatedShaft simulated_shaft(const config::Config& config);

/// Where the simulated car meets the pit's buffer and the shaft's top (--simulate, the hydraulic
/// and USS cars): 500 mm below the lowest and above the highest of the floors' and the simulated
/// shaft's levels, room for the learning travel's approach of 300 mm (lift::kLearnApproachMm)
/// beyond a terminal level.
double shaft_bottom_mm(const config::Config& config);
double shaft_top_mm(const config::Config& config);

/// The simulated shaft's level switch at the simulated car, read by the controller's thread when
/// it reads the position (lock-free), as a level switch wired beside the encoder would be.
class SimulatedZoneSwitch final : public LevelZoneSource {
 public:
  SimulatedZoneSwitch(const SimulatedEncoder& encoder, const sim::SimulatedShaft& shaft)
      : encoder_(encoder), shaft_(shaft) {}
  bool level_zone(MonoTime) const noexcept override {
    // The switch sees the car itself, not the encoder's millimetres.
    return shaft_.level_zone(encoder_.exact_mm());
  }

 private:
  const SimulatedEncoder& encoder_;
  sim::SimulatedShaft shaft_;
};

/// The simulated I/O board of every simulated lift (--simulate): safety chain, doors and shaft
/// (from the floors), and the `sim` actions that act on it whatever the drive.
class SimulatedBoard {
 public:
  SimulatedBoard(const config::Config& config, MonoTime now);
  /// The board's actions (safety chain, door reversal, open, close, obstruct): applied, true;
  /// any other action, false (the drive's simulator takes it).
  bool apply(const api::SimRequest& request, MonoTime now);
  sim::SimulatedIo& io() noexcept { return io_; }
  const sim::SimulatedIo& io() const noexcept { return io_; }
  /// The board's part of a `sim` result: safety_chain_open, doors, door_obstructed.
  void add_state(nlohmann::json& out) const;

 private:
  sim::SimulatedIo io_;
  bool chain_open_ = false;  ///< injected safety chain opening
  bool obstructed_ = false;  ///< injected door obstruction
};
/// What the simulated card and the simulated USS bus share: the simulator's own thread, the
/// simulated I/O board and encoder its car moves, and the mutex under which that thread and the
/// io thread share the simulator and the board. A simulator's destructor stops its thread.
class SimulatorThread {
 public:
  SimulatorThread(const SimulatorThread&) = delete;
  SimulatorThread& operator=(const SimulatorThread&) = delete;

  /// The simulated encoder on the car (lock-free).
  const PositionSource& position() const { return encoder_; }
  /// The simulated shaft's level zone at the car (lock-free; the learning travel reads it).
  const LevelZoneSource& level_zone() const { return zone_; }
  /// The simulated I/O board's inputs now (io thread).
  lift::Inputs inputs(MonoTime now);
  /// The simulator's state as the `sim` command shows it (io thread).
  nlohmann::json state_json() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return state_json_locked();
  }

 protected:
  explicit SimulatorThread(const config::Config& config)
      : board_(config, mono_now()), zone_(encoder_, simulated_shaft(config)) {}
  ~SimulatorThread() = default;
  /// Runs `loop` on the simulator's thread; `loop` returns once stopping() is true.
  void start_thread(std::function<void()> loop);
  /// Ends the simulator's thread: false when it was not running.
  bool join_thread();
  bool stopping() const noexcept { return stop_.load(); }
  /// The simulated car is at `position_mm`, `moving` or not (simulator's thread, mutex_ held).
  void car_moved(double position_mm, bool moving, MonoTime now);
  /// state_json() with mutex_ held: the kind's simulator and the board (board_.add_state).
  virtual nlohmann::json state_json_locked() const = 0;

  mutable std::mutex mutex_;  ///< guards the simulator and board_ (its thread and the io thread)
  SimulatedBoard board_;
  SimulatedEncoder encoder_;
  SimulatedZoneSwitch zone_;  ///< the simulated shaft's level switch at encoder_

 private:
  std::atomic<bool> stop_{false};
  std::thread thread_;
};
/// Journals a `sim` action that was applied.
void journal_sim_action(const api::SimRequest& request);

/// Carries out `request` on the simulator of the kind `mine` describes: an action the kind did
/// not declare is refused (api::sim_action_refused) and reaches none of the handlers; the
/// board's actions go to `board`, the kind's other shared actions to `shared(api::SimAction)`
/// and its own to `own(std::size_t index)`, each returning a refusal or nullopt. An applied
/// action is journalled. The result: the refusal, or the simulator's `state()` after the action.
template <typename Shared, typename Own, typename State>
api::Result apply_sim(const api::KindSimActions& mine, const api::SimRequest& request,
                      SimulatedBoard& board, MonoTime now, Shared&& shared, Own&& own,
                      State&& state) {
  if (!mine.takes(request)) return api::sim_action_refused(request, mine.lift_name);
  std::optional<api::Result> refused;
  if (!request.shared) {
    refused = own(request.own);
  } else if (!board.apply(request, now)) {
    refused = shared(*request.shared);
  }
  if (refused) return std::move(*refused);
  journal_sim_action(request);
  return api::Result::ok(state());
}

/// The sequencers' inputs from the API's inputs (every drive kind reads the same machine).
lift::Inputs to_lift(const api::Inputs& inputs);
/// The lift model's settings of every kind from the configuration (travel.*).
lift::LiftConfig lift_config(const config::Config& config);
/// The API's view of the cycle's inputs (the `inputs` result under --simulate).
api::Inputs from_lift(const lift::Inputs& inputs);
/// "state changed" -> "state_changed": journal field values are snake_case words.
std::string snake(std::string_view text);

}  // namespace liftd::daemon
