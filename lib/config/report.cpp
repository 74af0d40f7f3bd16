// What is derived from a Schema besides loading: the effective-config dump, the
// `--check-config` summary and the Markdown reference.
#include <algorithm>
#include <sstream>

#include "config/schema.hpp"

namespace liftd::config {
namespace {

using nlohmann::json;

std::string markdown_cell(std::string text) {
  std::string out;
  for (char c : text) {
    if (c == '|') out += '\\';
    out += c;
  }
  return out;
}

std::string type_name(const Key& key) {
  switch (key.type) {
    case Type::boolean:
      return "boolean";
    case Type::integer:
      return "integer";
    case Type::string:
      return "string";
    case Type::choice:
      return "string";
    case Type::floors:
      return "array of {name, level_mm}";
    case Type::speed_map:
      return "object: speed -> mm";
    case Type::custom:
      return key.type_text;
  }
  return {};
}

std::string allowed_text(const Key& key) {
  if (!key.allowed_text.empty()) return key.allowed_text;
  switch (key.type) {
    case Type::boolean:
      return "true, false";
    case Type::integer:
      return std::to_string(key.min) + ".." + std::to_string(key.max);
    case Type::choice: {
      std::string out;
      for (const auto& c : key.choices) out += (out.empty() ? "`" : ", `") + json_quoted(c) + "`";
      return out;
    }
    default:
      return {};
  }
}

}  // namespace

nlohmann::json to_json(const Config& config, const Schema& schema) {
  json out = json::object();
  for (const auto& key : schema.keys()) {
    std::string pointer = "/" + key.path;
    std::replace(pointer.begin(), pointer.end(), '.', '/');
    out[json::json_pointer(pointer)] = key.get(config);
  }
  return out;
}

std::string summary(const Config& config, const Schema& schema) {
  std::ostringstream out;
  const KindRules* kind = schema.rules_of(config.drive.kind);
  if (kind != nullptr && kind->summary) {
    out << kind->summary(config);
  } else {
    out << "drive:    " << to_string(config.drive.kind) << " on " << config.drive.device
        << " (rs485 " << to_string(config.drive.rs485) << ")\n";
  }
  out << "floors:   " << config.floors.size();
  if (!config.floors.empty()) {
    out << ", " << json_quoted(config.floors.front().name) << " at "
        << config.floors.front().level_mm << " mm to " << json_quoted(config.floors.back().name)
        << " at " << config.floors.back().level_mm << " mm";
  }
  out << "\n";
  out << "position: " << to_string(config.position.source) << "\n";
  out << "api:      " << config.api.socket << " (group " << config.api.socket_group << ", at most "
      << config.api.max_clients << " clients)\n";
  out << "rt:       priority " << config.rt.priority << ", cpu "
      << (config.rt.cpu < 0 ? std::string("any") : std::to_string(config.rt.cpu))
      << ", lock memory " << (config.rt.lock_memory ? "yes" : "no") << "\n";
  out << "log:      " << to_string(config.log.level) << "\n";
  return out.str();
}

std::string reference_markdown(const Schema& schema) {
  const Config defaults;
  std::ostringstream out;
  out << "| Key | Type | Default | Allowed | Description |\n";
  out << "| --- | --- | --- | --- | --- |\n";
  for (const auto& key : schema.keys()) {
    out << "| `" << key.path << "` | " << markdown_cell(type_name(key)) << " | `"
        << markdown_cell(key.get(defaults).dump()) << "` | " << markdown_cell(allowed_text(key))
        << " | " << markdown_cell(key.description) << " |\n";
  }
  return out.str();
}

std::vector<std::string> key_paths(const Schema& schema) {
  std::vector<std::string> out;
  for (const auto& key : schema.keys()) out.push_back(key.path);
  return out;
}

}  // namespace liftd::config
