// The daemon as one piece: builds the DCP controller, its real-time cycle, the simulated lift
// (with --simulate) and the API server from the configuration, and registers them as daemon
// components. The cycle thread wakes the io thread after every cycle (an eventfd); the io
// thread then drains the cycle's queues and turns what it finds into journal lines, API replies
// and watch events, so a change reaches watchers from the cycle that saw it.
#pragma once

#include <array>
#include <chrono>
#include <memory>
#include <optional>
#include <string>
#include "can/encoder.hpp"
#include "rt/can_runner.hpp"
#include "rt/encoder_tap.hpp"

#include "api/server.hpp"
#include "config/config.hpp"
#include "dcp/control/dcp_controller.hpp"
#include "dcp/host/lift_backend.hpp"
#include "host/host.hpp"
#include "host/lift_core.hpp"
#include "io/pty.hpp"
#include "rt/cycle_runner.hpp"
#include "rt/overrun_journal.hpp"

namespace liftd::daemon {

/// The DCP controller's settings from the configuration (what a default Config gives is what a
/// default ControllerConfig holds: common/defaults.hpp).
control::ControllerConfig dcp_controller_config(const config::Config& config);

class SimulatedLift;

/// Everything between the configuration and the running components.
class LiftApp final : public LiftRunner {
 public:
  /// Builds the parts (throws std::invalid_argument / std::runtime_error with a clear message
  /// on a configuration the parts refuse) and registers them with `daemon`.
  LiftApp(Host& daemon, const config::Config& config, bool simulate);
  ~LiftApp() override;
  LiftApp(const LiftApp&) = delete;
  LiftApp& operator=(const LiftApp&) = delete;

  /// The API socket path in use.
  const std::string& socket_path() const override { return socket_path_; }
  /// The real-time cycle (statistics for benchmarks and diagnostics).
  const rt::CycleRunner& cycle() const { return *runner_; }

 private:
  bool start_cycle();
  void stop_cycle();
  bool start_api();
  void stop_api();
  void poll();
  void publish_state_if_changed(MonoTime now);
  void log_cycle_events();
  void handle_event(const control::ControllerEvent& event);
  void dump_flight_recorder(std::string_view why);
  void wind_down(std::function<void()> done);
  void check_wind_down(MonoTime now);
  std::string apply_config(const config::Config& next);

  Host& daemon_;
  const config::Config& config_;
  bool simulate_;
  std::string socket_path_;
  std::string runtime_dir_;

  std::unique_ptr<SimulatedLift> sim_;
  std::unique_ptr<control::PositionFeed> position_feed_;
  const control::PositionSource* position_ = nullptr;
  std::unique_ptr<can::CanEncoder> encoder_;       ///< position.source "can"
  std::unique_ptr<rt::EncoderTap> encoder_tap_;    ///< its frames to it
  std::unique_ptr<rt::CanRunner> encoder_runner_;  ///< reads its bus
  std::unique_ptr<control::DcpController> controller_;
  std::unique_ptr<rt::CycleRunner> runner_;
  std::unique_ptr<LiftBackend> backend_;
  std::unique_ptr<api::Server> server_;

  ThreadWake wake_;           ///< poll() after every cycle (the cycle thread's eventfd)
  StatePublisher publisher_;  // `state` events, as on every lift
  rt::OverrunJournal overruns_;
  bool running_ = false;
  std::uint64_t last_progress_ = 0;
  MonoTime last_clock_{};
  MonoTime last_sim_inputs_{};
  std::uint32_t last_display_version_ = 0;
  WindDown wind_down_;  ///< a service stop waiting for the car to rest, as on every lift
};

}  // namespace liftd::daemon
