#include "api/dispatcher.hpp"

#include <algorithm>
#include <exception>
#include <memory>
#include <stdexcept>
#include <utility>

namespace liftd::api {

std::string_view to_string(Access access) noexcept {
  switch (access) {
    case Access::Read:
      return "read";
    case Access::Control:
      return "control";
    case Access::Inputs:
      return "inputs";
  }
  return "read";
}

bool AccessSet::allows(Access level) const noexcept {
  switch (level) {
    case Access::Read:
      return read;
    case Access::Control:
      return control;
    case Access::Inputs:
      return inputs;
  }
  return false;
}

nlohmann::json AccessSet::to_json() const {
  nlohmann::json out = nlohmann::json::array();
  if (read) out.push_back("read");
  if (control) out.push_back("control");
  if (inputs) out.push_back("inputs");
  return out;
}

void Dispatcher::add(CommandSpec spec) {
  if (spec.name.empty()) throw std::invalid_argument("api: command without a name");
  if (!spec.handler)
    throw std::invalid_argument("api: command \"" + spec.name + "\" has no handler");
  if (commands_.count(spec.name) != 0) {
    throw std::invalid_argument("api: command \"" + spec.name + "\" registered twice");
  }
  std::string name = spec.name;
  commands_.emplace(std::move(name), std::move(spec));
}

const CommandSpec* Dispatcher::find(std::string_view name) const {
  const auto it = commands_.find(name);
  return it == commands_.end() ? nullptr : &it->second;
}

std::vector<std::string> Dispatcher::names() const {
  std::vector<std::string> out;
  for (const auto& [name, spec] : commands_) out.push_back(name);
  return out;
}

namespace {

/// Shared by the Responder copies of one request: sends the reply once; if every copy is
/// dropped without an answer, replies `internal` so the client never waits forever.
class ReplyState {
 public:
  ReplyState(nlohmann::json id, Dispatcher::SendFn send)
      : id_(std::move(id)), send_(std::move(send)) {}
  ReplyState(const ReplyState&) = delete;
  ReplyState& operator=(const ReplyState&) = delete;
  ~ReplyState() {
    if (!sent_) {
      try {
        finish(Result::fail(ErrorCode::Internal, "the command finished without a reply"));
      } catch (...) {  // a destructor must not throw; the connection is going away anyway
      }
    }
  }
  void finish(const Result& result) {
    if (sent_) return;
    sent_ = true;
    send_(reply_line(id_, result), result.is_ok());
  }
  bool sent() const { return sent_; }

