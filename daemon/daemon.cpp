// The daemon frame: start, READY=1, signals, reload, STOPPING=1, stop.
#include "daemon/daemon.hpp"

#include <asio/post.hpp>
#include <csignal>
#include <cstring>

#include "daemon/reload.hpp"
#include "kinds/commands.hpp"
#include "kinds/config_schema.hpp"
#include "log/log.hpp"

namespace liftd::daemon {
namespace {

const log::Logger kLog{"daemon"};

// "a, b, c" for log lines.
std::string join(const std::vector<std::string>& items) {
  std::string out;
  for (const auto& item : items) {
    if (!out.empty()) out += ", ";
    out += item;
  }
  return out;
}

log::Level to_log_level(config::LogLevel level) {
  return log::parse_level(config::to_string(level)).value_or(log::Level::info);
}

}  // namespace

std::string signal_name(int signal_number) {
  switch (signal_number) {
    case SIGTERM:
      return "SIGTERM";
    case SIGINT:
      return "SIGINT";
    case SIGHUP:
      return "SIGHUP";
    case SIGUSR1:
      return "SIGUSR1";
    case SIGUSR2:
      return "SIGUSR2";
    case SIGALRM:
      return "SIGALRM";
    case SIGVTALRM:
      return "SIGVTALRM";
    case SIGPROF:
      return "SIGPROF";
    case SIGIO:
      return "SIGIO";
    case SIGPWR:
      return "SIGPWR";
    case SIGSTKFLT:
      return "SIGSTKFLT";
    case SIGPIPE:
      return "SIGPIPE";
    default:
      if (signal_number >= SIGRTMIN && signal_number <= SIGRTMAX) {
        return "SIGRTMIN+" + std::to_string(signal_number - SIGRTMIN);
      }
      return "signal " + std::to_string(signal_number);
  }
}

void ignore_sigpipe() {
  struct sigaction action {};
  action.sa_handler = SIG_IGN;
  ::sigemptyset(&action.sa_mask);
  ::sigaction(SIGPIPE, &action, nullptr);
}

std::vector<int> handled_signals() {
  // Stop, reload, dump; then every signal whose default action ends the process although it
  // means nothing to liftd. SIGQUIT (a core dump on request), the fault signals (SIGSEGV,
  // SIGBUS, SIGFPE, SIGILL, SIGABRT, SIGSYS, SIGTRAP) and the resource limits (SIGXCPU,
  // SIGXFSZ) keep their default: they report a real problem.
  std::vector<int> out = {SIGTERM,   SIGINT,  SIGHUP, SIGUSR1, SIGUSR2,  SIGALRM,
                          SIGVTALRM, SIGPROF, SIGIO,  SIGPWR,  SIGSTKFLT};
  for (int n = SIGRTMIN; n <= SIGRTMAX; ++n) out.push_back(n);
  return out;
}

Daemon::Daemon(config::Config config, service::Notifier notifier,
               std::optional<std::chrono::microseconds> watchdog_timeout)
    : config_(std::move(config)),
      io_(1),  // one thread runs this context: Asio may skip internal locking
      signals_(io_),
      notifier_(std::move(notifier)),
      watchdog_timeout_(watchdog_timeout) {}

Daemon::~Daemon() = default;

void Daemon::add_component(Component component) {
  components_.push_back(std::move(component));
}

void Daemon::set_progress_probe(std::function<bool()> probe) {
  probe_ = std::move(probe);
}

void Daemon::set_running_status(std::string status) {
  running_status_ = std::move(status);
}

void Daemon::report_status(std::string_view status) {
  notifier_.status(status);
}

int Daemon::run() {
  notifier_.status("starting");
  // Handle the signals before anything starts, so a stop during startup is not lost.
  for (const int signal_number : handled_signals()) signals_.add(signal_number);
  wait_for_signal();

  for (auto& component : components_) {
    kLog.debug("starting {}", component.name);
    if (component.start && !component.start()) {
      log::event(log::Level::error, "daemon", "start_failed", {{"part", component.name}},
                 "could not start " + component.name + "; stopping", log::Catalogued::StartFailed);
      notifier_.stopping("failed to start " + component.name);
      stop_components();
      return exit_code::kFailure;
    }
    ++started_;
  }

  notifier_.ready(running_status_);
  log::event(log::Level::info, "daemon", "ready", {{"status", running_status_}},
             "liftd ready: " + running_status_, log::Catalogued::Started);

  if (watchdog_timeout_) {
    watchdog_ = std::make_unique<service::Watchdog>(io_, notifier_, *watchdog_timeout_, probe_);
    kLog.info("systemd watchdog: timeout {} ms, pinging every {} ms",
              watchdog_timeout_->count() / 1000, watchdog_->period().count() / 1000);
    watchdog_->start();
  }

  io_.run();
  return exit_code_;
}

void Daemon::request_stop(std::string_view reason, int code) {
  if (stopping_) return;
  stopping_ = true;
  stop_reason_ = std::string(reason);
  exit_code_ = code;
  notifier_.stopping("stopping: " + std::string(reason));
  log::event(log::Level::info, "daemon", "stopping", {{"reason", std::string(reason)}},
             "stopping: " + std::string(reason));
  // Components wind down in reverse order (the car comes to rest) while the io_context still
  // runs; the watchdog keeps pinging meanwhile, then everything stops.
  wind_down_from(started_);
}

void Daemon::wind_down_from(std::size_t index) {
  while (index > 0) {
    --index;
    if (components_[index].wind_down) {
      components_[index].wind_down(
          [this, index] { asio::post(io_, [this, index] { wind_down_from(index); }); });
      return;
    }
  }
  if (watchdog_) watchdog_->stop();
  stop_components();
  signals_.cancel();
  io_.stop();
}

void Daemon::wait_for_signal() {
  signals_.async_wait([this](const std::error_code& error, int signal_number) {
    if (!error) on_signal(signal_number);
  });
}

void Daemon::on_signal(int signal_number) {
  switch (signal_number) {
    case SIGTERM:
    case SIGINT:
      request_stop(signal_name(signal_number));
      return;
    case SIGHUP:
      reload();
      break;
    case SIGUSR1:
      log::event(log::Level::info, "daemon", "dump_requested", {{"signal", "SIGUSR1"}},
                 "SIGUSR1: writing the flight recorder");
      if (dump_) dump_();
      break;
    default:
      log::event(log::Level::warn, "daemon", "signal_ignored",
                 {{"signal", signal_name(signal_number)}},
                 signal_name(signal_number) +
                     " has no meaning for liftd; ignored (SIGTERM stops, SIGHUP reloads, "
                     "SIGUSR1 writes the flight recorder)");
      break;
  }
  if (!stopping_) wait_for_signal();
}

void Daemon::set_config_loader(std::function<config::LoadResult()> load, std::string origin) {
  load_config_ = std::move(load);
  config_origin_ = std::move(origin);
}

void Daemon::set_config_applier(std::function<std::string(const config::Config&)> apply) {
  apply_config_ = std::move(apply);
}

void Daemon::set_dump_handler(std::function<void()> dump) {
  dump_ = std::move(dump);
}

void Daemon::add_drive_commands(api::Dispatcher& dispatcher, api::Backend& backend) {
  kinds::add_drive_kind_commands(dispatcher, backend);
}

const config::Schema& Daemon::config_schema() const {
  return kinds::config_schema();
}

ReloadOutcome Daemon::refuse_reload(std::vector<std::string> problems) {
  ReloadOutcome outcome;
  outcome.refused = true;
  for (const auto& problem : problems) {
    log::event(log::Level::error, "config", "reload_refused",
               {{"file", config_origin_}, {"problem", problem}},
               "reload refused, the running configuration stays: " + problem,
               log::Catalogued::ReloadRefused);
  }
  notifier_.ready("reload refused (" + std::to_string(problems.size()) + " problem(s) in " +
                  config_origin_ + ", see the journal); " + running_status_);
  outcome.problems = std::move(problems);
  return outcome;
}

ReloadOutcome Daemon::reload() {
  if (!load_config_) {
    notifier_.reloading("reloading");
    log::event(log::Level::info, "daemon", "reload_skipped", {},
               "reload: no configuration file (--simulate without --config); nothing to read");
    notifier_.ready(running_status_);
    return {};
  }
  notifier_.reloading("reloading " + config_origin_);
  log::event(log::Level::info, "daemon", "reload_started", {{"file", config_origin_}},
             "reloading the configuration from " + config_origin_);
  const config::LoadResult loaded = load_config_();
  if (!loaded.ok()) {
    std::vector<std::string> problems;
    for (const auto& problem : loaded.problems) problems.push_back(config::to_string(problem));
    return refuse_reload(std::move(problems));
  }
  ReloadPlan plan = plan_reload(config_, loaded.config);
  if (apply_config_ && !plan.applied.empty()) {
    // Applied first: it may still refuse (an unknown group), and then nothing has changed.
    const std::string error = apply_config_(plan.effective);
    if (!error.empty()) return refuse_reload({error});
  }
  ReloadOutcome outcome;
  for (const auto& change : plan.applied) {
    if (change.key == "log.level" && keep_log_level_) {
      log::event(log::Level::warn, "config", "reload_kept", {{"key", change.key}},
                 "log.level: the file says " + change.requested +
                     " but --log-level on the command line decides; keeping it");
      continue;
    }
    outcome.applied.push_back(change.key);
  }
  if (!keep_log_level_) log::set_level(to_log_level(plan.effective.log.level));
  for (const auto& change : plan.need_restart) {
    log::event(log::Level::warn, "config", "reload_restart_needed",
               {{"key", change.key}, {"running", change.running}, {"requested", change.requested}},
               change.key + " changed from " + change.running + " to " + change.requested +
                   ": it takes effect only after a restart (systemctl restart liftd); keeping " +
                   change.running,
               log::Catalogued::ReloadNeedsRestart);
    outcome.need_restart.push_back(change.key);
  }
  config_ = plan.effective;
  const std::string summary = outcome.applied.empty() ? "nothing changed that applies now"
                                                      : "applied " + join(outcome.applied);
  log::event(log::Level::info, "daemon", "reloaded",
             {{"file", config_origin_},
              {"applied", join(outcome.applied)},
              {"restart_needed", join(outcome.need_restart)}},
             "configuration reloaded from " + config_origin_ + ": " + summary +
                 (outcome.need_restart.empty()
                      ? ""
                      : "; waiting for a restart: " + join(outcome.need_restart)));
  notifier_.ready(outcome.need_restart.empty()
                      ? running_status_
                      : running_status_ + " (" + std::to_string(outcome.need_restart.size()) +
                            " changed key(s) wait for a restart)");
  return outcome;
}

void Daemon::stop_components() {
  while (started_ > 0) {
    --started_;
    auto& component = components_[started_];
    kLog.debug("stopping {}", component.name);
    if (component.stop) component.stop();
  }
}

}  // namespace liftd::daemon
