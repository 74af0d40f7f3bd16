#include "sch001/registry_entry.hpp"

#include <array>
#include <cstdio>
#include <sstream>

#include "config/schema.hpp"
#include "sch001/config/section.hpp"
#include "sch001/protocol.hpp"

namespace liftd::sch001 {
namespace {

using config::Config;
using config::FastDown;
using config::Key;
using config::Problems;
using config::Sch001Config;
using nlohmann::json;

constexpr std::array<std::string_view, 2> kFastDownNames{"hsp", "sp3"};
// Card document 3c: the frames carry floor numbers in one byte.
constexpr std::size_t kMaxFloors = 255;

// The shared keys a SCH001 lift needs beyond their own range (only for a SCH001 lift).
void check_sch001(const Config& cfg, const json& /*document*/, Problems& problems) {
  if (cfg.floors.size() > kMaxFloors) {
    problems.push_back({"floors", "an SCH001 lift has at most 255 floors (one byte, 3c)"});
  }
}

std::string sch001_summary(const Config& cfg) {
  std::ostringstream out;
  // Card document 1.6 and 2: base P479 (0 = 0x550), our node base + P480.
  const int base =
      sch001_section(cfg).base == 0 ? static_cast<int>(kDefaultBase) : sch001_section(cfg).base;
  char ids[64];
  std::snprintf(ids, sizeof ids, "card receives on 0x%03X, sends to 0x%03X", base + 1,
                base + sch001_section(cfg).controller_node);
  out << "drive:    sch001 on CAN " << cfg.can.interface << " (" << ids << ")\n";
  out << "sch001:   " << (sch001_section(cfg).single_unit ? "single unit" : "several units")
      << ", fast down by " << (sch001_section(cfg).fast_down == FastDown::sp3 ? "SP3" : "HSP")
      << (sch001_section(cfg).has_v4   ? ", V3 and V4"
          : sch001_section(cfg).has_v3 ? ", V3"
                                       : "")
      << ", star-delta " << sch001_section(cfg).star_delta_ms << " ms\n";
  return out.str();
}

std::vector<Key> sch001_keys() {
  std::vector<Key> t;
  // 0x7A0 + 95 = 0x7FF: the card's 96 identifiers stay within 11 bits (card document 1.6).
  t.push_back(
      config::int_key("sch001.base", 0, 0x7A0,
                      "card parameter P479: base of the card's 96 CAN identifiers; 0 = 0x550 "
                      "(card document 2.1)",
                      config::kind_section<config::Sch001Config>, &Sch001Config::base));
  t.push_back(
      config::int_key("sch001.controller_node", 2, 95,
                      "card parameter P480: our node is base + this (49: 0x581; card document "
                      "1.6, 2.2)",
                      config::kind_section<config::Sch001Config>, &Sch001Config::controller_node));
  t.push_back(config::bool_key(
      "sch001.single_unit", "one power unit: the card's AVV and PNP2 are valid (card document 3b)",
      config::kind_section<config::Sch001Config>, &Sch001Config::single_unit));
  t.push_back(
      config::enum_key("sch001.fast_down", kFastDownNames,
                       "the fast speed down: hsp when card P435 = 0, sp3 when card P453 = 1",
                       config::kind_section<config::Sch001Config>, &Sch001Config::fast_down));
  t.push_back(config::bool_key("sch001.has_v3", "the unit has speed V3 (HSP + SP1)",
                               config::kind_section<config::Sch001Config>, &Sch001Config::has_v3));
  t.push_back(config::bool_key("sch001.has_v4", "the unit has speed V4 (HSP + SP2)",
                               config::kind_section<config::Sch001Config>, &Sch001Config::has_v4));
  t.push_back(config::int_key(
      "sch001.star_delta_ms", 0, 10000, "motor start (star-delta) before SFY and the up signals",
      config::kind_section<config::Sch001Config>, &Sch001Config::star_delta_ms));
  t.push_back(config::int_key(
      "sch001.slowdown_up_mm", 10, 5000, "fast speed up ends this far below the level",
      config::kind_section<config::Sch001Config>, &Sch001Config::slowdown_up_mm));
  t.push_back(config::int_key(
      "sch001.slowdown_down_mm", 10, 5000, "fast speed down ends this far above the level",
      config::kind_section<config::Sch001Config>, &Sch001Config::slowdown_down_mm));
  t.push_back(
      config::int_key("sch001.slowdown_v3_mm", 10, 5000, "V3 up ends this far below the level",
                      config::kind_section<config::Sch001Config>, &Sch001Config::slowdown_v3_mm));
  t.push_back(
      config::int_key("sch001.slowdown_v4_mm", 10, 5000, "V4 up ends this far below the level",
                      config::kind_section<config::Sch001Config>, &Sch001Config::slowdown_v4_mm));
  t.push_back(config::int_key("sch001.stop_tolerance_mm", 1, 50,
                              "the slow approach drops every signal within this of the level",
                              config::kind_section<config::Sch001Config>,
                              &Sch001Config::stop_tolerance_mm));
  t.push_back(config::int_key("sch001.relevel_start_mm", 2, 100,
                              "relevel when the car at rest is further than this from its level",
                              config::kind_section<config::Sch001Config>,
                              &Sch001Config::relevel_start_mm));
  t.push_back(config::int_key("sch001.max_travel_ms", 5000, 300000,
                              "motor run-time limiter: a travel longer than this ends",
                              config::kind_section<config::Sch001Config>,
                              &Sch001Config::max_travel_ms));
  t.push_back(config::bool_key(
      "sch001.auto_relevel", "relevel by itself when the car at rest sinks out of the level zone",
      config::kind_section<config::Sch001Config>, &Sch001Config::auto_relevel));
  return t;
}

}  // namespace

config::KindRules RegistryEntry::config_rules() {
  config::KindRules rules;
  rules.kind = drive::Kind::Sch001;
  rules.keys = sch001_keys();
  rules.check = check_sch001;
  rules.summary = sch001_summary;
  return rules;
}

}  // namespace liftd::sch001