 private:
  nlohmann::json id_;
  Dispatcher::SendFn send_;
  bool sent_ = false;
};

}  // namespace

namespace {

// Parses `line` (discarded on error) and records the first key that appears twice in one object.
nlohmann::json parse_checked(std::string_view line, std::optional<std::string>& duplicate) {
  // nlohmann keeps the last of duplicate keys silently; a request with two "cmd" keys must not
  // run either. The callback sees every key with the object it belongs to.
  std::vector<std::vector<std::string>> objects;
  const nlohmann::json::parser_callback_t callback =
      [&](int /*depth*/, nlohmann::json::parse_event_t event, nlohmann::json& parsed) {
        using Event = nlohmann::json::parse_event_t;
        switch (event) {
          case Event::object_start:
            objects.emplace_back();
            break;
          case Event::object_end:
            if (!objects.empty()) objects.pop_back();
            break;
          case Event::key:
            if (!objects.empty() && !duplicate) {
              auto& keys = objects.back();
              const auto& key = parsed.get_ref<const std::string&>();
              if (std::find(keys.begin(), keys.end(), key) != keys.end()) {
                duplicate = key;
              } else {
                keys.push_back(key);
              }
            }
            break;
          default:
            break;
        }
        return true;
      };
  return nlohmann::json::parse(line.begin(), line.end(), callback, false);
}

}  // namespace

std::optional<std::string> find_duplicate_key(std::string_view line) {
  std::optional<std::string> duplicate;
  (void)parse_checked(line, duplicate).is_discarded();
  return duplicate;
}

void Dispatcher::handle_line(std::string_view line, const Peer& peer, SessionControl& session,
                             SendFn send) const {
  const auto fail = [&send](const nlohmann::json& id, ErrorCode code, std::string message,
                            std::string field = {}) {
    send(reply_line(id, Result::fail(code, std::move(message), std::move(field))), false);
  };
  if (json_nesting_depth(line, limits_.max_depth) > limits_.max_depth) {
    fail(nullptr, ErrorCode::BadJson,
         "JSON nests deeper than " + std::to_string(limits_.max_depth) + " levels");
    return;
  }
  if (const auto nul = line.find('\0'); nul != std::string_view::npos) {
    // The parser would take the NUL for the end of the text and run the part before it.
    fail(nullptr, ErrorCode::BadJson,
         "raw NUL byte at offset " + std::to_string(nul) +
             ": JSON text cannot contain one (inside a string write \\u0000)");
    return;
  }
  std::optional<std::string> duplicate;
  nlohmann::json request = parse_checked(line, duplicate);
  if (request.is_discarded()) {
    fail(nullptr, ErrorCode::BadJson, "not valid JSON (expected one object per line)");
    return;
  }
  if (duplicate) {
    // Which of two "cmd" keys was meant is unknowable: run neither.
    fail(nullptr, ErrorCode::BadJson,
         "duplicate key \"" + capped(*duplicate) + "\": each key may appear once per object");
    return;
  }
  if (!request.is_object()) {
    fail(nullptr, ErrorCode::BadRequest, "a request must be a JSON object");
    return;
  }
  nlohmann::json id = nullptr;
  if (const auto it = request.find("id"); it != request.end()) id = *it;
  const auto cmd = request.find("cmd");
  if (cmd == request.end()) {
    fail(id, ErrorCode::BadRequest, "missing field \"cmd\" (the command name, a string)", "cmd");
    return;
  }
  if (!cmd->is_string()) {
    fail(id, ErrorCode::BadRequest, "field \"cmd\" must be a string", "cmd");
    return;
  }
  const std::string& name = cmd->get_ref<const std::string&>();
  const CommandSpec* spec = find(name);
  if (spec == nullptr) {
    fail(id, ErrorCode::UnknownCmd, "unknown command \"" + capped(name) + "\"", "cmd");
    return;
  }
  if (!peer.access.allows(spec->access)) {
    fail(id, ErrorCode::Forbidden,
         "\"" + name + "\" needs " + std::string(to_string(spec->access)) + " access; uid " +
             std::to_string(peer.uid) + " is not in that group");
    return;
  }
  if (spec->needs && drive_kind_ && !offers_.has(*spec->needs)) {
    // Before the arguments: no argument could make the command exist on this lift.
    fail(id, ErrorCode::NotOffered,
         "\"" + name + "\" is not offered by drive kind \"" +
             std::string(drive::to_string(*drive_kind_)) + "\" (it has no " +
             std::string(drive::to_string(*spec->needs)) + " function)");
    return;
  }
  if (auto error = validate_args(request, spec->args)) {
    fail(id, error->code, std::move(error->message), std::move(error->field));
    return;
  }
  if (session.requests_in_flight() > limits_.max_in_flight) {
    fail(id, ErrorCode::Busy,
         "more than " + std::to_string(limits_.max_in_flight) + " requests unanswered");
    return;
  }
  auto state = std::make_shared<ReplyState>(std::move(id), std::move(send));
  Responder done = [state](Result result) { state->finish(result); };
  try {
    spec->handler(Call{request, peer, session}, std::move(done));
  } catch (const std::exception& e) {
    state->finish(Result::fail(ErrorCode::Internal, std::string("internal error: ") + e.what()));
  }
}

}  // namespace liftd::api
