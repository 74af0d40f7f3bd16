// Results and error codes of API requests, and the JSON line format both directions share.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <variant>

#include <initializer_list>
#include <utility>

#include <nlohmann/json.hpp>

namespace liftd::api {

/// Version of the line protocol announced in the greeting; bumped on incompatible changes.
inline constexpr int kApiVersion = 3;

/// Error codes of a failed request; to_string gives the snake_case name on the wire.
enum class ErrorCode : std::uint8_t {
  BadJson,     ///< the line is not valid JSON (or nests too deep)
  BadRequest,  ///< valid JSON, but not a valid request (the message names the field)
  UnknownCmd,  ///< no command of that name
  Forbidden,   ///< the peer's groups do not allow this command
  NotReady,    ///< the daemon cannot do it now (e.g. the drive link is not up)
  Busy,        ///< too many clients or requests in flight, or the drive is busy
  Fault,       ///< the drive or the daemon is in a fault state that forbids it
  TooLarge,    ///< the request line exceeds the size limit; the connection is closed
  Timeout,     ///< idle or partial-line timeout; the connection is closed
  Internal,    ///< a bug in liftd; the request may or may not have taken effect
  NotOffered,  ///< the lift's drive kind has no such function (e.g. `key` on a hydraulic lift)
};

/// "bad_json", "bad_request", ...
std::string_view to_string(ErrorCode code) noexcept;

/// A failed request: code, human-readable message, and for bad_request the offending field.
struct Error {
  ErrorCode code = ErrorCode::Internal;
  std::string message;
  std::string field;  ///< empty unless one field is at fault
};

/// Outcome of a command: a result object (as a JSON value, or already serialised) or an error.
class Result {
 public:
  /// A success with `value` as the reply's "result" (an object).
  static Result ok(nlohmann::json value = nlohmann::json::object());
  /// A success whose "result" is `compact_json`, an object already serialised by dump_compact
  /// (a command that answers the same object many times serialises it once).
  static Result ok_serialized(std::shared_ptr<const std::string> compact_json);
  /// A failure.
  static Result fail(ErrorCode code, std::string message, std::string field = {});

  /// True for a success.
  bool is_ok() const noexcept { return !std::holds_alternative<Error>(value_); }
  /// The result object; only valid when is_ok() (a serialised result is parsed on first use).
  const nlohmann::json& value() const;
  /// Appends the result object, serialised compactly, to `out`; only valid when is_ok().
  void append_compact(std::string& out) const;
  /// The error; only valid when !is_ok().
  const Error& error() const { return std::get<Error>(value_); }

 private:
  using Serialized = std::shared_ptr<const std::string>;
  explicit Result(std::variant<nlohmann::json, Error, Serialized> value)
      : value_(std::move(value)) {}
  std::variant<nlohmann::json, Error, Serialized> value_;
  mutable std::optional<nlohmann::json> parsed_;  // value() of a serialised result
};

/// Completion callback of a command. Call it exactly once, on the io_context's thread, possibly
/// after the handler returned (e.g. when the drive answered).
using Responder = std::function<void(Result)>;

/// Serialises one JSON value as a single line without the newline; invalid UTF-8 in strings is
/// replaced, never thrown.
std::string dump_compact(const nlohmann::json& value);
/// A JSON object of named flags in the order given ({"ready": true, ...}): a status byte's bits
/// in a `status` object.
nlohmann::json flags_object(std::initializer_list<std::pair<const char*, bool>> flags);
/// Longest piece of client input echoed in an error message, in bytes.
inline constexpr std::size_t kMaxEchoBytes = 64;

/// `text` for an error message: at most kMaxEchoBytes (cut at a UTF-8 character boundary), with
/// "... (N bytes)" appended when it was cut, so a 1 MB key gives a short message.
std::string capped(std::string_view text);

/// A reply line with its trailing '\n'.
std::string reply_line(const nlohmann::json& id, const Result& result);
/// An event line {"event":name,"data":data} with its trailing '\n'.
std::string event_line(std::string_view name, const nlohmann::json& data);

/// Deepest nesting of objects/arrays in a JSON text (strings and escapes skipped), without
/// parsing it; stops counting once `limit` is exceeded and returns limit + 1.
int json_nesting_depth(std::string_view text, int limit) noexcept;

}  // namespace liftd::api
