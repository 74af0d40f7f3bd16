#include "api/server.hpp"

#include <poll.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>
#include <deque>
#include <optional>
#include <set>
#include <stdexcept>
#include <utility>
#include <vector>

#include <spdlog/spdlog.h>

#include "api/access.hpp"
#include "api/commands.hpp"
#include "api/request_budget.hpp"
#include "common/version.hpp"

namespace liftd::api {

using Socket = asio::local::stream_protocol::socket;
using SteadyClock = std::chrono::steady_clock;

namespace {

/// Bytes read from a socket per read call.
constexpr std::size_t kReadChunkBytes = 4096;
/// How long a connection being closed may take to flush its last error line.
constexpr std::chrono::seconds kFlushGrace{1};
/// Pause before accepting again after accept() failed (e.g. out of file descriptors).
constexpr std::chrono::milliseconds kAcceptRetry{100};
/// Request lines of one client handled in one turn of the io thread. A client that pipelines
/// more waits for its next turn behind everything else the io thread has queued (the other
/// clients' turns, the cycle's wake-ups that carry the watchers' events), so every client gets
/// a fair share and none holds the thread for a whole batch.
constexpr std::size_t kLinesPerTurn = 4;

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

class Session;

}  // namespace

class Server::Impl : public std::enable_shared_from_this<Server::Impl> {
 public:
  Impl(asio::io_context& io, Backend& backend, ServerConfig config, LogFn log)
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

  void register_builtins() {
    std::weak_ptr<Impl> weak = weak_from_this();
    add_builtin_commands(dispatcher_, backend_, [weak]() {
      const auto self = weak.lock();
      return self ? to_json(self->counters()) : nlohmann::json::object();
    });
  }

  void start();
  void stop();
  void reconfigure(const ServerConfig& next);
  void publish(std::string_view event, const nlohmann::json& data);
  ServerCounters counters() const;
  void accept_next();
  void on_accept(const asio::error_code& ec, Socket socket);
  void reject(Socket socket, ErrorCode code, const std::string& message);
  /// Why a new connection from `peer` is refused (limits), or nothing.
  std::optional<std::string> admission_refusal(const Peer& peer) const;
  void remove(const std::shared_ptr<Session>& session) { sessions_.erase(session); }
  /// Takes one request's share of the budget (api.max_requests_per_s), or false.
  bool take_budget() { return budget_.take(SteadyClock::now()); }
  /// `session` ran out of budget: it takes its next turn when there is some again, behind the
  /// clients that ran out before it (one queue, so every waiting client gets an equal share).
  void wait_for_budget(std::shared_ptr<Session> session);
  void arm_budget_timer();
  void on_budget_timer();

  asio::io_context& io_;
  Backend& backend_;
  ServerConfig config_;
  LogFn log_;
  AccessPolicy policy_;
  Dispatcher dispatcher_;
  asio::local::stream_protocol::acceptor acceptor_;
  asio::steady_timer retry_timer_;
  RequestBudget budget_;
  asio::steady_timer budget_timer_;
  bool budget_timer_armed_ = false;
  std::deque<std::shared_ptr<Session>> budget_queue_;  // waiting for budget, oldest first
  std::set<std::shared_ptr<Session>> sessions_;
  ServerCounters counters_{};
  std::uint64_t next_session_id_ = 1;
  bool listening_ = false;
  bool created_socket_file_ = false;
  dev_t socket_dev_ = 0;  // the socket file this server bound, to remove only that one
  ino_t socket_ino_ = 0;
};

namespace {

/// One connected client.
class Session final : public std::enable_shared_from_this<Session>, public SessionControl {
  friend class Server::Impl;  // on_budget_timer() gives waiting clients their turn

 public:
  Session(std::shared_ptr<Server::Impl> server, Socket socket, Peer peer, std::vector<gid_t> groups,
          std::uint64_t id)
      : server_(std::move(server)),
        socket_(std::move(socket)),
        timer_(server_->io_),
        peer_(peer),
        groups_(std::move(groups)),
        id_(id),
        last_request_(SteadyClock::now()) {}

