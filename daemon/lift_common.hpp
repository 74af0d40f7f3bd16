// What the daemon's lift of every drive kind sets up alike: the runtime directory, the API
// server's configuration and its socket (systemd socket activation), the journal sink of the
// API server, and applying a reloaded configuration to the server.
#pragma once

#include <optional>
#include <string>
#include <string_view>

#include "api/server.hpp"
#include "can/encoder.hpp"
#include "config/config.hpp"
#include "lift/inputs.hpp"
#include "lift/position_source.hpp"

namespace liftd::daemon {

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
  MachineInputs(const config::Config& config, lift::PositionFeed* feed, bool simulated)
      : config_(config), feed_(feed), simulated_(simulated) {}
  /// Takes an `inputs` update (partial updates keep the rest); a refusal, changing nothing, when
  /// it carries a position the configured source does not take.
  std::optional<api::Result> update(const api::InputUpdate& update);
  /// A new sample from the simulated machine (--simulate).
  void simulated_sample(const lift::Inputs& sample) { sample_ = sample; }
  /// What the cycle should see now; nullopt under --simulate before the machine's first sample.
  std::optional<lift::Inputs> current() const;
  /// The API's inputs as merged so far (the `inputs` command's result).
  const api::Inputs& from_api() const noexcept { return api_; }

 private:
  const config::Config& config_;
  lift::PositionFeed* feed_;
  bool simulated_;
  api::Inputs api_{};
  std::optional<lift::Inputs> sample_;
};
/// The sequencers' inputs from the API's inputs (every drive kind reads the same machine).
lift::Inputs to_lift(const api::Inputs& inputs);
/// "state changed" -> "state_changed": journal field values are snake_case words.
std::string snake(std::string_view text);

}  // namespace liftd::daemon
