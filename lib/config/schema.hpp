// What a section of the configuration file declares: its keys (type, range, default, the
// reference text) and the checks across them. The shared sections are in lib/config; each drive
// kind declares its own section in its folder (lib/<kind>/config) with the same tools, and
// lib/kinds puts them together into the one Schema the loader, the dump and the reference use.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "config/config.hpp"

namespace liftd::config {

/// Every problem found so far, in the order found.
using Problems = std::vector<Problem>;

/// How a key's value is checked and shown in the reference.
enum class Type : std::uint8_t { boolean, integer, string, choice, floors, speed_map, custom };

/// One key of the file: one row of the reference.
struct Key {
  std::string path;                  ///< "section.key"
  Type type = Type::integer;         ///< how the value is checked
  std::int64_t min = 0;              ///< integer: smallest value; string: shortest length
  std::int64_t max = 0;              ///< integer: largest value; string: longest length
  std::vector<std::string> choices;  ///< choice: the allowed strings
  std::string allowed_text;          ///< overrides the generated "allowed" column when set
  std::string type_text;             ///< custom: the "type" column
  std::string description;           ///< the reference's description column
  /// string: extra rule; returns what is wrong, or an empty string.
  std::function<std::string(const std::string&)> check;
  /// Stores a value that passed validation.
  std::function<void(Config&, const nlohmann::json&)> set;
  /// Reads the value back (defaults come from get(Config{})).
  std::function<nlohmann::json(const Config&)> get;
  /// floors / speed_map / custom: validates and stores in one go.
  std::function<void(const nlohmann::json&, const std::string&, Config&, Problems&)> custom;
};

/// A check across keys: the configuration as loaded, the document it came from (to tell a key
/// set in the file from a default) and the problems to add to.
using CrossCheck =
    std::function<void(const Config& config, const nlohmann::json& document, Problems& problems)>;

/// A drive kind's part of the schema. Its keys are accepted and checked for type and range
/// whatever `drive.kind` says (a file may keep the sections of other kinds); its cross-check and
/// its summary apply only when `drive.kind` is this kind.
struct KindRules {
  DriveKind kind = DriveKind::Dcp;  ///< the kind these rules belong to
  std::vector<Key> keys;            ///< the keys of its section, in reference order
  CrossCheck check;                 ///< the checks across its keys (may be empty)
  /// The `--check-config` summary lines that describe the drive, each ending in a newline.
  std::function<std::string(const Config&)> summary;
};

/// What a floor may be: the characters its name may have and how far its level may be from the
/// lowest floor. Given by the kind whose display and position report set the limits.
struct FloorRules {
  /// The character set's name in the reference ("the DCP display character set").
  std::string charset_name;
  /// What the character set holds, in a problem's text (after the name, in parentheses).
  std::string charset_details;
  /// The bytes a name is shown as, nullopt where the character set cannot show it. Two names
  /// shown alike are the same name.
  std::function<std::optional<std::string>(std::string_view name)> shown_as;
  /// level_mm lies within -max_level_mm..max_level_mm.
  std::int64_t max_level_mm = 0;
};

/// Every key of the file in reference order, and the kinds' rules. lib/kinds builds the one the
/// daemon uses (kinds::config_schema()).
class Schema {
 public:
  /// Appends the keys of a shared section.
  void add(std::vector<Key> keys);
  /// Appends a drive kind's section; its cross-check and summary apply to that kind only.
  void add(KindRules kind);
  /// Every key, in the order added.
  const std::vector<Key>& keys() const noexcept { return keys_; }
  /// The rules of a kind; nullptr when no section of that kind was added.
  const KindRules* rules_of(DriveKind kind) const noexcept;

