#include "api/server.hpp"

#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <spdlog/spdlog.h>

#include "api/commands.hpp"
#include "api/server_impl.hpp"

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

std::string errno_text(int error) {
  return std::strerror(error);
}

/// Throws unless `path` is free: removes a socket file nobody listens on.
void clear_stale_socket(const std::string& path) {
  struct stat st {};
  if (lstat(path.c_str(), &st) != 0) {
    if (errno == ENOENT) return;
    throw std::runtime_error("api: cannot inspect " + path + ": " + errno_text(errno));
  }
  if (!S_ISSOCK(st.st_mode)) {
    throw std::runtime_error("api: " + path + " exists and is not a socket; not removing it");
  }
  const int fd = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0) throw std::runtime_error("api: socket(): " + errno_text(errno));
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  std::strncpy(addr.sun_path, path.c_str(), sizeof addr.sun_path - 1);
  const int rc = ::connect(fd, reinterpret_cast<const sockaddr*>(&addr), sizeof addr);
  const int error = errno;
  ::close(fd);
  if (rc == 0) {
    throw std::runtime_error("api: another process is listening on " + path +
                             " (is liftd already running?)");
  }
  if (error != ECONNREFUSED) {
    throw std::runtime_error("api: cannot probe " + path + ": " + errno_text(error));
  }
  if (::unlink(path.c_str()) != 0) {
    throw std::runtime_error("api: cannot remove stale socket " + path + ": " + errno_text(errno));
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

void Server::Impl::start() {
  if (listening_) return;
  const std::string& path = config_.socket_path;
  asio::error_code ec;
  if (config_.listen_fd >= 0) {
    // Socket activation: systemd bound, set up and listens on it; its file stays systemd's.
    acceptor_.assign(asio::local::stream_protocol(), config_.listen_fd, ec);
    if (ec) {
      throw std::runtime_error("api: cannot use the socket systemd passed (fd " +
                               std::to_string(config_.listen_fd) + "): " + ec.message());
    }
    config_.listen_fd = -1;  // the acceptor owns it now
    listening_ = true;
    log_(LogLevel::Info, "api: listening on the socket systemd passed (" + path + ")");
    accept_next();
    return;
  }
  if (path.empty() || path.size() >= sizeof(sockaddr_un{}.sun_path)) {
    throw std::runtime_error("api: socket path \"" + path + "\" is empty or too long");
  }
  std::optional<gid_t> socket_gid;
  if (!config_.socket_group.empty()) socket_gid = resolve_group(config_.socket_group);
  clear_stale_socket(path);
  acceptor_.open(asio::local::stream_protocol(), ec);
  if (!ec) acceptor_.bind(asio::local::stream_protocol::endpoint(path), ec);
  if (ec) {
    acceptor_.close();
    throw std::runtime_error("api: cannot bind " + path + ": " + ec.message() +
                             " (does the directory exist?)");
  }
  created_socket_file_ = true;
  struct stat bound {};
  if (::lstat(path.c_str(), &bound) == 0) {
    socket_dev_ = bound.st_dev;
    socket_ino_ = bound.st_ino;
  }
  // Nobody can connect before listen(), so fixing the mode and group here leaves no window.
  if (::chmod(path.c_str(), static_cast<mode_t>(config_.socket_mode)) != 0) {
    const int error = errno;
    stop();
    throw std::runtime_error("api: chmod " + path + ": " + errno_text(error));
  }
  if (socket_gid && ::chown(path.c_str(), static_cast<uid_t>(-1), *socket_gid) != 0) {
    const int error = errno;
    stop();
    throw std::runtime_error("api: cannot give " + path + " to group " + config_.socket_group +
                             ": " + errno_text(error));
  }
  acceptor_.listen(asio::socket_base::max_listen_connections, ec);
  if (ec) {
    stop();
    throw std::runtime_error("api: listen on " + path + ": " + ec.message());
  }
  listening_ = true;
  log_(LogLevel::Info, "api: listening on " + path);
  accept_next();
}

void Server::Impl::wait_for_budget(std::shared_ptr<Session> session) {
  budget_queue_.push_back(std::move(session));
  arm_budget_timer();
}

void Server::Impl::arm_budget_timer() {
  if (budget_timer_armed_ || budget_queue_.empty()) return;
  budget_timer_armed_ = true;
  budget_timer_.expires_at(budget_.next_at(SteadyClock::now()));
  budget_timer_.async_wait([weak = weak_from_this()](const asio::error_code& ec) {
    const auto self = weak.lock();
    if (!self || ec) return;
    self->budget_timer_armed_ = false;
    self->on_budget_timer();
  });
}

void Server::Impl::on_budget_timer() {
  // Each client that waited takes its turn in order while there is budget; one that runs out
  // again goes to the back. At most one round per expiry: the next comes with the budget.
  for (std::size_t n = budget_queue_.size(); n > 0 && !budget_queue_.empty(); --n) {
    const auto now = SteadyClock::now();
    if (budget_.next_at(now) > now) break;
    const auto session = std::move(budget_queue_.front());
    budget_queue_.pop_front();
    session->take_turn();
  }
  arm_budget_timer();
}

void Server::Impl::stop() {
  asio::error_code ignored;
  acceptor_.close(ignored);
  retry_timer_.cancel();
  budget_timer_.cancel();
  budget_queue_.clear();
  const auto sessions = std::vector<std::shared_ptr<Session>>(sessions_.begin(), sessions_.end());
  for (const auto& session : sessions) session->close("server stopping");
  sessions_.clear();
  if (created_socket_file_) {
    created_socket_file_ = false;
    const std::string& path = config_.socket_path;
    struct stat now {};
    if (::lstat(path.c_str(), &now) != 0) {
      log_(LogLevel::Info, "api: " + path + " is already gone");
    } else if (now.st_dev != socket_dev_ || now.st_ino != socket_ino_) {
      log_(LogLevel::Warn, "api: not removing " + path +
                               ": it is no longer the socket this daemon created (another "
                               "process has bound it since)");
    } else {
      ::unlink(path.c_str());
    }
  }
  if (config_.listen_fd >= 0) {  // passed by systemd but never taken over
    ::close(config_.listen_fd);
    config_.listen_fd = -1;
  }
  if (listening_) log_(LogLevel::Info, "api: stopped");
  listening_ = false;
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
