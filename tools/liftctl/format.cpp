#include "format.hpp"

#include <algorithm>
#include <sstream>

namespace liftctl {
namespace {

using nlohmann::json;

std::string text(const json& value) {
  if (value.is_null()) return "-";
  if (value.is_string()) return value.get<std::string>();
  if (value.is_boolean()) return value.get<bool>() ? "yes" : "no";
  return value.dump();
}

const json& at(const json& object, const char* key) {
  static const json null_value = nullptr;
  if (!object.is_object()) return null_value;
  const auto it = object.find(key);
  return it == object.end() ? null_value : *it;
}

/// Names of the true members of an object of booleans, or "-".
std::string true_flags(const json& flags) {
  std::string out;
  if (!flags.is_object()) return "-";
  for (const auto& [name, value] : flags.items()) {
    if (value.is_boolean() && value.get<bool>()) out += (out.empty() ? "" : " ") + name;
  }
  return out.empty() ? "-" : out;
}

void flatten(const json& value, const std::string& prefix, std::ostringstream& out) {
  if (value.is_object() && !value.empty()) {
    for (const auto& [key, inner] : value.items()) {
      flatten(inner, prefix.empty() ? key : prefix + "." + key, out);
    }
    return;
  }
  out << (prefix.empty() ? "value" : prefix) << ": " << text(value) << '\n';
}

}  // namespace

std::string format_status(const json& s) {
  std::ostringstream out;
  const json& drive = at(s, "drive");
  const json& car = at(s, "car");
  const json& travel = at(s, "travel");
  const json& rt = at(s, "rt");
  out << "link:     " << text(at(at(s, "link"), "state")) << '\n';
  out << "drive:    " << text(at(drive, "mode")) << ", status: " << true_flags(at(drive, "status"))
      << '\n';
  if (!at(drive, "extended").is_null()) {
    out << "extended: " << true_flags(at(drive, "extended")) << '\n';
  }
  out << "car:      floor " << text(at(car, "floor")) << ", position "
      << (at(car, "position_mm").is_null() ? "unknown" : text(at(car, "position_mm")) + " mm")
      << '\n';
  out << "travel:   " << text(at(travel, "state"));
  if (!at(travel, "direction").is_null()) out << " " << text(at(travel, "direction"));
  if (!at(travel, "target_floor").is_null())
    out << " to floor " << text(at(travel, "target_floor"));
  out << '\n';
  const json& faults = at(s, "faults");
  if (!faults.is_array() || faults.empty()) {
    out << "faults:   none\n";
  } else {
    out << "faults:\n";
    for (const auto& f : faults) {
      out << "  " << text(at(f, "code")) << ": " << text(at(f, "text")) << " (since "
          << text(at(f, "since")) << ")\n";
    }
  }
  out << "rt:       " << text(at(rt, "policy")) << " priority " << text(at(rt, "priority"))
      << (at(rt, "realtime") == true ? "" : " (real-time scheduling NOT obtained)")
      << (at(rt, "memory_locked") == true ? ", memory locked" : ", memory not locked") << '\n';
  return out.str();
}

std::string format_state_line(const json& s) {
  std::ostringstream out;
  const json& car = at(s, "car");
  const json& faults = at(s, "faults");
  out << "link=" << text(at(at(s, "link"), "state")) << " mode=" << text(at(at(s, "drive"), "mode"))
      << " status=" << true_flags(at(at(s, "drive"), "status"))
      << " floor=" << text(at(car, "floor")) << " position_mm=" << text(at(car, "position_mm"))
      << " travel=" << text(at(at(s, "travel"), "state"))
      << " faults=" << (faults.is_array() ? faults.size() : 0);
  return out.str();
}

std::string format_event_line(const std::string& name, const json& data) {
  if (name == "state") return "state " + format_state_line(data);
  std::ostringstream out;
  out << name;
  if (data.is_object()) {
    for (const auto& [key, value] : data.items()) {
      out << ' ' << key << '=' << (value.is_structured() ? value.dump() : text(value));
    }
  } else if (!data.is_null()) {
    out << ' ' << data.dump();
  }
  return out.str();
}

std::string format_stats(const json& stats) {
  std::ostringstream out;
  for (const char* section : {"link", "cycle", "api"}) {
    const json& part = at(stats, section);
    if (!part.is_object()) continue;
    out << section << ":\n";
    for (const auto& [key, value] : part.items()) out << "  " << key << ": " << text(value) << '\n';
  }
  return out.str();
}

std::string format_trace(const json& trace) {
  std::ostringstream out;
  const json& frames = at(trace, "frames");
  if (!frames.is_array() || frames.empty()) return "no frames traced\n";
  out << "      t_ms  master             drive\n";
  for (const auto& f : frames) {
    const json& t = at(f, "t_us");
    char buf[32];
    std::snprintf(buf, sizeof buf, "%10.3f", t.is_number() ? t.get<double>() / 1000.0 : 0.0);
    out << buf << "  " << text(at(f, "tx")) << "  "
        << (at(f, "rx").is_null() ? "(no reply)" : text(at(f, "rx"))) << '\n';
  }
  return out.str();
}

std::string format_display(const json& display) {
  std::ostringstream out;
  const json& lines = at(display, "lines");
  std::size_t width = 20;  // DCP 5.6.2: cursor positions 0..19, so 20 characters a line
  if (lines.is_array()) {
    for (const auto& l : lines) {
      if (l.is_string()) width = std::max(width, l.get<std::string>().size());
    }
  }
  out << '+' << std::string(width, '-') << "+\n";
  if (lines.is_array()) {
    for (const auto& l : lines) {
      std::string s = l.is_string() ? l.get<std::string>() : "";
      s.resize(width, ' ');
      out << '|' << s << "|\n";
    }
  }
  out << '+' << std::string(width, '-') << "+\n";
  const json& cursor = at(display, "cursor");
  if (!cursor.is_null()) {
    out << "cursor: line " << text(at(cursor, "line")) << ", column " << text(at(cursor, "column"))
        << '\n';
  }
  return out.str();
}

std::string format_generic(const json& result) {
  std::ostringstream out;
  if (result.is_object() && result.empty()) return "ok\n";
  flatten(result, "", out);
  return out.str();
}

}  // namespace liftctl
