// The API server's internals its pieces share: Server::Impl and one client's Session.
#pragma once

#include <sys/types.h>

#include <array>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <asio.hpp>
#include <nlohmann/json.hpp>

#include "api/access.hpp"
#include "api/request_budget.hpp"
#include "api/server.hpp"

namespace liftd::api {

using Socket = asio::local::stream_protocol::socket;
using SteadyClock = std::chrono::steady_clock;

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

// One connected client; internal to the server.
class Session;

class Server::Impl : public std::enable_shared_from_this<Server::Impl> {
 public:
  Impl(asio::io_context& io, Backend& backend, ServerConfig config, LogFn log);

  void register_builtins();

  void start();
  void stop();
  void reconfigure(const ServerConfig& next);
  void publish(std::string_view event, const nlohmann::json& data);
  void announce(std::string_view event, const nlohmann::json& data);
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

  void start();
  /// Takes new settings: access from the server's current policy, the idle timeout. A watcher
  /// that may no longer read is told why and its stream ends.
  void settings_changed();
  /// The peer's credentials and access.
  const Peer& peer() const { return peer_; }

  /// Closes the socket now and forgets the session.
  void close(std::string_view reason);
  /// Queues a line. Replies are always queued: reading pauses while the queue is full, so they
  /// stay bounded. An event that does not fit is not queued but counted: once the watcher has
  /// taken half its queue, a `missed` event with the count comes before the next event, so it
  /// knows to read `status` again. A watcher that takes nothing at all is closed as a stalled
  /// reader.
  void enqueue(std::shared_ptr<const std::string> line, bool is_event);
  void set_watching(bool enable) override;
  bool watching() const override { return watching_; }
  void send_event(std::string line) override;
  std::size_t requests_in_flight() const override { return in_flight_; }

 private:
  void push_line(std::shared_ptr<const std::string> line);
  std::string describe() const;
  /// True while the replies already queued or owed fill the write queue: take no more requests.
  bool backlogged() const;
  /// True once the queue has drained to half: take requests again.
  bool drained() const;
  void read_more();
  void on_read(const asio::error_code& ec, std::size_t n);
  /// Handles the complete lines in pending_ until they run out or the write queue is full.
  void process_lines();
  /// Queues this client's next turn behind the io thread's other work (once).
  void owe_turn();
  /// Its next turn waits for the request budget (once).
  void wait_for_budget();
  /// The turn owe_turn() or wait_for_budget() promised.
  void take_turn();
  /// After a line was written or a reply queued: resume a paused client once drained.
  void maybe_resume();
  /// The lines waiting in pending_, then reading on (or finishing a client that is done).
  void handle_waiting_lines();
  /// Closes a half-closed client once nothing is owed to it any more.
  void close_if_done();
  std::string too_large_message() const;
  void handle(std::string_view line);
  /// Sends an error with a null id, then closes once it is written (or after a grace period).
  void fail_and_close(ErrorCode code, const std::string& message);
  void write_next();
  /// The moment the connection must be closed, if any.
  std::optional<SteadyClock::time_point> deadline() const;
  /// Makes sure the timer fires no later than the session's deadline. A timer already armed
  /// for an earlier moment stays (on_timer looks again when it fires), so the request path
  /// touches the timer only when a deadline moves closer: re-arming it for every request cost
  /// a timer update and a cancelled wait each time (api-bench against liftd --simulate).
  void arm_timer();
  void on_timer();

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

}  // namespace liftd::api