 private:
  std::vector<Key> keys_;
  std::vector<KindRules> kinds_;
};

// --- The shared sections, one function each (lib/config/sections_*.cpp). ---------------------

std::vector<Key> log_keys();     ///< log.*
std::vector<Key> drive_keys();   ///< drive.*
std::vector<Key> rt_keys();      ///< rt.*
std::vector<Key> api_keys();     ///< api.*
std::vector<Key> inputs_keys();  ///< inputs.*
std::vector<Key> record_keys();  ///< record.*
std::vector<Key> eta_keys();     ///< eta.*
/// floors, with the names and levels `rules` allows.
std::vector<Key> floors_keys(const FloorRules& rules);
std::vector<Key> position_keys();  ///< position.*
std::vector<Key> travel_keys();    ///< travel.*
std::vector<Key> can_keys();       ///< can.*
std::vector<Key> sim_keys();       ///< sim.*
/// The checks across the shared sections (position, api, travel); run for every kind.
void check_shared_keys(const Config& config, const nlohmann::json& document, Problems& problems);

// --- Helpers for the rules of a section. -----------------------------------------------------

/// Every DCP speed name (DCP 3.5.3.7): crawl, relevelling, fast start, inspection and V1..V7.
inline constexpr std::array<std::string_view, 11> kSpeedNames{"V0", "VN", "VF", "V1", "VI", "V2",
                                                              "V3", "V4", "V5", "V6", "V7"};

/// The name of an enum value in its name table (enum order).
template <class E, std::size_t N>
std::string_view enum_name(E value, const std::array<std::string_view, N>& names) {
  return names.at(static_cast<std::size_t>(value));
}

/// The enum value of a name in its name table; nullopt for a name not in it.
template <class E, std::size_t N>
std::optional<E> enum_from(std::string_view name, const std::array<std::string_view, N>& names) {
  for (std::size_t i = 0; i < N; ++i) {
    if (names[i] == name) return static_cast<E>(i);
  }
  return std::nullopt;
}

/// A JSON value as a problem shows it: compact, cut after 60 characters.
std::string show(const nlohmann::json& value);
/// A text in JSON quotes.
std::string json_quoted(std::string_view text);
/// " (did you mean \"x\"?)" for the closest word of `pool`, or an empty string.
std::string did_you_mean(std::string_view word, const std::vector<std::string>& pool);
/// True for a JSON integer, signed or unsigned.
bool is_integer(const nlohmann::json& value);
/// True when `value` is an integer min..max; otherwise adds a problem at `where`.
bool check_integer(const nlohmann::json& value, const std::string& where, std::int64_t min,
                   std::int64_t max, Problems& problems);
/// The value at a dotted key path of a document; nullptr when it is not there.
const nlohmann::json* find_value(const nlohmann::json& document, const std::string& path);
/// string rule: no control character (C0, DEL, C1); returns what is wrong, or "".
std::string control_rule(const std::string& text);
/// string rule: an absolute path without control characters; returns what is wrong, or "".
std::string absolute_path_rule(const std::string& text);

// --- Typed key builders: one call per key. ---------------------------------------------------

/// Where a drive kind's section is (Config::kinds): the `section` of a key of that section,
/// `kind_section<Sch001Config>`, as `&Config::travel` is of a shared one.
template <class Section>
struct KindSection {};
template <class Section>
inline constexpr KindSection<Section> kind_section{};

/// The section a key's `section` names in `c`.
template <class Section>
Section& section_in(Config& c, Section Config::*section) {
  return c.*section;
}
template <class Section>
const Section& section_in(const Config& c, Section Config::*section) {
  return c.*section;
}
template <class Section>
Section& section_in(Config& c, KindSection<Section>) {
  return c.kinds.get<Section>();
}
template <class Section>
const Section& section_in(const Config& c, KindSection<Section>) {
  return c.kinds.get<Section>();
}

/// An integer key min..max stored in `member` of the section `section` names.
template <class Where, class Section, class T>
Key int_key(std::string path, std::int64_t min, std::int64_t max, std::string description,
            Where section, T Section::*member) {
  Key key;
  key.path = std::move(path);
  key.type = Type::integer;
  key.min = min;
  key.max = max;
  key.description = std::move(description);
  key.set = [section, member](Config& c, const nlohmann::json& v) {
    section_in(c, section).*member = static_cast<T>(v.get<std::int64_t>());
  };
  key.get = [section, member](const Config& c) {
    return nlohmann::json(section_in(c, section).*member);
  };
  return key;
}

/// A boolean key stored in `member` of the section `section` names.
template <class Where, class Section>
Key bool_key(std::string path, std::string description, Where section, bool Section::*member) {
  Key key;
  key.path = std::move(path);
  key.type = Type::boolean;
  key.description = std::move(description);
  key.set = [section, member](Config& c, const nlohmann::json& v) {
    section_in(c, section).*member = v.get<bool>();
  };
  key.get = [section, member](const Config& c) {
    return nlohmann::json(section_in(c, section).*member);
  };
  return key;
}

/// A string key of min_length..max_length bytes that passes `check` (may be empty).
template <class Where, class Section>
Key string_key(std::string path, std::int64_t min_length, std::int64_t max_length,
               std::string allowed_text, std::function<std::string(const std::string&)> check,
               std::string description, Where section, std::string Section::*member) {
  Key key;
  key.path = std::move(path);
  key.type = Type::string;
  key.min = min_length;
  key.max = max_length;
  key.allowed_text = std::move(allowed_text);
  key.check = std::move(check);
  key.description = std::move(description);
  key.set = [section, member](Config& c, const nlohmann::json& v) {
    section_in(c, section).*member = v.get<std::string>();
  };
  key.get = [section, member](const Config& c) {
    return nlohmann::json(section_in(c, section).*member);
  };
  return key;
}

/// A key naming an enum value; `names` (enum order) must outlive the key.
template <class Where, class Section, class E, std::size_t N>
Key enum_key(std::string path, const std::array<std::string_view, N>& names,
             std::string description, Where section, E Section::*member) {
  Key key;
  key.path = std::move(path);
  key.type = Type::choice;
  for (auto name : names) key.choices.emplace_back(name);
  key.description = std::move(description);
  key.set = [section, member, &names](Config& c, const nlohmann::json& v) {
    section_in(c, section).*member = *enum_from<E>(v.get<std::string>(), names);
  };
  key.get = [section, member, &names](const Config& c) {
    return nlohmann::json(std::string(enum_name(section_in(c, section).*member, names)));
  };
  return key;
}

/// A key with its own check and store (`custom`) and value (`get`): the reference shows
/// `type_text` and `allowed_text`.
Key custom_key(
    std::string path, std::string type_text, std::string allowed_text, std::string description,
    std::function<void(const nlohmann::json&, const std::string&, Config&, Problems&)> custom,
    std::function<nlohmann::json(const Config&)> get);

}  // namespace liftd::config
