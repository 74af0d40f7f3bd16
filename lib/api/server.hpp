// The JSON-lines API server on a Unix stream socket. Runs on an io_context the daemon owns and
// never creates threads; every public method must be called on that io_context's thread.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <string_view>

#include <asio.hpp>
#include <nlohmann/json.hpp>

#include "api/backend.hpp"
#include "api/dispatcher.hpp"

namespace liftd::api {

/// Server settings (the daemon fills them from its config file).
struct ServerConfig {
  std::string socket_path = "/run/liftd/api.sock";  ///< where to listen
  /// A listening Unix stream socket passed by systemd (socket activation), or -1: then the
  /// server binds socket_path itself. A passed socket keeps the owner, group and mode its socket
  /// unit gave it, and its file is systemd's: stop() leaves it in place.
  int listen_fd = -1;
  std::string socket_group;      ///< group owning the socket file; empty: the daemon's group
  unsigned socket_mode = 0660;   ///< file mode of the socket (owner and group may connect)
  std::string read_group;        ///< members may run read commands; empty: root only
  std::string control_group;     ///< members may run control and read commands
  std::string inputs_group;      ///< members may send inputs and run read commands
  std::size_t max_clients = 32;  ///< more connections get `busy` and are closed
  /// Request lines answered per second over all clients; more wait their turn (nothing is
  /// refused), every waiting client an equal share. 0 = no limit.
  double max_requests_per_second = 0;
  /// Connections one uid may hold at once (root is exempt); more get `busy`.
  std::size_t max_clients_per_uid = 8;
  /// Of max_clients, this many are kept for peers with control access (the control group, root,
  /// the daemon's user): a read-only user cannot lock the dispatcher or a technician out.
  std::size_t reserved_clients = 4;
  std::size_t max_line_bytes = 64 * 1024;  ///< longest request line; longer: `too_large`
  int max_depth = 32;                      ///< deepest JSON nesting in a request
  std::size_t max_in_flight = 32;          ///< unanswered requests per client
  /// Per client. When its replies fill the queue to this, the server stops reading its requests
  /// until the queue has drained to half; events beyond it drop a watcher that falls behind.
  std::size_t write_queue_max_bytes = 1024 * 1024;
  /// Per client, in lines; the same rule as write_queue_max_bytes.
  std::size_t write_queue_max_messages = 4096;
  /// A client whose queued lines have not been taken for this long is dropped.
  std::chrono::milliseconds stalled_reader_timeout{std::chrono::seconds(30)};
  /// A client that sends nothing for this long (and is not watching) is closed; 0 disables.
  std::chrono::milliseconds idle_timeout{0};
  /// A request line must be complete this long after its first byte arrived.
  std::chrono::milliseconds partial_line_timeout{std::chrono::seconds(5)};
  /// `hello`'s `car`: who this lift is ({"name", "drive_kind", "floors"}); null: not told.
  nlohmann::json car = nullptr;
};

/// Severity of a server log line.
enum class LogLevel : std::uint8_t { Debug, Info, Warn, Error };
/// Where the server logs; by default spdlog's default logger.
using LogFn = std::function<void(LogLevel level, std::string_view message)>;

/// Counters the server keeps (also reported by `stats` as "api").
struct ServerCounters {
  std::uint64_t connections = 0;    ///< connections accepted since start
  std::uint64_t rejected = 0;       ///< connections refused (limits, no credentials)
  std::uint64_t requests = 0;       ///< request lines handled
  std::uint64_t errors = 0;         ///< replies with ok:false
  std::uint64_t dropped = 0;        ///< clients dropped: a stalled reader
  std::uint64_t missed_events = 0;  ///< events not sent to a watcher that fell behind
  std::uint64_t budget_waits = 0;   ///< turns a client waited for (max_requests_per_second)
  std::uint64_t timeouts = 0;       ///< clients closed by the idle or partial-line timeout
  std::uint64_t events = 0;         ///< events published
  std::size_t clients = 0;          ///< clients connected now
  std::size_t watchers = 0;         ///< clients watching now
};

/// The API server.
class Server {
 public:
  /// Registers the built-in commands; listens only after start(). Resolves the access groups
  /// here: throws std::runtime_error naming an unknown group.
  Server(asio::io_context& io, Backend& backend, ServerConfig config, LogFn log = {});
  ~Server();
  Server(const Server&) = delete;
  Server& operator=(const Server&) = delete;

  /// Binds and listens (or takes over config.listen_fd). A stale socket file (nothing
  /// listening) is removed; if another process listens there, or the path is not a socket,
  /// throws std::runtime_error saying so.
  void start();
  /// Closes the listener and every client and removes the socket file, but only if the path is
  /// still the socket this server bound (same device and inode): a socket another daemon has
  /// bound there since is left alone. Idempotent.
  void stop();
  /// Applies new access groups, client limit and idle timeout (a configuration reload). The
  /// groups are resolved first: an unknown group throws std::runtime_error and changes nothing.
  /// Connected clients get the new access and timeout from their next request on; clients above
  /// a lower max_clients stay connected, and new ones are refused with `busy` until there is room.
  void reconfigure(const ServerConfig& next);

  /// The command table: add later commands (travel, stop, ...) here before or after start().
  Dispatcher& dispatcher();
  /// Sends {"event":name,"data":data} to every watching client.
  void publish(std::string_view event, const nlohmann::json& data);
  /// Sends {"event":name,"data":data} to every client, watching or not (the `stopping` event:
  /// the last line a connection gets before liftd closes it).
  void announce(std::string_view event, const nlohmann::json& data);
  /// Current counters.
  ServerCounters counters() const;

  class Impl;

 private:
  std::shared_ptr<Impl> impl_;
};

/// The counters as the "api" object of `stats`.
nlohmann::json to_json(const ServerCounters& counters);

}  // namespace liftd::api
