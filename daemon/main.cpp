// liftd entry point: command line, configuration, logging, then the daemon frame.
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "common/cpu_set.hpp"
#include "common/version.hpp"
#include "config/config.hpp"
#include "daemon/cli.hpp"
#include "daemon/daemon.hpp"
#include "host/lift_common.hpp"
#include "kinds/config_schema.hpp"
#include "kinds/lifts.hpp"
#include "log/log.hpp"
#include "rt/board_settings.hpp"
#include "rt/cpu_split.hpp"
#include "rt/rt_thread.hpp"
#include "service/notify.hpp"

namespace {

using liftd::daemon::CommandLine;
namespace exit_code = liftd::daemon::exit_code;
namespace config = liftd::config;
namespace log = liftd::log;

// Both enums use the same names ("trace".."error"); convert by name, not by position.
log::Level to_log_level(config::LogLevel level) {
  return log::parse_level(config::to_string(level)).value_or(log::Level::info);
}

// Prints every problem of a configuration, one per line.
void print_problems(std::FILE* out, std::string_view path,
                    const std::vector<config::Problem>& problems) {
  std::fprintf(out, "liftd: %.*s: %zu problem%s:\n", static_cast<int>(path.size()), path.data(),
               problems.size(), problems.size() == 1 ? "" : "s");
  for (const auto& problem : problems) {
    std::fprintf(out, "  %s\n", config::to_string(problem).c_str());
  }
}

int check_config(const std::string& path) {
  const auto result = liftd::kinds::load_config(path);
  if (!result.ok()) {
    print_problems(stderr, path, result.problems);
    return exit_code::kBadConfig;
  }
  std::printf("%s: configuration is valid\n%s", path.c_str(),
              config::summary(result.config, liftd::kinds::config_schema()).c_str());
  return exit_code::kOk;
}

// What --simulate changes in any configuration file, at start and on every reload alike: the
// simulated encoder is the position source, and a simulated lift moves no car, so it runs for
// anyone, real time or not (and says which).
void simulate_overrides(config::Config& cfg) {
  cfg.position.source = config::PositionSource::sim;
  cfg.rt.require_realtime = false;
}

// Loads the configuration the command line names; the defaults when simulating without one.
std::optional<config::Config> load_config(const CommandLine& cl, bool to_log) {
  if (cl.simulate && !cl.config_path) return liftd::daemon::simulation_defaults();
  const std::string path = cl.config_path.value_or(std::string(liftd::daemon::kDefaultConfigPath));
  auto result = liftd::kinds::load_config(path);
  if (!result.ok()) {
    if (to_log) {
      for (const auto& problem : result.problems) {
        log::event(log::Level::error, "config", "config_invalid",
                   {{"file", path}, {"key", problem.where}}, config::to_string(problem),
                   log::Catalogued::ConfigRefused);
      }
      liftd::service::Notifier::from_environment().status(
          "configuration invalid: " + std::to_string(result.problems.size()) + " problem(s) in " +
          path + ", see the journal or run liftd --check-config " + path);
    } else {
      print_problems(stderr, path, result.problems);
    }
    return std::nullopt;
  }
  if (cl.simulate) simulate_overrides(result.config);
  return result.config;
}

// When the configuration requires real time, tries a thread with the cycle's scheduling before
// anything starts: a refusal is a configuration this host cannot run, so it ends with exit 2
// (the unit does not restart on it) instead of a cycle without real time behind one warning.
// Returns the refusal text, or nothing when the cycle can run.
std::optional<std::string> realtime_refusal(const config::Config& cfg) {
  if (!cfg.rt.require_realtime) return std::nullopt;
  liftd::rt::RtThreadOptions options;
  options.priority = cfg.rt.priority;
  options.cpu = cfg.rt.cpu;
  options.lock_memory = false;  // the cycle's own start locks memory
  options.stack_prefault_bytes = 0;
  liftd::rt::RtThread probe;
  if (const int error = probe.start(options, [] {}); error != 0) {
    return std::string("cannot start a thread: ") + std::strerror(error);
  }
  probe.join();
  const auto& status = probe.status();
  if (status.realtime && (cfg.rt.cpu < 0 || status.pinned)) return std::nullopt;
  return status.describe();
}

// With rt.cpu set, every thread but the real-time loops (the io thread with the API, the port
// keepers) runs on the other CPUs the process may use, so that nothing of liftd's own at normal
// priority competes on the real-time CPU with the tty's flip-buffer worker that a board's
// settings put there (docs/operations.md, "Real-time settings of a board"). Before any thread
// starts: the threads inherit it; the real-time threads pin themselves to rt.cpu.
void keep_normal_threads_off_the_cycle_cpu(const config::Config& cfg) {
  const liftd::rt::CpuSplit split = liftd::rt::keep_normal_threads_off(cfg.rt.cpu);
  if (split.error != 0) {
    log::event(log::Level::warn, "rt", "cpu_split_refused",
               {{"cpu", std::to_string(cfg.rt.cpu)}, {"errno", std::to_string(split.error)}},
               "could not keep the normal threads off CPU " + std::to_string(cfg.rt.cpu) + ": " +
                   std::strerror(split.error) + "; they share it with the cycle");
  } else if (!split.normal_cpus.empty()) {
    const std::string normal = liftd::cpu_list_text(split.normal_cpus);
    log::event(log::Level::info, "rt", "cpu_split",
               {{"cpu", std::to_string(cfg.rt.cpu)}, {"normal_cpus", normal}},
               "real-time threads on CPU " + std::to_string(cfg.rt.cpu) +
                   ", every other thread on CPU(s) " + normal);
  }
}

// The board settings around the real-time threads that liftd cannot make itself (the unbound
// workqueue's CPUs, the real-time CPU's idle states; docs/operations.md): one line naming what
// is missing, for the technician reading the journal. A warning when rt.cpu is set (the board is
// meant to be tuned), otherwise information.
void report_missing_board_settings(const config::Config& cfg) {
  const auto missing =
      liftd::rt::missing_board_settings(cfg.rt.cpu, liftd::rt::BoardFacts::current(cfg.rt.cpu));
  if (missing.empty()) return;
  std::string text;
  for (const auto& m : missing) text += (text.empty() ? "" : "; ") + m;
  log::event(cfg.rt.cpu >= 0 ? log::Level::warn : log::Level::info, "rt", "rt_settings_missing",
             {{"missing", std::to_string(missing.size())}},
             "real-time settings of this board missing (docs/operations.md, \"Real-time "
             "settings of a board\"): " +
                 text);
}

// A start that ends with exit 2 while systemd holds the API socket (liftd.socket): the clients
// waiting on it, and those that come within the next seconds, get one error line saying why
// instead of waiting; and since they are answered, the socket does not start liftd again at once
// for them (a client that reconnects continuously would otherwise run liftd into systemd's start
// limit and take the socket down with it).
void answer_clients_of_a_refused_start(const std::string& why) {
  const auto fds = liftd::service::listen_fds_from_environment();
  if (fds.empty()) return;
  const int fd = liftd::service::pick_listen_fd(fds, "api");
  liftd::service::close_unused_listen_fds(fds, fd);
  if (fd < 0) return;
  const std::size_t answered = liftd::service::answer_refused_start(
      fd, "liftd is not running: " + why, liftd::service::kRefusedStartLinger);
  ::close(fd);
  if (answered > 0) {
    log::event(log::Level::info, "daemon", "refused_start_answered",
               {{"clients", std::to_string(answered)}},
               "told " + std::to_string(answered) + " API client(s) why liftd is not running");
  }
}

int run_daemon(const CommandLine& cl) {
  log::init({cl.log_level.value_or(log::Level::info), log::Backend::automatic, "liftd"});
  auto cfg = load_config(cl, true);
  if (!cfg) {
    const std::string path =
        cl.config_path.value_or(std::string(liftd::daemon::kDefaultConfigPath));
    answer_clients_of_a_refused_start(
        "it refused its configuration file " + path + " (liftd --check-config " + path +
        " lists the problems); fix it, then: systemctl restart liftd");
    log::flush();
    return exit_code::kBadConfig;
  }
  log::set_level(cl.log_level.value_or(to_log_level(cfg->log.level)));
  if (const auto refusal = realtime_refusal(*cfg)) {
    const std::string text =
        "rt.require_realtime is true but the cycle thread cannot run with SCHED_FIFO priority " +
        std::to_string(cfg->rt.priority) +
        (cfg->rt.cpu >= 0 ? " on CPU " + std::to_string(cfg->rt.cpu) : std::string()) + ": " +
        *refusal +
        "; grant CAP_SYS_NICE (the unit does) or LimitRTPRIO, or set rt.require_realtime to "
        "false to run without real time";
    log::event(log::Level::error, "rt", "realtime_refused",
               {{"priority", std::to_string(cfg->rt.priority)}}, text);
    liftd::service::Notifier::from_environment().status("real-time scheduling refused: " +
                                                        *refusal);
    answer_clients_of_a_refused_start("real-time scheduling refused (" + *refusal +
                                      "); see journalctl -u liftd LIFTD_EVENT=realtime_refused");
    log::flush();
    return exit_code::kBadConfig;
  }
  report_missing_board_settings(*cfg);  // first: it reads the CPUs the whole process may use
  keep_normal_threads_off_the_cycle_cpu(*cfg);
  log::event(
      log::Level::info, "daemon", "starting",
      {{"version", std::string(liftd::kVersion)},
       {"config", cl.config_path.value_or(
                      cl.simulate ? "(defaults)" : std::string(liftd::daemon::kDefaultConfigPath))},
       {"mode", cl.simulate ? "simulate" : "drive"}},
      "liftd " + std::string(liftd::kVersion) + " starting");

  liftd::daemon::Daemon daemon(*cfg, liftd::service::Notifier::from_environment(),
                               liftd::service::watchdog_from_environment());
  daemon.keep_log_level(cl.log_level.has_value());
  if (!cl.simulate || cl.config_path) {
    const std::string path =
        cl.config_path.value_or(std::string(liftd::daemon::kDefaultConfigPath));
    const bool simulate = cl.simulate;
    daemon.set_config_loader(
        [path, simulate] {
          auto result = liftd::kinds::load_config(path);
          if (result.ok() && simulate) simulate_overrides(result.config);
          return result;
        },
        path);
  }
  std::unique_ptr<liftd::daemon::LiftRunner> app;
  try {
    // The daemon's copy: a reload updates it in place, and the parts read the keys it applies.
    app = liftd::kinds::make_lift(daemon, daemon.config(), cl.simulate);
  } catch (const std::exception& error) {
    log::event(log::Level::error, "daemon", "setup_failed", {}, error.what(),
               log::Catalogued::StartFailed);
    log::flush();
    return exit_code::kFailure;
  }
  const int code = daemon.run();
  log::event(log::Level::info, "daemon", "stopped", {{"exit_code", std::to_string(code)}},
             "liftd stopped", log::Catalogued::Stopped);
  log::flush();
  return code;
}

int dispatch(const CommandLine& cl) {
  switch (cl.mode) {
    case CommandLine::Mode::help:
      std::fputs(liftd::daemon::usage().c_str(), stdout);
      return exit_code::kOk;
    case CommandLine::Mode::version:
      std::printf("liftd %.*s\n", static_cast<int>(liftd::kVersion.size()), liftd::kVersion.data());
      return exit_code::kOk;
    case CommandLine::Mode::print_reference:
      std::fputs(config::reference_markdown(liftd::kinds::config_schema()).c_str(), stdout);
      return exit_code::kOk;
    case CommandLine::Mode::check_config:
      return check_config(*cl.config_path);
    case CommandLine::Mode::print_config: {
      const auto cfg = load_config(cl, false);
      if (!cfg) return exit_code::kBadConfig;
      std::printf("%s\n", config::to_json(*cfg, liftd::kinds::config_schema()).dump(2).c_str());
      return exit_code::kOk;
    }
    case CommandLine::Mode::run:
      return run_daemon(cl);
  }
  return exit_code::kFailure;
}

}  // namespace

int main(int argc, char** argv) {
  liftd::daemon::ignore_sigpipe();  // before any thread starts: they inherit the disposition
  std::vector<std::string_view> args(argv + 1, argv + argc);
  const auto parsed = liftd::daemon::parse_command_line(args);
  if (!parsed.command_line) {
    std::fprintf(stderr, "liftd: %s\nTry liftd --help.\n", parsed.error.c_str());
    return exit_code::kBadConfig;
  }
  try {
    return dispatch(*parsed.command_line);
  } catch (const std::exception& error) {
    log::write(log::Level::error, "daemon", std::string("fatal: ") + error.what());
    log::flush();
    return exit_code::kFailure;
  }
}
