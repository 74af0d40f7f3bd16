// The schema table and everything derived from it: validation, defaults, the effective-config
// dump and the Markdown reference. Add a key by adding one entry to schema() below.
#include "config/config.hpp"

#include <fcntl.h>
#include <sched.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>
#include <functional>
#include <sstream>

#include "dcp/charset.hpp"

namespace liftd::config {
namespace {

using nlohmann::json;

constexpr std::array<std::string_view, 5> kLogLevelNames{"trace", "debug", "info", "warn", "error"};
constexpr std::array<std::string_view, 3> kRs485Names{"auto", "required", "off"};
constexpr std::array<std::string_view, 3> kPositionSourceNames{"sim", "api", "can"};
constexpr std::array<std::string_view, 2> kFastDownNames{"hsp", "sp3"};
constexpr std::array<std::string_view, 2> kByteOrderNames{"little", "big"};
constexpr std::array<std::string_view, 4> kRelevelDoorsNames{"open", "closed", "both", "never"};
constexpr std::array<std::string_view, 2> kDcp3ReferenceNames{"position", "shaft_signals"};
constexpr std::array<std::string_view, 5> kDataInfoTypeNames{"0", "1", "2", "3", "4"};
// USS C 4.1: a PKW area of 0, 3 or 4 words, or of variable length (PKW = 127 in the drive).
constexpr std::array<std::string_view, 4> kUssPkwNames{"0", "3", "4", "variable"};
// USS B 2.4: the rates a USS interface offers.
constexpr std::array<int, 13> kUssBauds{300,   600,   1200,  2400,  4800,   9600,  19200,
                                        38400, 57600, 76800, 93750, 115200, 187500};
// USS A 4.3: ADR bits 0..4.
constexpr int kMaxUssAddress = 31;
// USS C 5.1: at most 16 PZD words.
constexpr int kMaxUssPzdWords = 16;
// USS A 4.3: 32 addresses on a bus, the drive one of them.
constexpr std::size_t kMaxUssSlaves = 31;
// A polling list may repeat addresses (USS A 2.1); 64 entries cover any sensible weighting.
constexpr std::size_t kMaxPollingList = 64;

// DCP 3.5.3.7: the DCP3 travelling speeds in the order an installation adds them.
constexpr const auto& kDcp3SpeedOrder = drive::kTravelSpeedNames;
// Every DCP speed name (DCP 3.5.3.7), to tell "not a speed" from "not used with this count".
constexpr std::array<std::string_view, 11> kAllSpeedNames{"V0", "VN", "VF", "V1", "VI", "V2",
                                                          "V3", "V4", "V5", "V6", "V7"};

// DCP 5.12.9: I9 carries the position as a sign and six decimal digits of mm.
constexpr std::int64_t kMaxLevelMm = 999999;
// DCP 3.2: deceleration distances are 15-bit values in mm (0x7FFF means "not known").
constexpr std::int64_t kMaxDecelMm = 0x7FFE;
// sockaddr_un::sun_path is 108 bytes on Linux, including the terminating NUL.
constexpr std::int64_t kMaxSocketPathLength = 107;
// useradd/groupadd: names are at most 32 characters.
constexpr std::int64_t kMaxGroupNameLength = 32;
constexpr std::int64_t kFloorNameMaxChars = 16;
constexpr std::size_t kMinFloors = 2;
constexpr std::size_t kMaxFloors = 64;

template <class E, std::size_t N>
std::string_view enum_name(E value, const std::array<std::string_view, N>& names) {
  return names.at(static_cast<std::size_t>(value));
}

template <class E, std::size_t N>
std::optional<E> enum_from(std::string_view name, const std::array<std::string_view, N>& names) {
  for (std::size_t i = 0; i < N; ++i) {
    if (names[i] == name) return static_cast<E>(i);
  }
  return std::nullopt;
}

enum class Type : std::uint8_t { boolean, integer, string, choice, floors, speed_map, custom };

using Problems = std::vector<Problem>;

// One row of the schema table.
struct Key {
  std::string path;
  Type type = Type::integer;
  std::int64_t min = 0;              // integer: smallest value; string: shortest length
  std::int64_t max = 0;              // integer: largest value; string: longest length
  std::vector<std::string> choices;  // choice: the allowed strings
  std::string allowed_text;          // overrides the generated "allowed" column when set
  std::string type_text;             // custom: the "type" column
  std::string description;
  // string: extra rule; returns what is wrong, or an empty string.
  std::function<std::string(const std::string&)> check;
  // Stores a value that passed validation.
  std::function<void(Config&, const json&)> set;
  // Reads the value back (defaults come from get(Config{})).
  std::function<json(const Config&)> get;
  // floors / speed_map: validates and stores in one go.
  std::function<void(const json&, const std::string&, Config&, Problems&)> custom;
};

std::string json_quoted(std::string_view text) {
  return json(std::string(text)).dump();
}

std::string show(const json& value) {
  std::string text = value.dump(-1, ' ', false, json::error_handler_t::replace);
  constexpr std::size_t kMaxShown = 60;
  if (text.size() > kMaxShown) text = text.substr(0, kMaxShown) + "...";
  return text;
}

std::string join_quoted(const std::vector<std::string>& items) {
  std::string out;
  for (const auto& item : items) {
    if (!out.empty()) out += ", ";
    out += json_quoted(item);
  }
  return out;
}

// The closest candidate within a small edit distance, for "did you mean".
std::optional<std::string> closest(std::string_view word, const std::vector<std::string>& pool) {
  std::optional<std::string> best;
  std::size_t best_distance = std::max<std::size_t>(2, word.size() / 3) + 1;
  for (const auto& candidate : pool) {
    std::size_t d = edit_distance(word, candidate);
    // A word that is a longer or shorter form of a candidate ("warning", "warn") is close too.
    const std::string_view shorter = word.size() < candidate.size() ? word : candidate;
    const std::string_view longer = word.size() < candidate.size() ? candidate : word;
    constexpr std::size_t kMinPrefix = 3;
    if (shorter.size() >= kMinPrefix && longer.substr(0, shorter.size()) == shorter) {
      d = std::min<std::size_t>(d, 2);
    }
    if (d < best_distance) {
      best_distance = d;
      best = candidate;
    }
  }
  return best;
}

std::string did_you_mean(std::string_view word, const std::vector<std::string>& pool) {
  auto best = closest(word, pool);
  return best ? " (did you mean " + json_quoted(*best) + "?)" : std::string{};
}

std::size_t utf8_length(std::string_view text) {
  return static_cast<std::size_t>(std::count_if(text.begin(), text.end(), [](char c) {
    return (static_cast<unsigned char>(c) & 0xC0U) != 0x80U;  // count lead bytes only
  }));
}

bool is_integer(const json& value) {
  return value.is_number_integer() || value.is_number_unsigned();
}

// Reads an integer key; false (and a problem) when it is not one or out of range.
bool check_integer(const json& value, const std::string& where, std::int64_t min, std::int64_t max,
                   Problems& problems) {
  const std::string range = std::to_string(min) + ".." + std::to_string(max);
  if (!is_integer(value)) {
    problems.push_back({where, "expected an integer " + range + ", got " + show(value)});
    return false;
  }
  const bool negative = !value.is_number_unsigned() && value.get<std::int64_t>() < 0;
  if (!negative && value.get<std::uint64_t>() > static_cast<std::uint64_t>(max)) {
    problems.push_back({where, show(value) + " is out of range: allowed " + range});
    return false;
  }
  if (value.get<std::int64_t>() < min) {
    problems.push_back({where, show(value) + " is out of range: allowed " + range});
    return false;
  }
  return true;
}

// The byte offset of the first control character (C0, DEL, or a UTF-8 encoded C1 U+0080..U+009F),
// or npos. A NUL would cut a path short where the kernel reads it; the others hide in logs.
std::size_t find_control(std::string_view text) {
  for (std::size_t i = 0; i < text.size(); ++i) {
    const auto byte = static_cast<unsigned char>(text[i]);
    if (byte < 0x20U || byte == 0x7FU) return i;
    if (byte == 0xC2U && i + 1 < text.size()) {
      const auto next = static_cast<unsigned char>(text[i + 1]);
      if (next >= 0x80U && next <= 0x9FU) return i;
    }
  }
  return std::string_view::npos;
}

std::string control_rule(const std::string& text) {
  const std::size_t at = find_control(text);
  if (at == std::string::npos) return {};
  char code[8];
  std::snprintf(code, sizeof code, "0x%02X",
                static_cast<unsigned>(static_cast<unsigned char>(text[at])));
  return std::string("contains a control character (byte ") + code + " at offset " +
         std::to_string(at) + "): not allowed";
}

std::string absolute_path_rule(const std::string& text) {
  if (text.empty() || text.front() != '/') return "must be an absolute path (start with /)";
  return control_rule(text);
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

std::string group_name_rule(const std::string& text) {
  if (text.empty()) return {};  // no group: root and the daemon's own user only
  // shadow-utils' default rule: a lower-case letter or _, then letters, digits, _ or -.
  const auto ok_first = [](char c) { return (c >= 'a' && c <= 'z') || c == '_'; };
  const auto ok_rest = [&](char c) { return ok_first(c) || (c >= '0' && c <= '9') || c == '-'; };
  if (text.empty() || !ok_first(text.front()) ||
      !std::all_of(text.begin() + 1, text.end(), ok_rest)) {
    return "is not a valid group name ([a-z_][a-z0-9_-]*)";
  }
  return {};
}

std::string two_capitals_rule(const std::string& text) {
  if (text.size() != 2 ||
      !std::all_of(text.begin(), text.end(), [](char c) { return c >= 'A' && c <= 'Z'; })) {
    return "must be exactly two capital letters A-Z";
  }
  return {};
}

// DCP 5.12.2.3: the codes the spec's table gives to named companies, lift-controller and drive
// makers alike. Sending one of them in I0 claims to be that company's controller.
std::string maker_code_rule(const std::string& text) {
  if (auto error = two_capitals_rule(text); !error.empty()) return error;
  static constexpr std::array<std::pair<std::string_view, std::string_view>, 21> kTaken = {{
      {"BP", "Boehnke + Partner"},
      {"KN", "Kollmorgen"},
      {"NL", "NEW LIFT"},
      {"OS", "OSMA-Aufzuege"},
      {"LI", "Schneider Steuerungstechnik"},
      {"ST", "Strack Lift Automation"},
      {"AB", "ABB"},
      {"BF", "Brunner & Fecher"},
      {"BH", "Bucher Hydraulics"},
      {"CT", "Control Techniques"},
      {"DA", "Danfoss"},
      {"DE", "Emotron"},
      {"FE", "Fuji Electric"},
      {"SS", "Gefran"},
      {"KW", "KW-Aufzugstechnik"},
      {"MT", "MagneTek"},
      {"RS", "RST Elektronik"},
      {"TY", "Thyssen Krupp"},
      {"VZ", "Venzke-DriveCon"},
      {"YE", "Yaskawa"},
      {"ZA", "Ziehl-Abegg"},
  }};
  for (const auto& [code, owner] : kTaken) {
    if (text == code) {
      return "is " + std::string(owner) +
             "'s code in the DCP 5.12.2.3 table; use a code that table does not list (liftd's "
             "default is LD)";
    }
  }
  return {};
}

// --- Typed key builders: one call per table row. ---------------------------------------------

template <class Section, class T>
Key int_key(std::string path, std::int64_t min, std::int64_t max, std::string description,
            Section Config::*section, T Section::*member) {
  Key key;
  key.path = std::move(path);
  key.type = Type::integer;
  key.min = min;
  key.max = max;
  key.description = std::move(description);
  key.set = [section, member](Config& c, const json& v) {
    c.*section.*member = static_cast<T>(v.get<std::int64_t>());
  };
  key.get = [section, member](const Config& c) { return json(c.*section.*member); };
  return key;
}

template <class Section>
Key bool_key(std::string path, std::string description, Section Config::*section,
             bool Section::*member) {
  Key key;
  key.path = std::move(path);
  key.type = Type::boolean;
  key.description = std::move(description);
  key.set = [section, member](Config& c, const json& v) { c.*section.*member = v.get<bool>(); };
  key.get = [section, member](const Config& c) { return json(c.*section.*member); };
  return key;
}

template <class Section>
Key string_key(std::string path, std::int64_t min_length, std::int64_t max_length,
               std::string allowed_text, std::function<std::string(const std::string&)> check,
               std::string description, Section Config::*section, std::string Section::*member) {
  Key key;
  key.path = std::move(path);
  key.type = Type::string;
  key.min = min_length;
  key.max = max_length;
  key.allowed_text = std::move(allowed_text);
  key.check = std::move(check);
  key.description = std::move(description);
  key.set = [section, member](Config& c, const json& v) {
    c.*section.*member = v.get<std::string>();
  };
  key.get = [section, member](const Config& c) { return json(c.*section.*member); };
  return key;
}

template <class Section, class E, std::size_t N>
Key enum_key(std::string path, const std::array<std::string_view, N>& names,
             std::string description, Section Config::*section, E Section::*member) {
  Key key;
  key.path = std::move(path);
  key.type = Type::choice;
  for (auto name : names) key.choices.emplace_back(name);
  key.description = std::move(description);
  key.set = [section, member, &names](Config& c, const json& v) {
    c.*section.*member = *enum_from<E>(v.get<std::string>(), names);
  };
  key.get = [section, member, &names](const Config& c) {
    return json(std::string(enum_name(c.*section.*member, names)));
  };
  return key;
}

// --- Custom keys. ----------------------------------------------------------------------------

// A floor name is shown on the drive's display (DCP 5.2, appendix A), so it must consist of
// characters that character set has. None of them has a canonical decomposition or is a
// combining mark, so every allowed name is already in Unicode NFC: two names that are equal after
// normalisation are equal byte for byte, and no normalisation table is needed.
constexpr std::string_view kFloorNameRule =
    "1..16 printable characters of the DCP display character set (DCP appendix A: ASCII "
    "letters, digits, space and signs except \\ ~, and \u00e4 \u00f6 \u00fc \u00c4 "
    "\u00d6 \u00dc \u00df \u00b0 \u00b1 \u00b5 and some Greek letters and arrows), no "
    "space at either end";

std::optional<std::string> display_bytes(std::string_view name) {
  std::array<std::uint8_t, 64> out{};
  const dcp::CharsetResult r = dcp::from_utf8(name, out);
  if (!r.ok()) return std::nullopt;
  return std::string(reinterpret_cast<const char*>(out.data()), r.written);
}

void apply_floors(const json& value, const std::string& where, Config& config, Problems& problems) {
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
    bool good = true;
    if (!entry.contains("name")) {
      problems.push_back({at, "missing \"name\""});
      good = false;
    } else if (!entry["name"].is_string()) {
      problems.push_back({at + ".name", "expected a string, got " + show(entry["name"])});
      good = false;
    } else {
      floor.name = entry["name"].get<std::string>();
      const std::size_t length = utf8_length(floor.name);
      const bool displayable = display_bytes(floor.name).has_value();
      const bool padded =
          !floor.name.empty() && (floor.name.front() == ' ' || floor.name.back() == ' ');
      if (length < 1 || length > static_cast<std::size_t>(kFloorNameMaxChars) || !displayable ||
          padded) {
        problems.push_back({at + ".name", show(entry["name"]) +
                                              " is not allowed: " + std::string(kFloorNameRule)});
        good = false;
      }
    }
    if (!entry.contains("level_mm")) {
      problems.push_back({at, "missing \"level_mm\""});
      good = false;
    } else if (check_integer(entry["level_mm"], at + ".level_mm", -kMaxLevelMm, kMaxLevelMm,
                             problems)) {
      floor.level_mm = static_cast<std::int32_t>(entry["level_mm"].get<std::int64_t>());
    } else {
      good = false;
    }
    if (!good) {
      all_good = false;
      continue;
    }
    // Unique as shown on the drive's display: names that differ only in a character the display
    // shows the same way (the micro sign and the Greek mu) are the same name.
    for (std::size_t j = 0; j < floors.size(); ++j) {
      if (display_bytes(floors[j].name) == display_bytes(floor.name)) {
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
          std::find(kAllSpeedNames.begin(), kAllSpeedNames.end(), name) != kAllSpeedNames.end();
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

void apply_uss_baud(const json& value, const std::string& where, Config& config,
                    Problems& problems) {
  std::string allowed;
  for (int baud : kUssBauds) allowed += (allowed.empty() ? "" : ", ") + std::to_string(baud);
  if (!is_integer(value) ||
      std::find(kUssBauds.begin(), kUssBauds.end(), value.get<std::int64_t>()) == kUssBauds.end()) {
    problems.push_back(
        {where, show(value) + " is not a USS rate: use one of " + allowed + " (USS B 2.4)"});
    return;
  }
  config.uss.baud = static_cast<int>(value.get<std::int64_t>());
}

std::optional<UssPkw> uss_pkw_from(const json& value) {
  if (!value.is_string()) return std::nullopt;
  return enum_from<UssPkw>(value.get<std::string>(), kUssPkwNames);
}

void apply_uss_slaves(const json& value, const std::string& where, Config& config,
                      Problems& problems) {
  if (!value.is_array()) {
    problems.push_back(
        {where,
         "expected an array of {\"address\", \"pkw\", \"pzd_words\"} objects, got " + show(value)});
    return;
  }
  if (value.size() > kMaxUssSlaves) {
    problems.push_back({where, "has " + std::to_string(value.size()) + " entries: at most " +
                                   std::to_string(kMaxUssSlaves) + " (USS A 4.3)"});
    return;
  }
  const std::vector<std::string> members{"address", "pkw", "pzd_words"};
  std::vector<UssSlave> slaves;
  bool good = true;
  for (std::size_t i = 0; i < value.size(); ++i) {
    const std::string at = where + "[" + std::to_string(i) + "]";
    const json& entry = value[i];
    if (!entry.is_object()) {
      problems.push_back(
          {at, "expected an object {\"address\", \"pkw\", \"pzd_words\"}, got " + show(entry)});
      good = false;
      continue;
    }
    for (const auto& [k, v] : entry.items()) {
      if (std::find(members.begin(), members.end(), k) == members.end()) {
        problems.push_back({at + "." + k, "unknown key" + did_you_mean(k, members)});
        good = false;
      }
    }
    UssSlave slave;
    if (!entry.contains("address")) {
      problems.push_back({at, "missing \"address\""});
      good = false;
    } else if (check_integer(entry["address"], at + ".address", 0, kMaxUssAddress, problems)) {
      slave.address = static_cast<int>(entry["address"].get<std::int64_t>());
      for (std::size_t j = 0; j < slaves.size(); ++j) {
        if (slaves[j].address == slave.address) {
          problems.push_back({at + ".address", std::to_string(slave.address) +
                                                   " is already the address of " + where + "[" +
                                                   std::to_string(j) + "]"});
          good = false;
        }
      }
    } else {
      good = false;
    }
    if (entry.contains("pkw")) {
      if (auto pkw = uss_pkw_from(entry["pkw"])) {
        slave.pkw = *pkw;
      } else {
        problems.push_back({at + ".pkw", show(entry["pkw"]) +
                                             " is not allowed: use \"0\", \"3\", \"4\" or "
                                             "\"variable\" (USS C 4.1)"});
        good = false;
      }
    }
    if (entry.contains("pzd_words")) {
      if (check_integer(entry["pzd_words"], at + ".pzd_words", 0, kMaxUssPzdWords, problems)) {
        slave.pzd_words = static_cast<int>(entry["pzd_words"].get<std::int64_t>());
      } else {
        good = false;
      }
    }
    slaves.push_back(slave);
  }
  if (good) config.uss.slaves = std::move(slaves);
}

void apply_polling_list(const json& value, const std::string& where, Config& config,
                        Problems& problems) {
  if (!value.is_array() || value.size() > kMaxPollingList) {
    problems.push_back({where, "expected an array of at most " + std::to_string(kMaxPollingList) +
                                   " slave addresses 0..31, got " + show(value)});
    return;
  }
  std::vector<int> list;
  bool good = true;
  for (std::size_t i = 0; i < value.size(); ++i) {
    const std::string at = where + "[" + std::to_string(i) + "]";
    if (check_integer(value[i], at, 0, kMaxUssAddress, problems)) {
      list.push_back(static_cast<int>(value[i].get<std::int64_t>()));
    } else {
      good = false;
    }
  }
  if (good) config.uss.polling_list = std::move(list);
}

void apply_uss_speeds(const json& value, const std::string& where, Config& config,
                      Problems& problems) {
  const std::vector<std::string> names(kAllSpeedNames.begin(), kAllSpeedNames.end());
  if (!value.is_object()) {
    problems.push_back(
        {where,
         "expected an object of speed name -> setpoint (e.g. {\"V4\": 100}), got " + show(value)});
    return;
  }
  std::map<std::string, double> speeds;
  bool good = true;
  for (const auto& [name, setpoint] : value.items()) {
    const std::string at = where + "." + name;
    if (std::find(names.begin(), names.end(), name) == names.end()) {
      problems.push_back({at,
                          "is not a speed name: use V0 (crawl), VN (relevelling), VI "
                          "(inspection) or V1..V7" +
                              did_you_mean(name, names)});
      good = false;
      continue;
    }
    if (!setpoint.is_number() || setpoint.get<double>() <= 0) {
      problems.push_back({at,
                          "expected a positive number in the drive's unit (uss.full_scale), "
                          "got " +
                              show(setpoint)});
      good = false;
      continue;
    }
    speeds[name] = setpoint.get<double>();
  }
  if (good) config.uss.speeds = std::move(speeds);
}

const std::vector<Key>& schema() {
  static const std::vector<Key> table = [] {
    std::vector<Key> t;
    t.push_back(enum_key("log.level", kLogLevelNames,
                         "least severe message logged (--log-level overrides it)", &Config::log,
                         &LogConfig::level));
    // drive
    t.push_back(
        enum_key("drive.kind", drive::kKindNames,
                 "protocol of the drive: DCP over RS485, SCH001 hydraulic card over CAN, or "
                 "Siemens USS over RS485",
                 &Config::drive, &DriveConfig::kind));
    t.push_back(string_key("drive.device", 1, 4096, "absolute path", absolute_path_rule,
                           "serial port of the drive link", &Config::drive, &DriveConfig::device));
    t.push_back(enum_key("drive.rs485", kRs485Names,
                         "kernel RS485 mode: auto = use where supported and warn where not; "
                         "required = refuse to start without it; off = never",
                         &Config::drive, &DriveConfig::rs485));
    // dcp
    t.push_back(string_key("dcp.manufacturer", 2, 2,
                           "two capital letters A-Z, not a code of the DCP 5.12.2.3 table",
                           maker_code_rule, "lift-controller maker code sent in I0 (DCP 5.12.2.3)",
                           &Config::dcp, &DcpConfig::manufacturer));
    t.push_back(string_key("dcp.language", 2, 2, "two capital letters A-Z (ISO 639)",
                           two_capitals_rule,
                           "language code sent in I0; the drive falls back to English "
                           "(DCP 5.12.2)",
                           &Config::dcp, &DcpConfig::language));
    {
      Key k;
      k.path = "dcp.data_info_type";
      k.type = Type::choice;
      for (auto name : kDataInfoTypeNames) k.choices.emplace_back(name);
      k.description =
          "data-information-type set with I1: what the drive's data bytes carry (DCP 5.12.3)";
      k.set = [](Config& c, const json& v) { c.dcp.data_info_type = v.get<std::string>()[0]; };
      k.get = [](const Config& c) { return json(std::string(1, c.dcp.data_info_type)); };
      t.push_back(std::move(k));
    }
    t.push_back(bool_key("dcp.extended_position",
                         "ask for the extended I9 reply with the measured travel distance "
                         "(DCP 5.12.9)",
                         &Config::dcp, &DcpConfig::extended_position));
    t.push_back(int_key("dcp.link_fault_frames", 1, 100,
                        "consecutive bad or missing replies that make a link fault (DCP 7.3: 10)",
                        &Config::dcp, &DcpConfig::link_fault_frames));
    t.push_back(int_key("dcp.link_recover_frames", 1, 100,
                        "consecutive good replies that end a link fault (DCP 7.3: 10)",
                        &Config::dcp, &DcpConfig::link_recover_frames));
    t.push_back(int_key("dcp.request_timeout_ms", 100, 10000,
                        "how long to wait for the drive's reply to an I-message", &Config::dcp,
                        &DcpConfig::request_timeout_ms));
    // rt
    t.push_back(int_key("rt.priority", 1, 99, "SCHED_FIFO priority of the cycle thread",
                        &Config::rt, &RtConfig::priority));
    t.push_back(bool_key("rt.require_realtime",
                         "refuse to start (exit 2) when the cycle thread cannot get SCHED_FIFO at "
                         "rt.priority; false = run with normal scheduling and warn (--simulate "
                         "always runs)",
                         &Config::rt, &RtConfig::require_realtime));
    t.push_back(int_key("rt.cpu", -1, 1023,
                        "CPU the cycle thread is pinned to; -1 = none; must be online and "
                        "allowed for the daemon",
                        &Config::rt, &RtConfig::cpu));
    t.push_back(bool_key("rt.lock_memory", "lock all memory (mlockall) so the cycle never pages",
                         &Config::rt, &RtConfig::lock_memory));
    t.push_back(int_key("rt.flight_recorder_s", 1, 300,
                        "seconds of link traffic kept in memory for fault analysis", &Config::rt,
                        &RtConfig::flight_recorder_s));
    t.push_back(int_key("rt.trace_files_kept", 1, 100,
                        "flight-recorder files (liftd-trace-*.txt) kept in the runtime directory; "
                        "the oldest are removed beyond it",
                        &Config::rt, &RtConfig::trace_files_kept));
    // DCP 7.2: the drive's reply ends by 13.625 ms, the next master frame starts at 15 ms.
    t.push_back(int_key("rt.send_window_us", 0, 1375,
                        "a cycle that wakes up at most this late still sends (counted as a late "
                        "send above 500 us); later wake-ups skip the cycle. DCP 7.2 allows at "
                        "most 15 ms - 13.625 ms = 1375 us",
                        &Config::rt, &RtConfig::send_window_us));
    // api
    t.push_back(string_key("api.socket", 1, kMaxSocketPathLength,
                           "absolute path, at most 107 bytes", absolute_path_rule,
                           "Unix socket of the JSON API", &Config::api, &ApiConfig::socket));
    t.push_back(string_key("api.socket_group", 0, kMaxGroupNameLength, "group name",
                           group_name_rule,
                           "group owning the API socket (empty: the daemon's own group)",
                           &Config::api, &ApiConfig::socket_group));
    t.push_back(string_key(
        "api.read_group", 0, kMaxGroupNameLength, "group name", group_name_rule,
        "members may read state and watch events (empty: nobody but root and the daemon's user)",
        &Config::api, &ApiConfig::read_group));
    t.push_back(
        string_key("api.control_group", 0, kMaxGroupNameLength, "group name", group_name_rule,
                   "members may send calls, travels and resets (empty: root and the daemon's user)",
                   &Config::api, &ApiConfig::control_group));
    t.push_back(string_key("api.inputs_group", 0, kMaxGroupNameLength, "group name",
                           group_name_rule,
                           "members may send machine inputs, the I/O board's daemon (empty: root "
                           "and the daemon's user)",
                           &Config::api, &ApiConfig::inputs_group));
    t.push_back(int_key("api.max_clients", 1, 256, "API connections served at once", &Config::api,
                        &ApiConfig::max_clients));
    t.push_back(int_key("api.max_clients_per_uid", 1, 256,
                        "API connections one user (uid) may hold at once; root is exempt",
                        &Config::api, &ApiConfig::max_clients_per_uid));
    t.push_back(int_key("api.reserved_clients", 0, 255,
                        "of api.max_clients, this many are kept for clients with control access "
                        "(api.control_group, root, the daemon's user); less than api.max_clients",
                        &Config::api, &ApiConfig::reserved_clients));
    t.push_back(int_key("api.stalled_reader_timeout_s", 1, 3600,
                        "drop a client whose replies have waited unread this long (a pipelining "
                        "client that reads is never dropped: liftd stops reading from it instead)",
                        &Config::api, &ApiConfig::stalled_reader_timeout_s));
    t.push_back(int_key("api.idle_timeout_s", 0, 86400,
                        "close a client silent this long; 0 = never", &Config::api,
                        &ApiConfig::idle_timeout_s));
    // 66 Hz is one event per 15 ms cycle (DCP 7.2).
    t.push_back(int_key("api.state_rate_hz", 1, 66,
                        "`state` watch events that only carry new position or speed go out at "
                        "most this often; discrete changes (drive status, link, travel, faults, "
                        "calls) go out from the cycle that saw them",
                        &Config::api, &ApiConfig::state_rate_hz));
    // inputs
    t.push_back(int_key("inputs.timeout_ms", 50, 10000,
                        "machine inputs older than this count as lost (safe stop)", &Config::inputs,
                        &InputsConfig::timeout_ms));
    {
      Key k;
      k.path = "floors";
      k.type = Type::floors;
      k.allowed_text =
          "2..64 entries; name 1..16 characters of the DCP display character set, unique, no "
          "space at either end; level_mm -999999..999999, strictly increasing";
      k.description = "the building's floors, lowest first, level in mm above the lowest floor";
      k.custom = apply_floors;
      k.get = [](const Config& c) {
        json out = json::array();
        for (const auto& f : c.floors) out.push_back({{"name", f.name}, {"level_mm", f.level_mm}});
        return out;
      };
      t.push_back(std::move(k));
    }
    t.push_back(enum_key("position.source", kPositionSourceNames,
                         "where the car's absolute position comes from: sim (--simulate forces "
                         "it), api (the inputs command), can (an absolute encoder on "
                         "can.interface, position.can_*)",
                         &Config::position, &PositionConfig::source));
    t.push_back(int_key("position.can_id", 0, 0x7FF, "11-bit identifier of the encoder's frame",
                        &Config::position, &PositionConfig::can_id));
    t.push_back(int_key("position.can_offset", 0, 6, "first data byte of the position value",
                        &Config::position, &PositionConfig::can_offset));
    t.push_back(int_key("position.can_length", 2, 4, "bytes of the position value",
                        &Config::position, &PositionConfig::can_length));
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
    // travel
    t.push_back(int_key("travel.level_tolerance_mm", 1, 50,
                        "the car counts as level within this distance of the floor",
                        &Config::travel, &TravelConfig::level_tolerance_mm));
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
    {
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
    }
    // can, sch001
    t.push_back(string_key("can.interface", 1, 112,
                           "interface name (at most 15 bytes) or unix:PATH", can_endpoint_rule,
                           "CAN endpoint of the SCH001 card: a SocketCAN interface at 125 kbit/s "
                           "(card document 3a), or unix:PATH where a card simulator listens",
                           &Config::can, &CanConfig::interface));
    // 0x7A0 + 95 = 0x7FF: the card's 96 identifiers stay within 11 bits (card document 1.6).
    t.push_back(int_key("sch001.base", 0, 0x7A0,
                        "card parameter P479: base of the card's 96 CAN identifiers; 0 = 0x550 "
                        "(card document 2.1)",
                        &Config::sch001, &Sch001Config::base));
    t.push_back(int_key("sch001.controller_node", 2, 95,
                        "card parameter P480: our node is base + this (49: 0x581; card document "
                        "1.6, 2.2)",
                        &Config::sch001, &Sch001Config::controller_node));
    t.push_back(bool_key("sch001.single_unit",
                         "one power unit: the card's AVV and PNP2 are valid (card document 3b)",
                         &Config::sch001, &Sch001Config::single_unit));
    t.push_back(enum_key("sch001.fast_down", kFastDownNames,
                         "the fast speed down: hsp when card P435 = 0, sp3 when card P453 = 1",
                         &Config::sch001, &Sch001Config::fast_down));
    t.push_back(bool_key("sch001.has_v3", "the unit has speed V3 (HSP + SP1)", &Config::sch001,
                         &Sch001Config::has_v3));
    t.push_back(bool_key("sch001.has_v4", "the unit has speed V4 (HSP + SP2)", &Config::sch001,
                         &Sch001Config::has_v4));
    t.push_back(int_key("sch001.star_delta_ms", 0, 10000,
                        "motor start (star-delta) before SFY and the up signals", &Config::sch001,
                        &Sch001Config::star_delta_ms));
    t.push_back(int_key("sch001.slowdown_up_mm", 10, 5000,
                        "fast speed up ends this far below the level", &Config::sch001,
                        &Sch001Config::slowdown_up_mm));
    t.push_back(int_key("sch001.slowdown_down_mm", 10, 5000,
                        "fast speed down ends this far above the level", &Config::sch001,
                        &Sch001Config::slowdown_down_mm));
    t.push_back(int_key("sch001.slowdown_v3_mm", 10, 5000, "V3 up ends this far below the level",
                        &Config::sch001, &Sch001Config::slowdown_v3_mm));
    t.push_back(int_key("sch001.slowdown_v4_mm", 10, 5000, "V4 up ends this far below the level",
                        &Config::sch001, &Sch001Config::slowdown_v4_mm));
    t.push_back(int_key("sch001.stop_tolerance_mm", 1, 50,
                        "the slow approach drops every signal within this of the level",
                        &Config::sch001, &Sch001Config::stop_tolerance_mm));
    t.push_back(int_key("sch001.relevel_start_mm", 2, 100,
                        "relevel when the car at rest is further than this from its level",
                        &Config::sch001, &Sch001Config::relevel_start_mm));
    t.push_back(int_key("sch001.max_travel_ms", 5000, 300000,
                        "motor run-time limiter: a travel longer than this ends", &Config::sch001,
                        &Sch001Config::max_travel_ms));
    t.push_back(bool_key("sch001.auto_relevel",
                         "relevel by itself when the car at rest sinks out of the level zone",
                         &Config::sch001, &Sch001Config::auto_relevel));
    // uss
    {
      Key k;
      k.path = "uss.baud";
      k.type = Type::custom;
      k.type_text = "integer";
      k.allowed_text =
          "300, 600, 1200, 2400, 4800, 9600, 19200, 38400, 57600, 76800, 93750, "
          "115200, 187500";
      k.description = "USS bus rate in baud; 8E1 characters (USS B 2.4, B 3.2)";
      k.custom = apply_uss_baud;
      k.get = [](const Config& c) { return json(c.uss.baud); };
      t.push_back(std::move(k));
    }
    t.push_back(int_key("uss.drive_address", 0, kMaxUssAddress,
                        "USS address of the lift drive (ADR bits 0..4, USS A 4.3)", &Config::uss,
                        &UssConfig::drive_address));
    t.push_back(enum_key("uss.drive_pkw", kUssPkwNames,
                         "the drive's PKW area: none, 3 or 4 words, or variable (USS C 4.1); "
                         "set the drive's own PKW parameter alike",
                         &Config::uss, &UssConfig::drive_pkw));
    t.push_back(int_key("uss.drive_pzd_words", 2, kMaxUssPzdWords,
                        "PZD words of the drive (USS C 5.1): STW/ZSW and HSW/HIW at least",
                        &Config::uss, &UssConfig::drive_pzd_words));
    {
      Key k;
      k.path = "uss.slaves";
      k.type = Type::custom;
      k.type_text = "array of {address, pkw, pzd_words}";
      k.allowed_text =
          "at most 31 slaves besides the drive, addresses 0..31 unique, pkw \"0\" "
          "\"3\" \"4\" \"variable\" (default \"4\"), pzd_words 0..16 (default 2)";
      k.description =
          "other USS slaves on the bus (e.g. a door operator), polled for their "
          "parameters and process data";
      k.custom = apply_uss_slaves;
      k.get = [](const Config& c) {
        json out = json::array();
        for (const auto& slave : c.uss.slaves) {
          out.push_back({{"address", slave.address},
                         {"pkw", std::string(enum_name(slave.pkw, kUssPkwNames))},
                         {"pzd_words", slave.pzd_words}});
        }
        return out;
      };
      t.push_back(std::move(k));
    }
    {
      Key k;
      k.path = "uss.polling_list";
      k.type = Type::custom;
      k.type_text = "array of integers";
      k.allowed_text =
          "at most 64 addresses of the drive and uss.slaves, any order, repeats "
          "allowed, the drive at least once; [] = the drive, then each slave";
      k.description = "the order in which the master polls the slaves (USS A 2.1)";
      k.custom = apply_polling_list;
      k.get = [](const Config& c) { return json(c.uss.polling_list); };
      t.push_back(std::move(k));
    }
    t.push_back(int_key("uss.reply_delay_ms", 1, 20,
                        "longest wait for the start of a reply; never below the start pause "
                        "(USS A 5.2.1.1: at most 20 ms)",
                        &Config::uss, &UssConfig::reply_delay_ms));
    t.push_back(int_key("uss.cycle_time_ms", 0, 6500,
                        "fixed time of one pass through the polling list; 0 = as fast as the "
                        "bus allows (USS A 5.1.1)",
                        &Config::uss, &UssConfig::cycle_time_ms));
    t.push_back(int_key("uss.telegram_failures", 1, 100,
                        "consecutive failed telegrams of the drive that end a travel (like a DCP "
                        "link fault)",
                        &Config::uss, &UssConfig::telegram_failures));
    t.push_back(int_key("uss.pkw_repeat_limit", 1, 1000,
                        "polls a parameter request is repeated without its reply before it "
                        "fails (USS C 4)",
                        &Config::uss, &UssConfig::pkw_repeat_limit));
    t.push_back(bool_key("uss.mirror_at_start",
                         "send each slave a mirror telegram as a link test at start (USS A 5.3)",
                         &Config::uss, &UssConfig::mirror_at_start));
    t.push_back(int_key("uss.full_scale_raw", 1, 32767,
                        "main setpoint / actual value word that stands for uss.full_scale "
                        "(USS C 5.2.2: 0x4000 = 16384 = 100 %)",
                        &Config::uss, &UssConfig::full_scale_raw));
    t.push_back(int_key("uss.full_scale", 1, 100000,
                        "the drive's unit at uss.full_scale_raw (100 for percent, 50 for Hz of a "
                        "50 Hz motor, ...)",
                        &Config::uss, &UssConfig::full_scale));
    t.push_back(int_key("uss.profile_timeout_ms", 100, 30000,
                        "the drive reaches the state asked for in its status word within this, "
                        "or it is a drive fault (USS C 5.2.1)",
                        &Config::uss, &UssConfig::profile_timeout_ms));
    {
      Key k;
      k.path = "uss.speeds";
      k.type = Type::custom;
      k.type_text = "object: speed -> setpoint";
      k.allowed_text =
          "V0 (crawl), VN (relevelling), VI (inspection) and every travelling speed "
          "of travel.dcp3_speed_count, each > 0 in uss.full_scale units and within "
          "a signed word once scaled";
      k.description = "main setpoint (HSW) of each speed, in the drive's unit";
      k.custom = apply_uss_speeds;
      k.get = [](const Config& c) { return json(c.uss.speeds); };
      t.push_back(std::move(k));
    }
    t.push_back(int_key("sim.dcp", 3, 4, "DCP version the simulated drive speaks (--simulate)",
                        &Config::sim, &SimConfig::dcp));
    return t;
  }();
  return table;
}

std::vector<std::string> known_paths_and_sections() {
  std::vector<std::string> out;
  for (const auto& key : schema()) {
    out.push_back(key.path);
    const auto dot = key.path.find('.');
    if (dot != std::string::npos) {
      std::string section = key.path.substr(0, dot);
      if (std::find(out.begin(), out.end(), section) == out.end()) out.push_back(section);
    }
  }
  return out;
}

bool is_section(const std::string& name) {
  return std::any_of(schema().begin(), schema().end(),
                     [&](const Key& k) { return k.path.rfind(name + ".", 0) == 0; });
}

bool is_leaf(const std::string& path) {
  return std::any_of(schema().begin(), schema().end(),
                     [&](const Key& k) { return k.path == path; });
}

// Reports unknown keys and sections that are not objects.
void find_unknown(const json& object, const std::string& prefix, Problems& problems) {
  const std::vector<std::string> pool = known_paths_and_sections();
  for (const auto& [name, value] : object.items()) {
    const std::string path = prefix.empty() ? name : prefix + "." + name;
    if (is_leaf(path)) continue;
    if (is_section(path)) {
      if (value.is_object()) {
        find_unknown(value, path, problems);
      } else {
        problems.push_back({path, "expected an object (a section), got " + show(value)});
      }
      continue;
    }
    problems.push_back({path, "unknown key" + did_you_mean(path, pool)});
  }
}

const json* find_value(const json& document, const std::string& path) {
  const json* node = &document;
  std::size_t start = 0;
  while (true) {
    const auto dot = path.find('.', start);
    const std::string part = path.substr(start, dot == std::string::npos ? dot : dot - start);
    if (!node->is_object()) return nullptr;
    const auto it = node->find(part);
    if (it == node->end()) return nullptr;
    node = &*it;
    if (dot == std::string::npos) return node;
    start = dot + 1;
  }
}

void apply_key(const Key& key, const json& value, Config& config, Problems& problems) {
  switch (key.type) {
    case Type::boolean:
      if (!value.is_boolean()) {
        problems.push_back({key.path, "expected true or false, got " + show(value)});
        return;
      }
      break;
    case Type::integer:
      if (!check_integer(value, key.path, key.min, key.max, problems)) return;
      break;
    case Type::string: {
      if (!value.is_string()) {
        problems.push_back({key.path, "expected a string, got " + show(value)});
        return;
      }
      const auto text = value.get<std::string>();
      const auto length = static_cast<std::int64_t>(text.size());
      if (length < key.min || length > key.max) {
        problems.push_back({key.path, show(value) + " has " + std::to_string(length) +
                                          " bytes: allowed " + std::to_string(key.min) + ".." +
                                          std::to_string(key.max)});
        return;
      }
      if (key.check) {
        const std::string why = key.check(text);
        if (!why.empty()) {
          problems.push_back({key.path, show(value) + " " + why});
          return;
        }
      }
      break;
    }
    case Type::choice:
      if (!value.is_string() || std::find(key.choices.begin(), key.choices.end(),
                                          value.get<std::string>()) == key.choices.end()) {
        problems.push_back(
            {key.path, show(value) + " is not allowed: use one of " + join_quoted(key.choices) +
                           (value.is_string() ? did_you_mean(value.get<std::string>(), key.choices)
                                              : std::string{})});
        return;
      }
      break;
    case Type::floors:
    case Type::speed_map:
    case Type::custom:
      key.custom(value, key.path, config, problems);
      return;
  }
  key.set(config, value);
}

// The uss.* keys that must agree with each other (only for a USS lift).
void check_uss(const Config& config, Problems& problems) {
  const UssConfig& uss = config.uss;
  // The CAN encoder needs a CAN runner of its own; the USS lift has none in this version.
  if (config.position.source == PositionSource::can) {
    problems.push_back({"position.source",
                        "\"can\" is not available with drive.kind \"uss\" in "
                        "this version: use \"api\" (the inputs command)"});
  }
  auto known = [&](int address) {
    return address == uss.drive_address ||
           std::any_of(uss.slaves.begin(), uss.slaves.end(),
                       [&](const UssSlave& s) { return s.address == address; });
  };
  for (std::size_t i = 0; i < uss.slaves.size(); ++i) {
    if (uss.slaves[i].address == uss.drive_address) {
      problems.push_back({"uss.slaves[" + std::to_string(i) + "].address",
                          std::to_string(uss.drive_address) +
                              " is uss.drive_address: the drive is not listed again"});
    }
  }
  for (std::size_t i = 0; i < uss.polling_list.size(); ++i) {
    if (!known(uss.polling_list[i])) {
      problems.push_back({"uss.polling_list[" + std::to_string(i) + "]",
                          std::to_string(uss.polling_list[i]) +
                              " is neither uss.drive_address nor in uss.slaves"});
    }
  }
  if (!uss.polling_list.empty() && std::find(uss.polling_list.begin(), uss.polling_list.end(),
                                             uss.drive_address) == uss.polling_list.end()) {
    problems.push_back({"uss.polling_list", "never polls the drive (uss.drive_address " +
                                                std::to_string(uss.drive_address) + ")"});
  }
  std::vector<std::string> needed = {"V0", "VN", "VI"};
  for (const auto& name : dcp3_speeds(config.travel.dcp3_speed_count)) needed.push_back(name);
  for (const auto& name : needed) {
    if (uss.speeds.count(name) == 0) {
      problems.push_back({"uss.speeds", "has no setpoint for " + name +
                                            ": V0, VN, VI and every speed of "
                                            "travel.dcp3_speed_count need one"});
    }
  }
  // USS C 5.2.2: the main setpoint is a signed word.
  const double limit = static_cast<double>(uss.full_scale) * 32767.0 / uss.full_scale_raw;
  for (const auto& [name, setpoint] : uss.speeds) {
    if (setpoint > limit) {
      std::ostringstream text;
      text << setpoint << " does not fit the signed setpoint word: at most " << limit
           << " with uss.full_scale " << uss.full_scale << " = uss.full_scale_raw "
           << uss.full_scale_raw;
      problems.push_back({"uss.speeds." + name, text.str()});
    }
  }
}

void check_cross_keys(const Config& config, const json& document, Problems& problems) {
  if (config.position.can_offset + config.position.can_length > 8) {
    problems.push_back({"position.can_offset",
                        std::to_string(config.position.can_offset) + " + position.can_length " +
                            std::to_string(config.position.can_length) +
                            " must stay within the 8 data bytes of a CAN frame"});
  }
  if (config.position.can_um_per_count == 0) {
    problems.push_back({"position.can_um_per_count", "0 is no scale: use micrometres per count"});
  }
  // The SCH001 frame carries floor numbers in one byte (card document 3c).
  if (config.drive.kind == DriveKind::Sch001 && config.floors.size() > 255) {
    problems.push_back({"floors", "an SCH001 lift has at most 255 floors (one byte, 3c)"});
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

// 1-based line and column of a byte offset, for parse errors.
std::pair<std::size_t, std::size_t> line_column(std::string_view text, std::size_t offset) {
  offset = std::min(offset, text.size());
  std::size_t line = 1;
  std::size_t column = 1;
  for (std::size_t i = 0; i < offset; ++i) {
    if (text[i] == '\n') {
      ++line;
      column = 1;
    } else {
      ++column;
    }
  }
  return {line, column};
}

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

std::vector<Floor> default_floors() {
  // Six floors 3 m apart: a small building for --simulate and the examples.
  std::vector<Floor> floors;
  constexpr int kFloorCount = 6;
  constexpr std::int32_t kFloorHeightMm = 3000;
  for (int i = 0; i < kFloorCount; ++i) floors.push_back({std::to_string(i), i * kFloorHeightMm});
  return floors;
}

std::string to_string(const Problem& problem) {
  return problem.where + ": " + problem.message;
}

std::vector<std::string> dcp3_speeds(int speed_count) {
  std::vector<std::string> out;
  for (int i = 0; i < speed_count && i < static_cast<int>(kDcp3SpeedOrder.size()); ++i) {
    out.emplace_back(kDcp3SpeedOrder[static_cast<std::size_t>(i)]);
  }
  return out;
}

std::size_t edit_distance(std::string_view a, std::string_view b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diagonal = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t above = row[j];
      const std::size_t cost = a[i - 1] == b[j - 1] ? 0 : 1;
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + cost});
      diagonal = above;
    }
  }
  return row[b.size()];
}

LoadResult from_json(const json& document) {
  LoadResult result;
  if (!document.is_object()) {
    result.problems.push_back({"(top level)", "expected a JSON object, got " + show(document)});
    return result;
  }
  find_unknown(document, "", result.problems);
  for (const auto& key : schema()) {
    if (const json* value = find_value(document, key.path)) {
      apply_key(key, *value, result.config, result.problems);
    }
  }
  // A valid speed count with the default distances can still disagree: check them together.
  if (find_value(document, "travel.dcp3_decel_distance_mm") == nullptr &&
      find_value(document, "travel.dcp3_speed_count") != nullptr) {
    for (const auto& key : schema()) {
      if (key.type == Type::speed_map) {
        apply_key(key, key.get(result.config), result.config, result.problems);
      }
    }
  }
  check_cross_keys(result.config, document, result.problems);
  if (result.config.drive.kind == DriveKind::Uss) check_uss(result.config, result.problems);
  return result;
}

LoadResult parse(std::string_view text, std::string_view origin) {
  // Track the keys of each open object to report duplicates, which JSON parsers drop silently.
  struct Frame {
    bool is_object;
    std::vector<std::string> keys;
    std::string name;
  };
  std::vector<Frame> stack;
  std::string pending_key;
  Problems duplicates;
  const auto path_of = [&](const std::string& key) {
    std::string out;
    for (const auto& f : stack) {
      if (!f.name.empty()) out += (out.empty() ? "" : ".") + f.name;
    }
    return out.empty() ? key : out + "." + key;
  };
  const json::parser_callback_t callback = [&](int /*depth*/, json::parse_event_t event,
                                               json& parsed) {
    switch (event) {
      case json::parse_event_t::object_start:
      case json::parse_event_t::array_start:
        stack.push_back({event == json::parse_event_t::object_start, {}, pending_key});
        pending_key.clear();
        break;
      case json::parse_event_t::object_end:
      case json::parse_event_t::array_end:
        if (!stack.empty()) stack.pop_back();
        break;
      case json::parse_event_t::key: {
        const auto key = parsed.get<std::string>();
        if (!stack.empty() && stack.back().is_object) {
          auto& keys = stack.back().keys;
          if (std::find(keys.begin(), keys.end(), key) != keys.end()) {
            duplicates.push_back({path_of(key), "duplicate key: only one value is allowed"});
          }
          keys.push_back(key);
        }
        pending_key = key;
        break;
      }
      case json::parse_event_t::value:
        pending_key.clear();
        break;
    }
    return true;
  };
  json document;
  try {
    document = json::parse(text.begin(), text.end(), callback, true, false);
  } catch (const json::parse_error& error) {
    const auto [line, column] = line_column(text, error.byte == 0 ? 0 : error.byte - 1);
    std::string what = error.what();
    // nlohmann's text starts with "[json.exception.parse_error.101] parse error at line ..:";
    // keep only the part after the last ": " (what was expected and found).
    const auto colon = what.rfind(": ");
    if (colon != std::string::npos) what = what.substr(colon + 2);
    LoadResult result;
    result.problems.push_back(
        {std::string(origin) + ":" + std::to_string(line) + ":" + std::to_string(column),
         "malformed JSON: " + what});
    return result;
  } catch (const json::exception& error) {
    // out_of_range 406: a number too large for any JSON number type (e.g. 1E989299). The
    // library gives no position for it.
    LoadResult result;
    result.problems.push_back(
        {std::string(origin), error.id == 406 ? "malformed JSON: a number is too large to represent"
                                              : std::string("malformed JSON: ") + error.what()});
    return result;
  }
  LoadResult result = from_json(document);
  result.problems.insert(result.problems.begin(), duplicates.begin(), duplicates.end());
  return result;
}

namespace {

std::string file_type_name(mode_t mode) {
  if (S_ISDIR(mode)) return std::strerror(EISDIR);  // "Is a directory", as read() would say
  if (S_ISFIFO(mode)) return "it is a FIFO";
  if (S_ISCHR(mode)) return "it is a character device";
  if (S_ISBLK(mode)) return "it is a block device";
  if (S_ISSOCK(mode)) return "it is a socket";
  return "it is of an unknown type";
}

}  // namespace

LoadResult load_file(const std::filesystem::path& path) {
  const auto problem = [&](std::string message) {
    LoadResult result;
    result.problems.push_back({path.string(), std::move(message)});
    return result;
  };
  const auto unreadable = [&](int error) {
    return problem(std::string("cannot read the config file: ") + std::strerror(error));
  };
  const auto not_regular = [&](mode_t mode) {
    return problem("cannot read the config file: " + file_type_name(mode) +
                   "; only a regular file is read");
  };
  const auto too_large = [&]() {
    return problem("cannot read the config file: it is larger than " +
                   std::to_string(kMaxFileBytes) + " bytes");
  };
  // Look before opening: opening a device can have effects (a serial port drops DTR) and a FIFO
  // blocks. Symbolic links are followed (a config under /etc may well be one).
  struct stat before {};
  if (::stat(path.c_str(), &before) != 0) return unreadable(errno);
  if (!S_ISREG(before.st_mode)) return not_regular(before.st_mode);
  // O_NONBLOCK: should the path become a FIFO between stat() and open(), open() still returns;
  // fstat() then tells what was really opened.
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK | O_NOCTTY);
  if (fd < 0) return unreadable(errno);
  struct stat opened {};
  if (::fstat(fd, &opened) != 0) {
    const int error = errno;
    ::close(fd);
    return unreadable(error);
  }
  if (!S_ISREG(opened.st_mode)) {
    ::close(fd);
    return not_regular(opened.st_mode);
  }
  if (static_cast<std::uintmax_t>(opened.st_size) > kMaxFileBytes) {
    ::close(fd);
    return too_large();
  }
  std::string text;
  char buffer[4096];
  while (true) {
    const ssize_t n = ::read(fd, buffer, sizeof(buffer));
    if (n < 0) {
      const int error = errno;
      if (error == EINTR) continue;
      ::close(fd);
      return unreadable(error);
    }
    if (n == 0) break;
    // The file may grow while we read it: the limit holds for what is read, too.
    if (text.size() + static_cast<std::size_t>(n) > kMaxFileBytes) {
      ::close(fd);
      return too_large();
    }
    text.append(buffer, static_cast<std::size_t>(n));
  }
  ::close(fd);
  LoadResult result = parse(text, path.string());
  const Problems host = check_host(result.config, HostFacts::current());
  result.problems.insert(result.problems.end(), host.begin(), host.end());
  return result;
}

HostFacts HostFacts::current() {
  HostFacts facts;
  cpu_set_t set;
  CPU_ZERO(&set);
  // The affinity mask holds only CPUs that are online and that this process (its cgroup's
  // cpuset, the unit's CPUAffinity=) may use: exactly where the cycle thread can be pinned.
  if (::sched_getaffinity(0, sizeof set, &set) == 0) {
    for (int cpu = 0; cpu < CPU_SETSIZE; ++cpu) {
      if (CPU_ISSET(static_cast<std::size_t>(cpu), &set)) facts.usable_cpus.push_back(cpu);
    }
  }
  return facts;
}

std::vector<Problem> check_host(const Config& config, const HostFacts& host) {
  Problems problems;
  if (config.rt.cpu >= 0 && std::find(host.usable_cpus.begin(), host.usable_cpus.end(),
                                      config.rt.cpu) == host.usable_cpus.end()) {
    std::string usable;
    for (std::size_t i = 0; i < host.usable_cpus.size(); ++i) {
      // Ranges as the kernel writes them: 0-3,6.
      std::size_t j = i;
      while (j + 1 < host.usable_cpus.size() &&
             host.usable_cpus[j + 1] == host.usable_cpus[j] + 1) {
        ++j;
      }
      if (!usable.empty()) usable += ",";
      usable += std::to_string(host.usable_cpus[i]);
      if (j > i) usable += "-" + std::to_string(host.usable_cpus[j]);
      i = j;
    }
    problems.push_back({"rt.cpu", std::to_string(config.rt.cpu) +
                                      " is not a CPU this machine lets liftd run on: use -1 or "
                                      "one of " +
                                      (usable.empty() ? std::string("(none found)") : usable)});
  }
  return problems;
}

nlohmann::json to_json(const Config& config) {
  json out = json::object();
  for (const auto& key : schema()) {
    std::string pointer = "/" + key.path;
    std::replace(pointer.begin(), pointer.end(), '.', '/');
    out[json::json_pointer(pointer)] = key.get(config);
  }
  return out;
}

std::string summary(const Config& config) {
  std::ostringstream out;
  if (config.drive.kind == DriveKind::Sch001) {
    // Card document 1.6 and 2: base P479 (0 = 0x550), our node base + P480.
    const int base = config.sch001.base == 0 ? 0x550 : config.sch001.base;
    char ids[64];
    std::snprintf(ids, sizeof ids, "card receives on 0x%03X, sends to 0x%03X", base + 1,
                  base + config.sch001.controller_node);
    out << "drive:    sch001 on CAN " << config.can.interface << " (" << ids << ")\n";
    out << "sch001:   " << (config.sch001.single_unit ? "single unit" : "several units")
        << ", fast down by " << (config.sch001.fast_down == FastDown::sp3 ? "SP3" : "HSP")
        << (config.sch001.has_v4   ? ", V3 and V4"
            : config.sch001.has_v3 ? ", V3"
                                   : "")
        << ", star-delta " << config.sch001.star_delta_ms << " ms\n";
  } else if (config.drive.kind == DriveKind::Uss) {
    out << "drive:    uss on " << config.drive.device << " at " << config.uss.baud
        << " baud 8E1 (rs485 " << to_string(config.drive.rs485) << "), drive address "
        << config.uss.drive_address << ", PKW " << enum_name(config.uss.drive_pkw, kUssPkwNames)
        << ", PZD " << config.uss.drive_pzd_words << " words\n";
    out << "uss:      " << config.uss.slaves.size() << " other slave(s), polling list "
        << (config.uss.polling_list.empty() ? std::string("drive then each slave")
                                            : json(config.uss.polling_list).dump())
        << ", reply delay " << config.uss.reply_delay_ms << " ms\n";
  } else {
    out << "drive:    " << to_string(config.drive.kind) << " on " << config.drive.device
        << " (rs485 " << to_string(config.drive.rs485) << ")\n";
    out << "dcp:      maker " << config.dcp.manufacturer << ", language " << config.dcp.language
        << ", data-information-type " << config.dcp.data_info_type << ", link fault after "
        << config.dcp.link_fault_frames << " frames\n";
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

std::string reference_markdown() {
  const Config defaults;
  std::ostringstream out;
  out << "| Key | Type | Default | Allowed | Description |\n";
  out << "| --- | --- | --- | --- | --- |\n";
  for (const auto& key : schema()) {
    out << "| `" << key.path << "` | " << markdown_cell(type_name(key)) << " | `"
        << markdown_cell(key.get(defaults).dump()) << "` | " << markdown_cell(allowed_text(key))
        << " | " << markdown_cell(key.description) << " |\n";
  }
  return out.str();
}

std::vector<std::string> key_paths() {
  std::vector<std::string> out;
  for (const auto& key : schema()) out.push_back(key.path);
  return out;
}

std::string_view to_string(LogLevel value) {
  return enum_name(value, kLogLevelNames);
}
std::string_view to_string(Rs485Mode value) {
  return enum_name(value, kRs485Names);
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

std::optional<LogLevel> parse_log_level(std::string_view name) {
  return enum_from<LogLevel>(name, kLogLevelNames);
}

}  // namespace liftd::config
