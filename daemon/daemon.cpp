// The daemon frame: start, READY=1, signals, STOPPING=1, stop.
#include "daemon/daemon.hpp"

#include <asio/post.hpp>
#include <csignal>
#include <cstring>

#include "log/log.hpp"

namespace liftd::daemon {
namespace {

const log::Logger kLog{"daemon"};

}  // namespace

std::string signal_name(int signal_number) {
  switch (signal_number) {
    case SIGTERM:
      return "SIGTERM";
    case SIGINT:
      return "SIGINT";
    case SIGHUP:
      return "SIGHUP";
    default:
      return "signal " + std::to_string(signal_number);
  }
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
  signals_.add(SIGTERM);
  signals_.add(SIGINT);
  signals_.add(SIGHUP);
  wait_for_signal();

  for (auto& component : components_) {
    kLog.debug("starting {}", component.name);
    if (component.start && !component.start()) {
      log::event(log::Level::error, "daemon", "start_failed", {{"part", component.name}},
                 "could not start " + component.name + "; stopping");
      notifier_.stopping("failed to start " + component.name);
      stop_components();
      return exit_code::kFailure;
    }
    ++started_;
  }

  notifier_.ready(running_status_);
  log::event(log::Level::info, "daemon", "ready", {{"status", running_status_}},
             "liftd ready: " + running_status_);

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
  if (signal_number == SIGHUP) {
    log::event(log::Level::warn, "daemon", "reload_unsupported", {{"signal", "SIGHUP"}},
               "SIGHUP: reloading the configuration is not supported; restart the service "
               "(systemctl restart liftd) to apply a new one");
    wait_for_signal();
    return;
  }
  request_stop(signal_name(signal_number));
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