  void start() {
    nlohmann::json hello = {{"version", std::string(kVersion)},
                            {"api", kApiVersion},
                            {"access", peer_.access.to_json()},
                            {"max_line_bytes", server_->config_.max_line_bytes}};
    enqueue(std::make_shared<const std::string>(event_line("hello", hello)), false);
    read_more();
    arm_timer();
  }

  /// Takes new settings: access from the server's current policy, the idle timeout. A watcher
  /// that may no longer read is told why and its stream ends.
  void settings_changed() {
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

  /// The peer's credentials and access.
  const Peer& peer() const { return peer_; }

  /// Closes the socket now and forgets the session.
  void close(std::string_view reason) {
    if (closed_) return;
    closed_ = true;
    if (watching_) --server_->counters_.watchers;
    watching_ = false;
    --server_->counters_.clients;
    server_->log_(LogLevel::Debug, describe() + " closed: " + std::string(reason));
    asio::error_code ignored;
    timer_.cancel();
    socket_.shutdown(asio::socket_base::shutdown_both, ignored);
    socket_.close(ignored);
    queue_.clear();
    queued_bytes_ = 0;
    server_->remove(shared_from_this());
  }

  /// Queues a line. Replies are always queued: reading pauses while the queue is full, so they
  /// stay bounded. An event that does not fit is not queued but counted: once the watcher has
  /// taken half its queue, a `missed` event with the count comes before the next event, so it
  /// knows to read `status` again. A watcher that takes nothing at all is closed as a stalled
  /// reader.
  void enqueue(std::shared_ptr<const std::string> line, bool is_event) {
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

  void set_watching(bool enable) override {
    if (enable == watching_) return;
    watching_ = enable;
    if (enable) {
      ++server_->counters_.watchers;
    } else {
      --server_->counters_.watchers;
    }
  }
  bool watching() const override { return watching_; }
  void send_event(std::string line) override {
    enqueue(std::make_shared<const std::string>(std::move(line)), true);
  }
  std::size_t requests_in_flight() const override { return in_flight_; }

 private:
  void push_line(std::shared_ptr<const std::string> line) {
    queued_bytes_ += line->size();
    queue_.push_back(std::move(line));
    if (!writing_) write_next();
  }

  std::string describe() const {
    return "api client #" + std::to_string(id_) + " (pid " + std::to_string(peer_.pid) + ", uid " +
           std::to_string(peer_.uid) + ")";
  }

  /// True while the replies already queued or owed fill the write queue: take no more requests.
  bool backlogged() const {
    const ServerConfig& cfg = server_->config_;
    return queue_.size() + in_flight_ >= cfg.write_queue_max_messages ||
           queued_bytes_ >= cfg.write_queue_max_bytes;
  }
  /// True once the queue has drained to half: take requests again.
  bool drained() const {
    const ServerConfig& cfg = server_->config_;
    return queue_.size() + in_flight_ <= cfg.write_queue_max_messages / 2 &&
           queued_bytes_ <= cfg.write_queue_max_bytes / 2;
  }

  void read_more() {
    if (reading_ || closed_ || closing_ || peer_done_) return;
    reading_ = true;
    socket_.async_read_some(asio::buffer(chunk_),
                            [self = shared_from_this()](const asio::error_code& ec, std::size_t n) {
                              self->reading_ = false;
                              self->on_read(ec, n);
                            });
  }

  void on_read(const asio::error_code& ec, std::size_t n) {
    if (closed_) return;
    if (ec == asio::error::eof) {
      // A client that closed its socket is gone (POLLHUP: both directions shut down): nothing
      // can reach it. One that only shut down writing (half-close) has said all it will:
      // answer what it sent (a last line without a newline counts), then close once every
      // reply is written.
      pollfd probe{socket_.native_handle(), POLLOUT, 0};
      if (::poll(&probe, 1, 0) > 0 && (probe.revents & (POLLHUP | POLLERR)) != 0) {
        close("client disconnected");
        return;
      }
      peer_done_ = true;
      if (!closing_ && !pending_.empty()) {
        pending_ += '\n';
        process_lines();
        if (closed_) return;
      }
      if (!turn_owed_) pending_.clear();  // else its next turn handles the rest
      close_if_done();
      if (!closed_) arm_timer();
      return;
    }
    if (ec) {
      close("read failed: " + ec.message());
      return;
    }
    if (closing_) return;
    if (pending_.empty() && n > 0) partial_since_ = SteadyClock::now();
    pending_.append(chunk_.data(), n);
    process_lines();
    if (closed_) return;
    if (!closing_ && !paused_ && !turn_owed_) read_more();
    arm_timer();
  }

  /// Handles the complete lines in pending_ until they run out or the write queue is full.
  void process_lines() {
    const std::size_t max_line = server_->config_.max_line_bytes;
    std::size_t start = 0;
    std::size_t lines = 0;
    paused_ = false;
    while (!closed_ && !closing_) {
      if (backlogged()) {
        // Backpressure: leave the rest unread until the client has taken its replies.
        paused_ = true;
        break;
      }
      const std::size_t newline = pending_.find('\n', start);
      if (newline == std::string::npos) break;
      if (lines++ == kLinesPerTurn) {
        // Fair share: the rest waits for this client's next turn; reading waits with it.
        owe_turn();
        break;
      }
      if (!server_->take_budget()) {
        // The requests of all clients together reached api.max_requests_per_s.
        wait_for_budget();
        break;
      }
      std::string_view line(pending_.data() + start, newline - start);
      start = newline + 1;
      if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
      if (line.size() > max_line) {
        fail_and_close(ErrorCode::TooLarge, too_large_message());
        break;
      }
      last_request_ = SteadyClock::now();
      if (line.find_first_not_of(" \t") == std::string_view::npos) continue;
      handle(line);
    }
    if (closed_) return;
    pending_.erase(0, start);
    if (!closing_ && !paused_ && !turn_owed_ && pending_.size() > max_line) {
      fail_and_close(ErrorCode::TooLarge, too_large_message());
    }
    if (closed_) return;
    if (start > 0 && !pending_.empty()) partial_since_ = SteadyClock::now();
  }

  /// Queues this client's next turn behind the io thread's other work (once).
  void owe_turn() {
    if (turn_owed_) return;
    turn_owed_ = true;
    asio::post(server_->io_, [self = shared_from_this()] { self->take_turn(); });
  }

  /// Its next turn waits for the request budget (once).
  void wait_for_budget() {
    if (turn_owed_) return;
    turn_owed_ = true;
    ++server_->counters_.budget_waits;
    server_->wait_for_budget(shared_from_this());
  }

  /// The turn owe_turn() or wait_for_budget() promised.
  void take_turn() {
    turn_owed_ = false;
    if (closed_) return;
    handle_waiting_lines();
  }

  /// After a line was written or a reply queued: resume a paused client once drained.
  void maybe_resume() {
    if (!paused_ || closed_ || closing_ || !drained()) return;
    handle_waiting_lines();
  }

  /// The lines waiting in pending_, then reading on (or finishing a client that is done).
  void handle_waiting_lines() {
    process_lines();
    if (closed_) return;
    if (peer_done_) {
      close_if_done();
    } else if (!paused_ && !turn_owed_ && !closing_) {
      read_more();
    }
    if (!closed_) arm_timer();
  }

  /// Closes a half-closed client once nothing is owed to it any more.
  void close_if_done() {
    if (closed_ || !peer_done_ || paused_ || turn_owed_) return;
    if (in_flight_ == 0 && queue_.empty() && !writing_) close("client finished (half-close)");
  }

  std::string too_large_message() const {
    return "request line longer than " + std::to_string(server_->config_.max_line_bytes) +
           " bytes; closing";
  }

  void handle(std::string_view line) {
    ++server_->counters_.requests;
    ++in_flight_;
    // Holds the session weakly: a backend may answer after the client (or the server) is gone.
    std::weak_ptr<Session> weak = shared_from_this();
    server_->dispatcher_.handle_line(line, peer_, *this, [weak](std::string reply, bool ok) {
      const auto self = weak.lock();
      if (!self || self->closed_) return;
      if (!ok) ++self->server_->counters_.errors;
      --self->in_flight_;
      self->enqueue(std::make_shared<const std::string>(std::move(reply)), false);
      if (!self->closed_) self->arm_timer();
    });
  }

  /// Sends an error with a null id, then closes once it is written (or after a grace period).
  void fail_and_close(ErrorCode code, const std::string& message) {
    ++server_->counters_.errors;
    enqueue(std::make_shared<const std::string>(reply_line(nullptr, Result::fail(code, message))),
            false);
    if (closed_) return;
    closing_ = true;
    close_deadline_ = SteadyClock::now() + kFlushGrace;
    server_->log_(LogLevel::Info, describe() + ": " + message);
    arm_timer();
  }

  void write_next() {
    if (queue_.empty() || closed_) {
      writing_ = false;
      if (closing_ && !closed_) close("closed after error");
      if (!closed_) close_if_done();
      return;
    }
    if (!writing_) write_since_ = SteadyClock::now();
    writing_ = true;
    const auto line = queue_.front();
    asio::async_write(socket_, asio::buffer(*line),
                      [self = shared_from_this(), line](const asio::error_code& ec, std::size_t) {
                        if (self->closed_) return;
                        if (ec) {
                          self->close("write failed: " + ec.message());
                          return;
                        }
                        self->queued_bytes_ -= line->size();
                        self->queue_.pop_front();
                        self->write_since_ = SteadyClock::now();  // the client took a line
                        self->write_next();
                        self->maybe_resume();
                        if (!self->closed_) self->arm_timer();
                      });
  }

  /// The moment the connection must be closed, if any.
  std::optional<SteadyClock::time_point> deadline() const {
    const ServerConfig& cfg = server_->config_;
    if (closing_) return close_deadline_;
    if (writing_) return write_since_ + cfg.stalled_reader_timeout;
    if (peer_done_ || paused_ || turn_owed_) return std::nullopt;
    if (!pending_.empty()) return partial_since_ + cfg.partial_line_timeout;
    if (cfg.idle_timeout.count() > 0 && !watching_ && in_flight_ == 0) {
      return last_request_ + cfg.idle_timeout;
    }
    return std::nullopt;
  }

  /// Makes sure the timer fires no later than the session's deadline. A timer already armed
  /// for an earlier moment stays (on_timer looks again when it fires), so the request path
  /// touches the timer only when a deadline moves closer: re-arming it for every request cost
  /// a timer update and a cancelled wait each time (api-bench against liftd --simulate).
  void arm_timer() {
    const auto due = deadline();
    if (!due || (armed_ && *armed_ <= *due)) return;
    armed_ = due;
    timer_.expires_at(*due);
    timer_.async_wait([self = shared_from_this()](const asio::error_code& ec) {
      if (!ec) self->on_timer();
    });
  }

  void on_timer() {
    if (closed_) return;
    armed_.reset();
    const auto now = SteadyClock::now();
    const auto due = deadline();
    if (!due || now < *due) {
      arm_timer();
      return;
    }
    if (closing_) {
      close("client did not take its last error line");
      return;
    }
    const ServerConfig& cfg = server_->config_;
    if (writing_) {
      // It cannot take a message either: log it and close.
      ++server_->counters_.dropped;
      server_->log_(LogLevel::Warn, describe() + " dropped: it took none of its " +
                                        std::to_string(queue_.size()) + " queued lines for " +
                                        std::to_string(cfg.stalled_reader_timeout.count()) + " ms");
      close("stalled reader");
      return;
    }
    ++server_->counters_.timeouts;
    if (!pending_.empty()) {
      fail_and_close(ErrorCode::Timeout, "request line not finished with a newline within " +
                                             std::to_string(cfg.partial_line_timeout.count()) +
                                             " ms; closing");
    } else {
      fail_and_close(ErrorCode::Timeout, "no request for " +
                                             std::to_string(cfg.idle_timeout.count()) +
                                             " ms; closing idle connection");
    }
  }

  std::shared_ptr<Server::Impl> server_;
  Socket socket_;
  asio::steady_timer timer_;
  Peer peer_;
  std::vector<gid_t> groups_;
  std::uint64_t id_;
  std::array<char, kReadChunkBytes> chunk_{};
  std::string pending_;
  std::deque<std::shared_ptr<const std::string>> queue_;
  std::size_t queued_bytes_ = 0;
  std::size_t in_flight_ = 0;
  bool writing_ = false;
  bool reading_ = false;    // an async read is outstanding
  bool paused_ = false;     // requests wait in pending_ until the write queue drains
  bool turn_owed_ = false;  // more lines wait in pending_ for this client's next turn
  bool peer_done_ = false;  // the client half-closed: no more requests will come
  bool watching_ = false;
  std::uint64_t missed_ = 0;  // events not sent since the queue was full
  bool closing_ = false;
  bool closed_ = false;
  SteadyClock::time_point last_request_;
  SteadyClock::time_point partial_since_{};
  SteadyClock::time_point close_deadline_{};
  SteadyClock::time_point write_since_{};  // the queue's head has waited since then
  std::optional<SteadyClock::time_point> armed_;
};

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

void Server::Impl::accept_next() {
  acceptor_.async_accept([self = shared_from_this()](const asio::error_code& ec, Socket socket) {
    self->on_accept(ec, std::move(socket));
  });
}

void Server::Impl::on_accept(const asio::error_code& ec, Socket socket) {
  if (!listening_ || ec == asio::error::operation_aborted) return;
  if (ec) {
    log_(LogLevel::Warn, "api: accept failed: " + ec.message());
    retry_timer_.expires_after(kAcceptRetry);
    retry_timer_.async_wait([self = shared_from_this()](const asio::error_code& wait_ec) {
      if (!wait_ec && self->listening_) self->accept_next();
    });
    return;
  }
  accept_next();
  const auto creds = peer_credentials(socket.native_handle());
  if (!creds) {
    reject(std::move(socket), ErrorCode::Forbidden, "peer credentials unavailable");
    return;
  }
  Peer peer;
  peer.pid = creds->pid;
  peer.uid = creds->uid;
  peer.gid = creds->gid;
  peer.access = policy_.access_for(creds->uid, creds->groups);
  if (const auto refusal = admission_refusal(peer)) {
    reject(std::move(socket), ErrorCode::Busy, *refusal);
    return;
  }
  ++counters_.connections;
  ++counters_.clients;
  auto session = std::make_shared<Session>(shared_from_this(), std::move(socket), peer,
                                           creds->groups, next_session_id_++);
  sessions_.insert(session);
  log_(LogLevel::Debug, "api: client pid " + std::to_string(peer.pid) + " uid " +
                            std::to_string(peer.uid) + " connected");
  session->start();
}

std::optional<std::string> Server::Impl::admission_refusal(const Peer& peer) const {
  if (sessions_.size() >= config_.max_clients) {
    return "too many clients (limit " + std::to_string(config_.max_clients) + "); try later";
  }
  // The last reserved_clients slots are for control access, so that a read-only user holding
  // connections cannot lock the dispatcher or a technician out.
  const std::size_t open_slots = config_.max_clients > config_.reserved_clients
                                     ? config_.max_clients - config_.reserved_clients
                                     : 0;
  if (!peer.access.control && sessions_.size() >= open_slots) {
    return "too many clients: the last " + std::to_string(config_.reserved_clients) + " of " +
           std::to_string(config_.max_clients) +
           " connections are kept for control access; try later";
  }
  if (peer.uid != 0) {
    const auto same_uid = static_cast<std::size_t>(std::count_if(
        sessions_.begin(), sessions_.end(),
        [&](const std::shared_ptr<Session>& s) { return s->peer().uid == peer.uid; }));
    if (same_uid >= config_.max_clients_per_uid) {
      return "uid " + std::to_string(peer.uid) + " already has " + std::to_string(same_uid) +
             " connections (limit " + std::to_string(config_.max_clients_per_uid) +
             " per user); close one first";
    }
  }
  return std::nullopt;
}

void Server::Impl::reject(Socket socket, ErrorCode code, const std::string& message) {
  ++counters_.rejected;
  log_(LogLevel::Warn, "api: connection refused: " + message);
  auto held = std::make_shared<Socket>(std::move(socket));
  auto line = std::make_shared<const std::string>(reply_line(nullptr, Result::fail(code, message)));
  // The line fits an empty socket buffer, so this completes at once; then the socket closes.
  asio::async_write(*held, asio::buffer(*line), [held, line](const asio::error_code&, std::size_t) {
    asio::error_code ignored;
    held->shutdown(asio::socket_base::shutdown_both, ignored);
    held->close(ignored);
  });
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
