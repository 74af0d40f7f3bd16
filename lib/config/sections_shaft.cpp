// The shared sections about the car and the shaft: floors, position, travel and can, and the
// checks across them.
#include <algorithm>
#include <array>

#include "config/schema.hpp"

namespace liftd::config {
namespace {

using nlohmann::json;

constexpr std::array<std::string_view, 3> kPositionSourceNames{"sim", "api", "can"};
constexpr std::array<std::string_view, 2> kByteOrderNames{"little", "big"};
constexpr std::array<std::string_view, 4> kRelevelDoorsNames{"open", "closed", "both", "never"};
constexpr std::array<std::string_view, 2> kDcp3ReferenceNames{"position", "shaft_signals"};

// DCP 3.2: deceleration distances are 15-bit values in mm (0x7FFF means "not known").
constexpr std::int64_t kMaxDecelMm = 0x7FFE;
constexpr std::int64_t kFloorNameMaxChars = 16;
constexpr std::size_t kMinFloors = 2;
constexpr std::size_t kMaxFloors = 64;

std::size_t utf8_length(std::string_view text) {
  return static_cast<std::size_t>(std::count_if(text.begin(), text.end(), [](char c) {
    return (static_cast<unsigned char>(c) & 0xC0U) != 0x80U;  // count lead bytes only
  }));
}

// A SocketCAN interface name (at most 15 bytes, IFNAMSIZ) or "unix:" and an absolute path.
std::string can_endpoint_rule(const std::string& text) {
  if (text.rfind("unix:", 0) == 0) {
    const std::string path = text.substr(5);
    if (path.size() > 107) return "unix: socket path longer than 107 bytes";
    return absolute_path_rule(path);
  }
  if (text.size() > 15) return "interface name longer than 15 bytes";
  const auto ok = [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' ||
           c == '-' || c == '.';
  };
  if (!std::all_of(text.begin(), text.end(), ok)) {
    return "is neither an interface name (letters, digits, _ - .) nor unix:PATH";
  }
  return {};
}

// A floor's name: a string of 1..16 characters the rules' character set can show, no space at
// either end; adds a problem and returns false otherwise.
bool check_floor_name(const json& entry, const std::string& at, const FloorRules& rules,
                      Floor& floor, Problems& problems) {
  if (!entry.contains("name")) {
    problems.push_back({at, "missing \"name\""});
    return false;
  }
  if (!entry["name"].is_string()) {
    problems.push_back({at + ".name", "expected a string, got " + show(entry["name"])});
    return false;
  }
  floor.name = entry["name"].get<std::string>();
  const std::size_t length = utf8_length(floor.name);
  const bool displayable = rules.shown_as(floor.name).has_value();
  const bool padded =
      !floor.name.empty() && (floor.name.front() == ' ' || floor.name.back() == ' ');
  if (length < 1 || length > static_cast<std::size_t>(kFloorNameMaxChars) || !displayable ||
      padded) {
    problems.push_back({at + ".name", show(entry["name"]) +
                                          " is not allowed: 1..16 printable characters of " +
                                          rules.charset_name + " (" + rules.charset_details +
                                          "), no space at either end"});
    return false;
  }
  return true;
}

// One entry of `floors` that is an object: its name and its level; false (and problems) when
// either is not good.
bool check_floor(const json& entry, const std::string& at, const FloorRules& rules, Floor& floor,
                 Problems& problems) {
  bool good = check_floor_name(entry, at, rules, floor, problems);
  if (!entry.contains("level_mm")) {
    problems.push_back({at, "missing \"level_mm\""});
    return false;
  }
  if (!check_integer(entry["level_mm"], at + ".level_mm", -rules.max_level_mm, rules.max_level_mm,
                     problems)) {
    return false;
  }
  floor.level_mm = static_cast<std::int32_t>(entry["level_mm"].get<std::int64_t>());
  return good;
}

void apply_floors(const json& value, const std::string& where, const FloorRules& rules,
                  Config& config, Problems& problems) {
  if (!value.is_array()) {
    problems.push_back(
        {where, "expected an array of {\"name\", \"level_mm\"} objects, got " + show(value)});
    return;
  }
  if (value.size() < kMinFloors || value.size() > kMaxFloors) {
    problems.push_back({where, "has " + std::to_string(value.size()) + " entries: allowed " +
                                   std::to_string(kMinFloors) + ".." + std::to_string(kMaxFloors)});
  }
  const std::vector<std::string> members{"name", "level_mm"};
  std::vector<Floor> floors;
  bool all_good = true;
  for (std::size_t i = 0; i < value.size(); ++i) {
    const std::string at = where + "[" + std::to_string(i) + "]";
    const json& entry = value[i];
    if (!entry.is_object()) {
      problems.push_back({at, "expected an object {\"name\", \"level_mm\"}, got " + show(entry)});
      all_good = false;
      continue;
    }
    for (const auto& [k, v] : entry.items()) {
      if (std::find(members.begin(), members.end(), k) == members.end()) {
        problems.push_back({at + "." + k, "unknown key" + did_you_mean(k, members)});
        all_good = false;
      }
    }
    Floor floor{"", 0};
    if (!check_floor(entry, at, rules, floor, problems)) {
      all_good = false;
      continue;
    }
    // Unique as shown: names that differ only in a character the lift shows the same way (on
    // the DCP display, the micro sign and the Greek mu) are the same name.
    for (std::size_t j = 0; j < floors.size(); ++j) {
      if (rules.shown_as(floors[j].name) == rules.shown_as(floor.name)) {
        problems.push_back({at + ".name", json_quoted(floor.name) + " is already the name of " +
                                              where + "[" + std::to_string(j) +
                                              "]: names must be unique"});
        all_good = false;
      }
    }
    if (!floors.empty() && floor.level_mm <= floors.back().level_mm) {
      problems.push_back({at + ".level_mm", std::to_string(floor.level_mm) +
                                                " is not above the previous floor's " +
                                                std::to_string(floors.back().level_mm) +
                                                ": levels must increase strictly"});
      all_good = false;
    }
    floors.push_back(std::move(floor));
  }
  if (all_good && value.size() >= kMinFloors && value.size() <= kMaxFloors) {
    config.floors = std::move(floors);
  }
}

void apply_speed_map(const json& value, const std::string& where, Config& config,
                     Problems& problems) {
  const std::vector<std::string> used = dcp3_speeds(config.travel.dcp3_speed_count);
  std::string used_text;
  for (const auto& s : used) used_text += (used_text.empty() ? "" : ", ") + s;
  if (!value.is_object()) {
    problems.push_back(
        {where,
         "expected an object of speed name -> mm (e.g. {\"V4\": 2500}), got " + show(value)});
    return;
  }
  std::map<std::string, int> distances;
  bool good = true;
  for (const auto& [name, mm] : value.items()) {
    const std::string at = where + "." + name;
    if (std::find(used.begin(), used.end(), name) == used.end()) {
      const bool is_speed =
          std::find(kSpeedNames.begin(), kSpeedNames.end(), name) != kSpeedNames.end();
      // DCP 3.5.3.7: the speed count decides which speed names an installation uses.
      problems.push_back({at, (is_speed ? "is not used with travel.dcp3_speed_count " +
                                              std::to_string(config.travel.dcp3_speed_count)
                                        : std::string("is not a DCP3 travelling speed")) +
                                  ": use " + used_text + " (DCP 3.5.3.7)" +
                                  (is_speed ? "" : did_you_mean(name, used))});
      good = false;
      continue;
    }
    if (!check_integer(mm, at, 1, kMaxDecelMm, problems)) {
      good = false;
      continue;
    }
    distances[name] = static_cast<int>(mm.get<std::int64_t>());
  }
  for (const auto& speed : used) {
    if (value.is_object() && !value.contains(speed)) {
      problems.push_back({where, "has no distance for " + speed + ": every speed in use (" +
                                     used_text + ") needs one"});
      good = false;
    }
  }
  if (good) config.travel.dcp3_decel_distance_mm = std::move(distances);
}

}  // namespace

std::vector<Key> floors_keys(const FloorRules& rules) {
  Key k;
  k.path = "floors";
  k.type = Type::floors;
  k.allowed_text = "2..64 entries; name 1..16 characters of " + rules.charset_name +
                   ", unique, no space at either end; level_mm -" +
                   std::to_string(rules.max_level_mm) + ".." + std::to_string(rules.max_level_mm) +
                   ", strictly increasing";
  k.description = "the building's floors, lowest first, level in mm above the lowest floor";
  k.custom = [rules](const json& value, const std::string& where, Config& config,
                     Problems& problems) { apply_floors(value, where, rules, config, problems); };
  k.get = [](const Config& c) {
    json out = json::array();
    for (const auto& f : c.floors) out.push_back({{"name", f.name}, {"level_mm", f.level_mm}});
    return out;
  };
  return {std::move(k)};
}

std::vector<Key> position_keys() {
  std::vector<Key> t;
  t.push_back(enum_key("position.source", kPositionSourceNames,
                       "where the car's absolute position comes from: sim (--simulate forces "
                       "it), api (the inputs command), can (an absolute encoder on "
                       "can.interface, position.can_*)",
                       &Config::position, &PositionConfig::source));
  t.push_back(int_key("position.can_id", 0, 0x7FF, "11-bit identifier of the encoder's frame",
                      &Config::position, &PositionConfig::can_id));
  t.push_back(int_key("position.can_offset", 0, 6, "first data byte of the position value",
                      &Config::position, &PositionConfig::can_offset));
  t.push_back(int_key("position.can_length", 2, 4, "bytes of the position value", &Config::position,
                      &PositionConfig::can_length));
  {
    Key k;
    k.path = "position.can_byte_order";
    k.type = Type::choice;
    for (auto name : kByteOrderNames) k.choices.emplace_back(name);
    k.description = "byte order of the position value";
    k.set = [](Config& c, const json& v) { c.position.can_big_endian = v == "big"; };
    k.get = [](const Config& c) { return json(c.position.can_big_endian ? "big" : "little"); };
    t.push_back(std::move(k));
  }
  t.push_back(bool_key("position.can_signed", "the position value is two's complement",
                       &Config::position, &PositionConfig::can_signed));
  t.push_back(int_key("position.can_um_per_count", -1000000, 1000000,
                      "scale: micrometres per count (negative: the encoder counts downwards), "
                      "not 0",
                      &Config::position, &PositionConfig::can_um_per_count));
  t.push_back(int_key("position.can_offset_mm", -999999, 999999, "car position (mm) at count 0",
                      &Config::position, &PositionConfig::can_offset_mm));
  t.push_back(int_key("position.can_timeout_ms", 10, 1000,
                      "an encoder value older than this counts as lost (any travel ends)",
                      &Config::position, &PositionConfig::can_timeout_ms));
  return t;
}

std::vector<Key> travel_keys() {
  std::vector<Key> t;
  t.push_back(int_key("travel.level_tolerance_mm", 1, 50,
                      "the car counts as level within this distance of the floor", &Config::travel,
                      &TravelConfig::level_tolerance_mm));
  t.push_back(int_key("travel.relevel_threshold_mm", 2, 100,
                      "relevel once the car is further than this from the floor", &Config::travel,
                      &TravelConfig::relevel_threshold_mm));
  t.push_back(enum_key("travel.relevel_with_doors", kRelevelDoorsNames,
                       "door state in which relevelling is allowed", &Config::travel,
                       &TravelConfig::relevel_with_doors));
  t.push_back(bool_key("travel.relevel_electric_stop",
                       "relevel without remaining distance with electric stop: keep B0 until "
                       "S6 and S1 are 0 (DCP 9.2.3.2)",
                       &Config::travel, &TravelConfig::relevel_electric_stop));
  t.push_back(bool_key("travel.use_start_parameters",
                       "send I7 start parameters before a DCP4 travel (DCP 5.12.7)",
                       &Config::travel, &TravelConfig::use_start_parameters));
  t.push_back(int_key("travel.fast_start_timeout_ms", 100, 10000,
                      "longest the car is held on an open brake in fast start (DCP 12)",
                      &Config::travel, &TravelConfig::fast_start_timeout_ms));
  t.push_back(int_key("travel.call_stop_ms", 0, 60000,
                      "at a served call the car stands at least this long before the next "
                      "queued travel starts (the doors' time to open); then it leaves once "
                      "they are locked",
                      &Config::travel, &TravelConfig::call_stop_ms));
  t.push_back(int_key(
      "travel.inspection_hold_ms", 100, 5000,
      "hold-to-run: an inspection travel stops unless its command is repeated within this time",
      &Config::travel, &TravelConfig::inspection_hold_ms));
  t.push_back(int_key("travel.dcp3_stop_lead_mm", 0, 100,
                      "DCP3 by position: withdraw B2 this far before the level, so the stop "
                      "from crawl ends on it (the crawl stop distance of the installation)",
                      &Config::travel, &TravelConfig::dcp3_stop_lead_mm));
  t.push_back(int_key("travel.dcp3_speed_count", 1, 7,
                      "travelling speeds of a DCP3 installation (DCP 3.5.3.7)", &Config::travel,
                      &TravelConfig::dcp3_speed_count));
  t.push_back(enum_key("travel.dcp3_reference", kDcp3ReferenceNames,
                       "where a DCP3 travel finds its deceleration point (B1 off) and its level "
                       "(B2 off): position = the car position against "
                       "travel.dcp3_decel_distance_mm and the floor; shaft_signals = the "
                       "decel_vN_up/down of its speed and direction and zone_level (inputs)",
                       &Config::travel, &TravelConfig::dcp3_reference));
  Key k;
  k.path = "travel.dcp3_decel_distance_mm";
  k.type = Type::speed_map;
  k.allowed_text =
      "one entry per speed in use (count 1: V4; 2: V4 V3; 3: + V2; 4: + V1; "
      "5: + V7; 6: + V6; 7: + V5), 1..32766 mm";
  k.description = "DCP3 fixed deceleration distance before the level, per speed";
  k.custom = apply_speed_map;
  k.get = [](const Config& c) { return json(c.travel.dcp3_decel_distance_mm); };
  t.push_back(std::move(k));
  return t;
}

std::vector<Key> can_keys() {
  return {string_key("can.interface", 1, 112, "interface name (at most 15 bytes) or unix:PATH",
                     can_endpoint_rule,
                     "CAN endpoint of the SCH001 card: a SocketCAN interface at 125 kbit/s "
                     "(card document 3a), or unix:PATH where a card simulator listens",
                     &Config::can, &CanConfig::interface)};
}

void check_shared_keys(const Config& config, const json& document, Problems& problems) {
  if (config.position.can_offset + config.position.can_length > 8) {
    problems.push_back({"position.can_offset",
                        std::to_string(config.position.can_offset) + " + position.can_length " +
                            std::to_string(config.position.can_length) +
                            " must stay within the 8 data bytes of a CAN frame"});
  }
  if (config.position.can_um_per_count == 0) {
    problems.push_back({"position.can_um_per_count", "0 is no scale: use micrometres per count"});
  }
  // Reserving every slot would leave none for read-only clients.
  if (config.api.reserved_clients >= config.api.max_clients) {
    problems.push_back({"api.reserved_clients", std::to_string(config.api.reserved_clients) +
                                                    " must be less than api.max_clients (" +
                                                    std::to_string(config.api.max_clients) + ")"});
  }
  // Relevelling inside the level tolerance would make the car hunt around the level.
  if (config.travel.relevel_threshold_mm <= config.travel.level_tolerance_mm) {
    const bool set_here = find_value(document, "travel.relevel_threshold_mm") != nullptr;
    problems.push_back({set_here ? "travel.relevel_threshold_mm" : "travel.level_tolerance_mm",
                        "relevel_threshold_mm (" +
                            std::to_string(config.travel.relevel_threshold_mm) +
                            ") must be greater than level_tolerance_mm (" +
                            std::to_string(config.travel.level_tolerance_mm) + ")"});
  }
}

std::string_view to_string(PositionSource value) {
  return enum_name(value, kPositionSourceNames);
}

std::string_view to_string(RelevelDoors value) {
  return enum_name(value, kRelevelDoorsNames);
}

std::string_view to_string(Dcp3Reference value) {
  return enum_name(value, kDcp3ReferenceNames);
}

}  // namespace liftd::config
