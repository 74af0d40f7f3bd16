#include "api/server.hpp"

#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <spdlog/spdlog.h>

#include "api/commands.hpp"
#include "api/server_impl.hpp"
#include "common/version.hpp"

namespace liftd::api {

namespace {

void default_log(LogLevel level, std::string_view message) {
  switch (level) {
    case LogLevel::Debug:
      spdlog::debug("{}", message);
      break;
    case LogLevel::Info:
      spdlog::info("{}", message);
      break;
    case LogLevel::Warn:
      spdlog::warn("{}", message);
      break;
    case LogLevel::Error:
      spdlog::error("{}", message);
      break;
  }
}

}  // namespace

Server::Impl::Impl(asio::io_context& io, Backend& backend, ServerConfig config, LogFn log)
    : io_(io),
      backend_(backend),
      config_(std::move(config)),
      log_(log ? std::move(log) : LogFn(default_log)),
      policy_(
          AccessPolicy::resolve(config_.read_group, config_.control_group, config_.inputs_group)),
      dispatcher_(DispatchLimits{config_.max_depth, config_.max_in_flight}),
      acceptor_(io),
      retry_timer_(io),
      budget_(config_.max_requests_per_second, kLinesPerTurn, SteadyClock::now()),
      budget_timer_(io) {}

void Server::Impl::register_builtins() {
  std::weak_ptr<Impl> weak = weak_from_this();
  add_builtin_commands(dispatcher_, backend_, [weak]() {
    const auto self = weak.lock();
    return self ? to_json(self->counters()) : nlohmann::json::object();
  });
}

void Server::Impl::reconfigure(const ServerConfig& next) {
  AccessPolicy policy =
      AccessPolicy::resolve(next.read_group, next.control_group, next.inputs_group);
  policy_ = std::move(policy);
  config_.read_group = next.read_group;
  config_.control_group = next.control_group;
  config_.inputs_group = next.inputs_group;
  config_.max_clients = next.max_clients;
  config_.idle_timeout = next.idle_timeout;
  config_.max_clients_per_uid = next.max_clients_per_uid;
  config_.reserved_clients = next.reserved_clients;
  config_.stalled_reader_timeout = next.stalled_reader_timeout;
  config_.max_requests_per_second = next.max_requests_per_second;
  budget_.set_rate(next.max_requests_per_second, SteadyClock::now());
  if (budget_timer_armed_) budget_timer_.cancel();  // its expiry was for the old rate
  budget_timer_armed_ = false;
  arm_budget_timer();
  const auto sessions = std::vector<std::shared_ptr<Session>>(sessions_.begin(), sessions_.end());
  for (const auto& session : sessions) session->settings_changed();
  log_(LogLevel::Info,
       "api: settings changed: max_clients " + std::to_string(config_.max_clients) +
           ", idle timeout " + std::to_string(config_.idle_timeout.count()) +
           " ms, requests per second " +
           (budget_.limited()
                ? std::to_string(static_cast<long long>(config_.max_requests_per_second))
                : std::string("unlimited")) +
           " ms, groups read \"" + config_.read_group + "\" control \"" + config_.control_group +
           "\" inputs \"" + config_.inputs_group + "\"");
}

void Session::start() {
  nlohmann::json hello = {{"version", std::string(kVersion)},
                          {"api", kApiVersion},
                          {"access", peer_.access.to_json()},
                          {"max_line_bytes", server_->config_.max_line_bytes}};
  if (!server_->config_.car.is_null()) hello["car"] = server_->config_.car;
  enqueue(std::make_shared<const std::string>(event_line("hello", hello)), false);
  read_more();
  arm_timer();
}

void Session::settings_changed() {
  if (closed_) return;
  peer_.access = server_->policy_.access_for(peer_.uid, groups_);
  if (watching_ && !peer_.access.allows(Access::Read)) {
    const nlohmann::json why = {{"reason", "read access revoked by a configuration reload"}};
    enqueue(std::make_shared<const std::string>(event_line("watch_ended", why)), false);
    set_watching(false);
    server_->log_(LogLevel::Info, describe() + ": watch ended, read access revoked");
  }
  arm_timer();
}

void Session::enqueue(std::shared_ptr<const std::string> line, bool is_event) {
  if (closed_) return;
  const ServerConfig& cfg = server_->config_;
  if (is_event) {
    const bool room = missed_ == 0 ? queue_.size() + 1 <= cfg.write_queue_max_messages &&
                                         queued_bytes_ + line->size() <= cfg.write_queue_max_bytes
                                   : drained();
    if (!room) {
      ++server_->counters_.missed_events;
      if (missed_++ == 0) {
        server_->log_(LogLevel::Warn, describe() + " does not read its events fast enough (" +
                                          std::to_string(queue_.size()) + " lines, " +
                                          std::to_string(queued_bytes_) +
                                          " bytes queued): events counted, not sent");
      }
      return;
    }
    if (missed_ != 0) {
      const std::uint64_t missed = std::exchange(missed_, 0);
      push_line(std::make_shared<const std::string>(event_line("missed", {{"count", missed}})));
    }
  }
  push_line(std::move(line));
}

void Session::set_watching(bool enable) {
  if (enable == watching_) return;
  watching_ = enable;
  if (enable) {
    ++server_->counters_.watchers;
  } else {
    --server_->counters_.watchers;
  }
}

void Session::send_event(std::string line) {
  enqueue(std::make_shared<const std::string>(std::move(line)), true);
}

void Server::Impl::publish(std::string_view event, const nlohmann::json& data) {
  ++counters_.events;
  if (counters_.watchers == 0) return;
  const auto line = std::make_shared<const std::string>(event_line(event, data));
  std::vector<std::shared_ptr<Session>> watchers;
  for (const auto& session : sessions_) {
    if (session->watching()) watchers.push_back(session);
  }
  for (const auto& session : watchers) session->enqueue(line, true);
}

void Server::Impl::announce(std::string_view event, const nlohmann::json& data) {
  ++counters_.events;
  const auto line = std::make_shared<const std::string>(event_line(event, data));
  const auto everyone = std::vector<std::shared_ptr<Session>>(sessions_.begin(), sessions_.end());
  for (const auto& session : everyone) session->enqueue(line, true);
}

ServerCounters Server::Impl::counters() const {
  return counters_;
}

Server::Server(asio::io_context& io, Backend& backend, ServerConfig config, LogFn log)
    : impl_(std::make_shared<Impl>(io, backend, std::move(config), std::move(log))) {
  impl_->register_builtins();
}

Server::~Server() {
  impl_->stop();
}

void Server::start() {
  impl_->start();
}
void Server::stop() {
  impl_->stop();
}
void Server::reconfigure(const ServerConfig& next) {
  impl_->reconfigure(next);
}
Dispatcher& Server::dispatcher() {
  return impl_->dispatcher_;
}
void Server::publish(std::string_view event, const nlohmann::json& data) {
  impl_->publish(event, data);
}
void Server::announce(std::string_view event, const nlohmann::json& data) {
  impl_->announce(event, data);
}
ServerCounters Server::counters() const {
  return impl_->counters();
}

nlohmann::json to_json(const ServerCounters& c) {
  return {{"clients", c.clients},
          {"watchers", c.watchers},
          {"connections", c.connections},
          {"rejected", c.rejected},
          {"requests", c.requests},
          {"errors", c.errors},
          {"dropped", c.dropped},
          {"timeouts", c.timeouts},
          {"events", c.events},
          {"missed_events", c.missed_events},
          {"budget_waits", c.budget_waits}};
}

}  // namespace liftd::api
