// What a drive kind's lift needs of the process that runs it (the daemon, daemon/daemon.hpp):
// the io_context, components started in order and stopped in reverse, the watchdog's probe, the
// status lines for systemd, what a reload and SIGUSR1 do, every drive kind's own API commands and
// the configuration's schema. A lift registers its parts through Host and is held as a
// LiftRunner.
#pragma once

#include <functional>
#include <string>
#include <string_view>

#include <asio/io_context.hpp>

#include "api/backend.hpp"
#include "api/dispatcher.hpp"
#include "config/config.hpp"

namespace liftd::daemon {

/// One part of the daemon with a start and a stop step, run on the io_context's thread.
struct Component {
  std::string name;             ///< shown in logs ("dcp", "sim", "api")
  std::function<bool()> start;  ///< returns false (after logging why) when it cannot start
  std::function<void()> stop;   ///< undoes start; called only for started components
  /// Optional, before any stop: brings the part to a safe rest (a moving car to a floor) while
  /// the io_context keeps running; calls `done` once finished.
  std::function<void(std::function<void()> done)> wind_down = nullptr;
};

/// The process a lift runs in, as the lift sees it.
class Host {
 public:
  virtual ~Host() = default;

  /// The io_context every component posts its work to.
  virtual asio::io_context& io() = 0;
  /// Adds a component; components start in the order added, stop in reverse.
  virtual void add_component(Component component) = 0;
  /// Sets the probe that gates WATCHDOG=1 (e.g. "the DCP cycle advanced since last time").
  /// Without one, every period counts as progress.
  virtual void set_progress_probe(std::function<bool()> probe) = 0;
  /// The STATUS= text sent with READY=1 once every component has started.
  virtual void set_running_status(std::string status) = 0;
  /// Sends a STATUS= line now (e.g. "link fault: drive not answering").
  virtual void report_status(std::string_view status) = 0;
  /// Applies the settings a reload may change (API access groups and limits) to the running
  /// parts; returns "" when done, or why it cannot (then nothing may have changed).
  virtual void set_config_applier(std::function<std::string(const config::Config&)> apply) = 0;
  /// What SIGUSR1 does: write the flight recorder.
  virtual void set_dump_handler(std::function<void()> dump) = 0;
  /// Adds every drive kind's own commands (lib/<kind>/host/commands) to the lift's API after
  /// the common ones: the lift's own kind's served by `backend`, the other kinds' known by name
  /// so that the dispatcher answers them `not_offered`.
  virtual void add_drive_commands(api::Dispatcher& dispatcher, api::Backend& backend) = 0;
  /// The schema of the configuration file (every drive kind's keys): the `config` command's
  /// dump.
  virtual const config::Schema& config_schema() const = 0;
  /// Why the process is stopping ("SIGTERM", ...), once it is; empty before.
  virtual std::string_view stop_reason() const = 0;
};

/// A running lift of any drive kind, as main() holds it.
class LiftRunner {
 public:
  virtual ~LiftRunner() = default;
  /// The API socket path in use.
  virtual const std::string& socket_path() const = 0;
};

}  // namespace liftd::daemon
