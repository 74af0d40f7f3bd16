// The simulated lift for `liftd --simulate`: the simulated drive serving one end of a
// pseudo-terminal (the cycle opens the other end exactly as it would a real RS485 port), the
// simulated encoder as the position source, and the simulated I/O board.
#pragma once

#include <memory>
#include <string>

#include "api/backend.hpp"
#include "api/result.hpp"
#include "config/config.hpp"
#include "dcp/control/dcp_controller.hpp"
#include "dcp/sim/serial_runner.hpp"
#include "host/lift_common.hpp"
#include "io/pty.hpp"
#include "lift/inputs.hpp"
#include "sim/shaft.hpp"
#include "sim/sim_io.hpp"

namespace liftd::daemon {

/// Drive simulator on a pty, encoder and I/O board for --simulate.
class SimulatedLift {
 public:
  /// Creates the pty pair; throws std::runtime_error naming the failing call.
  explicit SimulatedLift(const config::Config& config);
  ~SimulatedLift();
  SimulatedLift(const SimulatedLift&) = delete;
  SimulatedLift& operator=(const SimulatedLift&) = delete;

  /// The serial device the cycle opens (the pty's slave side).
  const std::string& device_path() const { return device_path_; }
  /// Starts the drive simulator thread.
  bool start();
  /// Stops it (idempotent).
  void stop();
  /// The simulated absolute encoder, read by the cycle thread (lock-free).
  const control::PositionSource& position() const;
  /// The simulated shaft's level zone at the car's position (read by the cycle thread).
  const LevelZoneSource& level_zone() const;
  /// The simulated I/O board's inputs now (io thread).
  lift::Inputs inputs(MonoTime now);
  /// Logs what the simulated drive did since the last call (io thread).
  void log_violations();
  /// Carries out a `sim` request at `now` (io thread); the result is state_json() after it, or
  /// `busy` for a drift while the car moves.
  api::Result apply(const api::SimRequest& request, MonoTime now);
  /// The injected state: drive switches, safety chain, doors, car position.
  nlohmann::json state_json() const;

 private:
  class Encoder;
  class ZoneSwitch;

  std::unique_ptr<io::PtyPair> pty_;  ///< held open so the cycle's side never sees a hang-up
  std::string device_path_;
  std::unique_ptr<dcp::sim::SerialDriveRunner> drive_;
  std::unique_ptr<Encoder> position_;
  std::unique_ptr<ZoneSwitch> zone_;
  SimulatedBoard board_;  ///< safety chain, doors, shaft
  bool started_ = false;
  bool general_fault_ = false;    ///< injected S3
  bool advance_warning_ = false;  ///< injected S2
  bool not_ready_ = false;        ///< injected S0 = 0
};

}  // namespace liftd::daemon
