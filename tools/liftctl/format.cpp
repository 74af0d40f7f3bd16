#include "format.hpp"

#include <algorithm>
#include <sstream>
#include <vector>

namespace liftctl {
namespace {

using nlohmann::json;

std::string text(const json& value) {
  if (value.is_null()) return "-";
  if (value.is_string()) return value.get<std::string>();
  if (value.is_boolean()) return value.get<bool>() ? "yes" : "no";
  return value.dump();
}

const json& at(const json& object, const std::string& key) {
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

/// "2 5 7" for an array of floors, "none" when empty.
std::string floor_list(const json& floors) {
  if (!floors.is_array() || floors.empty()) return "none";
  std::string out;
  for (const auto& f : floors) out += (out.empty() ? "" : " ") + text(f);
  return out;
}

/// "+4 mm" / "-3 mm": a signed distance.
std::string signed_mm(const json& mm) {
  if (!mm.is_number_integer()) return text(mm) + " mm";
  const auto value = mm.get<long long>();
  return (value > 0 ? "+" : "") + std::to_string(value) + " mm";
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

/// drive.state, and for `not_ready` what of the drive (`kind`) holds a travel back.
std::string drive_state_text(const json& kind, const json& state) {
  if (state != "not_ready") return text(state);
  const std::string why = kind == "sch001" ? "the card reports RDY = 0"
                          : kind == "uss"  ? "the drive is in local control or not ready to "
                                             "switch on"
                          : kind == "dcp" || kind.is_null() ? "the drive reports S0 = 0"
                                                            : "the drive is not ready";
  return "not_ready (" + why + ": no travel starts)";
}

/// The DCP object of a status: "dcp" since API 2, the "drive" object of an API 1 daemon.
const json& dcp_of(const json& s) {
  const json& dcp = at(s, "dcp");
  return dcp.is_object() ? dcp : at(s, "drive");
}

}  // namespace

std::string format_status(const json& s) {
  std::ostringstream out;
  const json& drive = at(s, "drive");
  const json& car = at(s, "car");
  const json& travel = at(s, "travel");
  const json& rt = at(s, "rt");
  out << "link:     " << text(at(at(s, "link"), "state")) << '\n';
  if (drive.contains("kind")) {  // API 2 and later
    out << "drive:    " << text(at(drive, "kind")) << ", "
        << drive_state_text(at(drive, "kind"), at(drive, "state")) << '\n';
  }
  if (at(drive, "kind") == "sch001") {
    const json& card = at(at(s, "sch001"), "card");
    out << "card:     "
        << (card.is_object() ? "relays on: " + true_flags(card) : std::string("not heard yet"))
        << ", timeout " << (at(at(s, "sch001"), "timeout_enabled") == false ? "off" : "on") << '\n';
    out << "signals:  " << true_flags(at(at(s, "sch001"), "commands")) << " (phase "
        << text(at(at(s, "sch001"), "phase")) << ")\n";
  }
  if (at(drive, "kind") == "uss") {
    const json& uss = at(s, "uss");
    out << "uss:      drive " << text(at(uss, "drive_address")) << " "
        << text(at(uss, "profile_state")) << " (asked: " << text(at(uss, "wish")) << "), phase "
        << text(at(uss, "phase")) << '\n';
    out << "words:    control " << true_flags(at(uss, "control_bits")) << "; status "
        << true_flags(at(uss, "status_bits")) << '\n';
    out << "speed:    setpoint " << text(at(at(uss, "setpoint"), "percent")) << " %, actual "
        << text(at(at(uss, "actual"), "percent")) << " %\n";
    std::string silent;
    const json& slaves = at(uss, "slaves");
    if (slaves.is_array()) {
      for (const auto& slave : slaves) {
        if (at(slave, "responding") == false)
          silent += (silent.empty() ? "" : " ") + text(at(slave, "address"));
      }
    }
    out << "slaves:   " << (slaves.is_array() ? slaves.size() : 0) << " on the bus"
        << (silent.empty() ? "" : ", not sending: " + silent) << '\n';
  }
  const json& kind = at(drive, "kind");
  if (kind.is_string() && kind != "dcp" && kind != "sch001" && kind != "uss" &&
      at(s, kind.get<std::string>()).is_object()) {
    // A drive kind this liftctl has no lines of its own for: its status object as it comes.
    std::ostringstream lines;
    flatten(at(s, kind.get<std::string>()), "", lines);
    std::istringstream each(lines.str());
    for (std::string line; std::getline(each, line);) {
      out << kind.get<std::string>() << ":  " << line << '\n';
    }
  }
  const json& dcp = dcp_of(s);
  if (kind.is_null() || kind == "dcp") {
    out << "dcp:      " << text(at(dcp, "mode")) << ", status: " << true_flags(at(dcp, "status"))
        << '\n';
    if (!at(dcp, "extended").is_null()) {
      out << "extended: " << true_flags(at(dcp, "extended")) << '\n';
    }
  }
  out << "car:      floor " << text(at(car, "floor")) << ", position "
      << (at(car, "position_mm").is_null() ? "unknown" : text(at(car, "position_mm")) + " mm");
  if (!at(car, "next_possible_stop").is_null()) {
    out << ", next possible stop: floor " << text(at(car, "next_possible_stop"));
  }
  out << '\n';
  // Older daemons do not report the outputs: print the line only when they are there.
  if (car.is_object() && car.contains("brake_open") && car.contains("contactors_on")) {
    out << "outputs:  brake " << (at(car, "brake_open") == true ? "open" : "closed")
        << ", motor contactors " << (at(car, "contactors_on") == true ? "on" : "off") << '\n';
  }
  out << "travel:   " << text(at(travel, "state"));
  if (!at(travel, "direction").is_null()) out << " " << text(at(travel, "direction"));
  if (!at(travel, "target_floor").is_null())
    out << " to floor " << text(at(travel, "target_floor"));
  out << '\n';
  if (travel.is_object() && travel.contains("calls")) {
    out << "calls:    " << floor_list(at(travel, "calls")) << '\n';
  }
  if (!at(travel, "last_slip_mm").is_null()) {
    out << "slip:     " << signed_mm(at(travel, "last_slip_mm"))
        << " on the last travel (drive's measured distance minus the position source's)\n";
  }
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
  out << "link=" << text(at(at(s, "link"), "state"));
  if (!at(at(s, "drive"), "state").is_null()) out << " drive=" << text(at(at(s, "drive"), "state"));
  out << " mode=" << text(at(dcp_of(s), "mode"))
      << " status=" << true_flags(at(dcp_of(s), "status")) << " floor=" << text(at(car, "floor"))
      << " position_mm=" << text(at(car, "position_mm"))
      << " travel=" << text(at(at(s, "travel"), "state"));
  const json& calls = at(at(s, "travel"), "calls");
  if (calls.is_array() && !calls.empty()) {
    std::string list;
    for (const auto& f : calls) list += (list.empty() ? "" : ",") + text(f);
    out << " calls=" << list;
  }
  out << " faults=" << (faults.is_array() ? faults.size() : 0);
  return out.str();
}

std::string format_event_line(const std::string& name, const json& data) {
  if (name == "state") return "state " + format_state_line(data);
  std::ostringstream out;
  if (name == "travel" && data.is_object() && data.contains("event")) {
    // "travel aborted (distance): safety_chain_open, target 9000 mm, at 5472 mm"
    out << "travel " << text(at(data, "event")) << " (" << text(at(data, "kind")) << ")";
    if (!at(data, "cause").is_null()) out << ": " << text(at(data, "cause"));
    const json& target = at(data, "target_mm");
    if (target.is_number_integer() && target.get<long long>() != 0) {
      out << ", target " << text(target) << " mm";
    }
    if (!at(data, "position_mm").is_null())
      out << ", at " << text(at(data, "position_mm")) << " mm";
    return out.str();
  }
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
  // API 3: the drive-neutral `link` and `cycle`, the drive kind's own counters under its name.
  // An API 2 daemon has every counter in `link` and `cycle`: printed as they come.
  // Any drive kind's object is printed, whatever its name: liftctl need not know the kind.
  std::ostringstream out;
  const auto print = [&out](const std::string& section, const json& part) {
    out << section << ":\n";
    std::ostringstream lines;
    flatten(part, "", lines);
    std::istringstream each(lines.str());
    for (std::string line; std::getline(each, line);) out << "  " << line << '\n';
  };
  std::vector<std::string> sections = {"link", "cycle"};
  if (stats.is_object()) {
    for (const auto& [key, part] : stats.items()) {
      if (part.is_object() && key != "link" && key != "cycle" && key != "api") {
        sections.push_back(key);
      }
    }
  }
  sections.emplace_back("api");
  for (const std::string& section : sections) {
    const json& part = at(stats, section);
    if (part.is_object()) print(section, part);
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

std::string format_travel_result(const json& request, const json& result) {
  const std::string command = text(at(request, "cmd"));
  const std::string action = text(at(request, "action"));
  const std::string floor = text(at(request, "floor"));
  const json& detail = at(result, "detail");
  const std::string note = detail.is_string() ? " (" + detail.get<std::string>() + ")" : "";
  std::string line;
  if (command == "travel") {
    line = at(result, "extended") == true
               ? "target of the running travel moved to floor " + floor
               : "travel to floor " + floor + " accepted; follow it with 'liftctl watch'" + note;
  } else if (command == "stop") {
    line = "stopping; calls queue cleared" + note;
  } else if (command == "fast_stop") {
    line = "fast stop sent; calls queue cleared" + note;
  } else if (command == "relevel") {
    line = "relevelling to the nearest floor" + note;
  } else if (command == "inspection") {
    const std::string direction = text(at(request, "direction"));
    if (text(at(request, "mode")) != "on") {
      line = "software inspection off";
    } else if (direction == "up" || direction == "down") {
      line = "software inspection on, " + direction +
             " held for travel.inspection_hold_ms: repeat to keep moving";
    } else {
      line = "software inspection on, no direction held";
    }
  } else if (command == "fast_start") {
    line = action == "arm" ? "fast start armed for floor " + floor +
                                 ": the car leaves when the doors are locked"
           : action == "go" ? "doors locked: the car leaves"
                            : "fast start aborted (controlled stop)";
  } else if (command == "calls") {
    if (at(result, "calls").is_array()) {
      line = "calls: " + floor_list(at(result, "calls"));
    } else if (action == "add") {
      line = detail == "already queued" ? "floor " + floor + " was already queued"
                                        : "floor " + floor + " queued";
    } else {
      line = "floor " + floor + " cancelled";
    }
  } else {
    return format_generic(result);
  }
  return line + "\n";
}

std::string format_generic(const json& result) {
  std::ostringstream out;
  if (result.is_object() && result.empty()) return "ok\n";
  flatten(result, "", out);
  return out.str();
}

}  // namespace liftctl
