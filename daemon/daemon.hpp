// The daemon's frame: an io_context on the main thread, signal handling, systemd notification
// and watchdog, configuration reload, and an ordered list of components (drive link,
// simulator, API server, ...) that are started before READY=1 and stopped in reverse order on
// SIGTERM/SIGINT.
//
// Signals: SIGTERM and SIGINT stop; SIGHUP reloads the configuration (`systemctl reload`);
// SIGUSR1 writes the flight recorder; every other signal that would end the process by
// default without meaning anything to us (SIGUSR2, SIGALRM, SIGVTALRM, SIGPROF, SIGIO,
// SIGPWR, SIGSTKFLT, the real-time signals) is logged and otherwise ignored. SIGPIPE is
// ignored for the whole process (ignore_sigpipe), so a reader that goes away is a write error.
#pragma once

#include <asio/io_context.hpp>
#include <asio/signal_set.hpp>
#include <chrono>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "config/config.hpp"
#include "host/host.hpp"
#include "service/notify.hpp"

namespace liftd::daemon {

/// Exit codes of the liftd process.
namespace exit_code {
inline constexpr int kOk = 0;         ///< clean stop on SIGTERM/SIGINT
inline constexpr int kFailure = 1;    ///< a component failed to start or an internal error
inline constexpr int kBadConfig = 2;  ///< bad command line or configuration
}  // namespace exit_code

/// What a reload did (also logged and reported to systemd).
struct ReloadOutcome {
  bool refused = false;                   ///< the file did not validate: nothing changed
  std::vector<std::string> problems;      ///< why it was refused, one line per problem
  std::vector<std::string> applied;       ///< keys whose new value is now in effect
  std::vector<std::string> need_restart;  ///< changed keys left as they were until a restart
};

/// Ignores SIGPIPE for the whole process: a closed stderr reader or API client is then an
/// EPIPE error where it happens instead of the end of the daemon. Call before any thread starts.
void ignore_sigpipe();

/// Every signal the daemon handles: stop, reload, dump, and those it logs and ignores.
std::vector<int> handled_signals();

/// Runs the daemon: owns the io_context (run on the calling thread), the signal set, the
/// notifier and the watchdog; hosts the lift (Host).
class Daemon final : public Host {
 public:
  /// A daemon for `config`, notifying through `notifier`, with the watchdog timeout systemd
  /// asked for (nullopt: no watchdog).
  Daemon(config::Config config, service::Notifier notifier,
         std::optional<std::chrono::microseconds> watchdog_timeout);
  ~Daemon() override;
  Daemon(const Daemon&) = delete;
  Daemon& operator=(const Daemon&) = delete;

  /// The io_context every component posts its work to.
  asio::io_context& io() override { return io_; }
  /// The configuration in effect (after a reload: the running values of keys that need a
  /// restart, the new values of the others). Stays at the same address for the daemon's life.
  const config::Config& config() const { return config_; }

  /// Adds a component; components start in the order added, stop in reverse.
  void add_component(Component component) override;
  /// Sets the probe that gates WATCHDOG=1 (e.g. "the DCP cycle advanced since last time").
  /// Without one, every period counts as progress.
  void set_progress_probe(std::function<bool()> probe) override;
  /// The STATUS= text sent with READY=1 once every component has started.
  void set_running_status(std::string status) override;
  /// Sends a STATUS= line now (e.g. "link fault: drive not answering").
  void report_status(std::string_view status) override;

  /// How to read the configuration file again on SIGHUP, and the file's name for messages.
  /// Without a loader (`--simulate` without `--config`) a reload has nothing to read.
  void set_config_loader(std::function<config::LoadResult()> load, std::string origin);
  /// Applies the settings a reload may change (API access groups and limits) to the running
  /// parts; returns "" when done, or why it cannot (then nothing may have changed).
  void set_config_applier(std::function<std::string(const config::Config&)> apply) override;
  /// Keeps the log level a reload would otherwise set from log.level (--log-level given).
  void keep_log_level(bool keep) { keep_log_level_ = keep; }
  /// What SIGUSR1 does: write the flight recorder.
  void set_dump_handler(std::function<void()> dump) override;
  /// Every drive kind's own commands, from the registry of drive kinds (drives.cpp).
  void add_drive_commands(api::Dispatcher& dispatcher, api::Backend& backend) override;
  /// Every drive kind's configuration schema (lib/kinds).
  const config::Schema& config_schema() const override;
  std::string_view stop_reason() const override { return stop_reason_; }

  /// Re-reads the configuration (RELOADING=1 ... READY=1): applies what can change while the
  /// drive link runs, names in the journal each changed key that needs a restart and keeps its
  /// running value, and changes nothing when the file does not validate.
  ReloadOutcome reload();

  /// Starts the components, sends READY=1 and runs the io_context until a stop is requested.
  /// Returns the process exit code.
  int run();
  /// Begins a clean shutdown (STOPPING=1, components stopped in reverse, run() returns `code`).
  void request_stop(std::string_view reason, int code = exit_code::kOk);

 private:
  void wait_for_signal();
  void on_signal(int signal_number);
  void stop_components();
  void wind_down_from(std::size_t index);
  ReloadOutcome refuse_reload(std::vector<std::string> problems);

  config::Config config_;
  asio::io_context io_;
  asio::signal_set signals_;
  service::Notifier notifier_;
  std::optional<std::chrono::microseconds> watchdog_timeout_;
  std::unique_ptr<service::Watchdog> watchdog_;
  std::function<bool()> probe_;
  std::vector<Component> components_;
  std::size_t started_ = 0;
  std::string running_status_ = "running";
  std::function<config::LoadResult()> load_config_;
  std::string config_origin_;
  std::function<std::string(const config::Config&)> apply_config_;
  std::function<void()> dump_;
  bool keep_log_level_ = false;
  bool stopping_ = false;
  std::string stop_reason_;  ///< request_stop()'s reason
  int exit_code_ = exit_code::kOk;
};

/// The name of a signal ("SIGTERM"), for logs.
std::string signal_name(int signal_number);

}  // namespace liftd::daemon
