#include "api/result.hpp"

namespace liftd::api {

std::string_view to_string(ErrorCode code) noexcept {
  switch (code) {
    case ErrorCode::BadJson:
      return "bad_json";
    case ErrorCode::BadRequest:
      return "bad_request";
    case ErrorCode::UnknownCmd:
      return "unknown_cmd";
    case ErrorCode::Forbidden:
      return "forbidden";
    case ErrorCode::NotReady:
      return "not_ready";
    case ErrorCode::Busy:
      return "busy";
    case ErrorCode::Fault:
      return "fault";
    case ErrorCode::TooLarge:
      return "too_large";
    case ErrorCode::Timeout:
      return "timeout";
    case ErrorCode::Internal:
      return "internal";
    case ErrorCode::NotOffered:
      return "not_offered";
  }
  return "internal";
}

Result Result::ok(nlohmann::json value) {
  return Result(std::move(value));
}

Result Result::ok_serialized(std::shared_ptr<const std::string> compact_json) {
  return Result(std::move(compact_json));
}

const nlohmann::json& Result::value() const {
  if (const auto* text = std::get_if<Serialized>(&value_)) {
    if (!parsed_) parsed_ = nlohmann::json::parse(**text);
    return *parsed_;
  }
  return std::get<nlohmann::json>(value_);
}

void Result::append_compact(std::string& out) const {
  if (const auto* text = std::get_if<Serialized>(&value_)) {
    out += **text;
  } else {
    out += dump_compact(std::get<nlohmann::json>(value_));
  }
}

Result Result::fail(ErrorCode code, std::string message, std::string field) {
  return Result(Error{code, std::move(message), std::move(field)});
}

nlohmann::json flags_object(std::initializer_list<std::pair<const char*, bool>> flags) {
  nlohmann::json j = nlohmann::json::object();
  for (const auto& [name, on] : flags) j[name] = on;
  return j;
}

std::string dump_compact(const nlohmann::json& value) {
  return value.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

std::string reply_line(const nlohmann::json& id, const Result& result) {
  if (result.is_ok()) {
    // The same bytes as dumping {"id","ok","result"} (keys in that sorted order), without
    // copying the result into a reply object first: status is the most frequent request.
    std::string line = "{\"id\":";
    line += dump_compact(id);
    line += ",\"ok\":true,\"result\":";
    result.append_compact(line);
    line += "}\n";
    return line;
  }
  nlohmann::json reply = nlohmann::json::object();
  reply["id"] = id;
  reply["ok"] = false;
  {
    const Error& error = result.error();
    nlohmann::json body = {{"code", to_string(error.code)}, {"message", error.message}};
    if (!error.field.empty()) body["field"] = error.field;
    reply["error"] = std::move(body);
  }
  std::string line = dump_compact(reply);
  line.push_back('\n');
  return line;
}

std::string event_line(std::string_view name, const nlohmann::json& data) {
  // The bytes of {"data","event"} dumped (keys in that sorted order), without copying data.
  std::string line = "{\"data\":";
  line += dump_compact(data);
  line += ",\"event\":";
  line += dump_compact(nlohmann::json(name));
  line += "}\n";
  return line;
}

int json_nesting_depth(std::string_view text, int limit) noexcept {
  int depth = 0;
  int deepest = 0;
  bool in_string = false;
  bool escaped = false;
  for (char c : text) {
    if (in_string) {
      if (escaped) {
        escaped = false;
      } else if (c == '\\') {
        escaped = true;
      } else if (c == '"') {
        in_string = false;
      }
      continue;
    }
    if (c == '"') {
      in_string = true;
    } else if (c == '{' || c == '[') {
      ++depth;
      if (depth > deepest) deepest = depth;
      if (deepest > limit) return limit + 1;
    } else if ((c == '}' || c == ']') && depth > 0) {
      --depth;
    }
  }
  return deepest;
}

std::string capped(std::string_view text) {
  if (text.size() <= kMaxEchoBytes) return std::string(text);
  std::size_t cut = kMaxEchoBytes;
  // Do not split a UTF-8 sequence: back up over continuation bytes (10xxxxxx).
  while (cut > 0 && (static_cast<unsigned char>(text[cut]) & 0xC0U) == 0x80U) --cut;
  return std::string(text.substr(0, cut)) + "... (" + std::to_string(text.size()) + " bytes)";
}

}  // namespace liftd::api
