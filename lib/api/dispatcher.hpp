// The command table and the request handler: one request line in, one reply line out.
// No sockets here, so it can be fuzzed and unit-tested on its own.
#pragma once

#include <sys/types.h>

#include <cstddef>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "api/result.hpp"
#include "api/schema.hpp"
#include "drive/drive.hpp"

namespace liftd::api {

/// Who may run a command.
enum class Access : std::uint8_t {
  Read,     ///< read group, control group, inputs group and root
  Control,  ///< control group and root
  Inputs,   ///< inputs group and root
};
/// "read", "control", "inputs".
std::string_view to_string(Access access) noexcept;

/// What a connected peer may do, decided once per connection from its credentials.
struct AccessSet {
  bool read = false;     ///< may run Read commands
  bool control = false;  ///< may run Control commands
  bool inputs = false;   ///< may run Inputs commands
  /// Whether a command of level `level` is allowed.
  bool allows(Access level) const noexcept;
  /// ["read", "control", ...] for the greeting.
  nlohmann::json to_json() const;
};

/// The connected process, from SO_PEERCRED.
struct Peer {
  pid_t pid = 0;     ///< process id
  uid_t uid = 0;     ///< user id
  gid_t gid = 0;     ///< primary group id
  AccessSet access;  ///< what it may do
};

/// Per-connection state a command may look at or change (valid only during the handler call).
class SessionControl {
 public:
  virtual ~SessionControl() = default;
  /// Turns the event stream on or off for this connection.
  virtual void set_watching(bool enable) = 0;
  /// Whether events are being sent to this connection.
  virtual bool watching() const = 0;
  /// Queues an event line (from event_line) behind the replies sent so far.
  virtual void send_event(std::string line) = 0;
  /// Requests started on this connection and not answered yet (including the current one).
  virtual std::size_t requests_in_flight() const = 0;
};

/// What a handler gets: the validated request (arguments are fields of it) and its context.
struct Call {
  const nlohmann::json& request;  ///< the whole request object; arguments validated
  const Peer& peer;               ///< who asked
  SessionControl& session;        ///< the asking connection
};

/// A command implementation; calls `done` exactly once, now or later.
using Handler = std::function<void(const Call& call, Responder done)>;

/// The handler of a command only one drive kind offers, served by that kind's own backend
/// interface (`backend`, nullptr on a lift of another kind). On such a lift the dispatcher
/// refuses the command by its capability before the handler runs; a dispatcher without a drive
/// kind gets `not_offered` with `refusal`.
template <typename KindBackend, typename Serve>
Handler served_by(KindBackend* backend, std::string refusal, Serve serve) {
  return [backend, refusal = std::move(refusal), serve = std::move(serve)](const Call& call,
                                                                           Responder done) {
    if (backend == nullptr) {
      done(Result::fail(ErrorCode::NotOffered, refusal));
      return;
    }
    serve(*backend, call, std::move(done));
  };
}

/// CommandSpec::needs of a command every drive kind offers.
inline constexpr std::optional<drive::Capability> kEveryDriveKind = std::nullopt;

/// One entry of the command table.
struct CommandSpec {
  std::string name;              ///< "status", "travel", ...
  Access access = Access::Read;  ///< who may run it
  ArgSchema args;                ///< its arguments
  std::string summary;           ///< one line for help
  Handler handler;               ///< what it does
  /// Offered only by drive kinds with this capability; nullopt: by every kind.
  std::optional<drive::Capability> needs;
};

/// Limits applied by the dispatcher.
struct DispatchLimits {
  int max_depth = 32;              ///< deepest object/array nesting accepted in a request
  std::size_t max_in_flight = 32;  ///< unanswered requests per connection before `busy`
};

/// The first key that appears twice in one object of `line`, or nothing (also nothing for text
/// that is not JSON: the parser reports that).
std::optional<std::string> find_duplicate_key(std::string_view line);

/// The command table and request handling.
class Dispatcher {
 public:
  /// Function that receives a reply line (with '\n') and whether it reports success.
  using SendFn = std::function<void(std::string line, bool ok)>;

  explicit Dispatcher(DispatchLimits limits = {}) : limits_(limits) {}

  /// Adds a command; throws std::invalid_argument on an empty or duplicate name or a missing
  /// handler (a startup error).
  void add(CommandSpec spec);
  /// The command named `name`, or nullptr.
  const CommandSpec* find(std::string_view name) const;
  /// Every command name, sorted.
  std::vector<std::string> names() const;
  /// The lift's drive kind and what it offers beyond the common commands (its row of the
  /// registry, lib/kinds, sets both): commands that need a capability the kind lacks are
  /// answered with `not_offered`. Until it is set every command is offered.
  void set_drive_kind(drive::Kind kind, drive::Capabilities offers) {
    drive_kind_ = kind;
    offers_ = offers;
  }

  /// Handles one request line (without its '\n'). `send` is called exactly once with the reply
  /// line, either before this returns or later when an asynchronous handler completes.
  void handle_line(std::string_view line, const Peer& peer, SessionControl& session,
                   SendFn send) const;

 private:
  DispatchLimits limits_;
  std::optional<drive::Kind> drive_kind_;
  drive::Capabilities offers_ = drive::Capabilities::all();
  std::map<std::string, CommandSpec, std::less<>> commands_;
};

}  // namespace liftd::api
