#include "uss/registry_entry.hpp"

#include <algorithm>
#include <array>
#include <sstream>

#include "config/schema.hpp"
#include "uss/config/section.hpp"
#include "uss/telegram.hpp"

namespace liftd::uss {
namespace {

using config::check_integer;
using config::Config;
using config::did_you_mean;
using config::enum_from;
using config::enum_name;
using config::is_integer;
using config::Key;
using config::PositionSource;
using config::Problems;
using config::show;
using config::UssConfig;
using config::UssPkw;
using config::UssSlave;
using nlohmann::json;

// USS C 4.1: a PKW area of 0, 3 or 4 words, or of variable length (PKW = 127 in the drive).
constexpr std::array<std::string_view, 4> kUssPkwNames{"0", "3", "4", "variable"};
// USS B 2.4: the rates a USS interface offers.
constexpr std::array<int, 13> kUssBauds{300,   600,   1200,  2400,  4800,   9600,  19200,
                                        38400, 57600, 76800, 93750, 115200, 187500};
// USS A 4.3: ADR bits 0..4.
constexpr int kMaxAddress = kMaxSlaveAddress;
// USS C 2, C 5.1: at most 16 PZD words.
constexpr int kMaxPzd = static_cast<int>(kMaxPzdWords);
// USS A 4.3: 32 addresses on a bus, the drive one of them.
constexpr std::size_t kBusAddresses = kMaxSlaveAddress + 1U;
constexpr std::size_t kMaxUssSlaves = kBusAddresses - 1;
// A polling list may repeat addresses (USS A 2.1); 64 entries cover any sensible weighting.
constexpr std::size_t kMaxPollingList = 64;

void apply_uss_baud(const json& value, const std::string& where, Config& cfg, Problems& problems) {
  std::string allowed;
  for (int baud : kUssBauds) allowed += (allowed.empty() ? "" : ", ") + std::to_string(baud);
  if (!is_integer(value) ||
      std::find(kUssBauds.begin(), kUssBauds.end(), value.get<std::int64_t>()) == kUssBauds.end()) {
    problems.push_back(
        {where, show(value) + " is not a USS rate: use one of " + allowed + " (USS B 2.4)"});
    return;
  }
  uss_section(cfg).baud = static_cast<int>(value.get<std::int64_t>());
}

std::optional<UssPkw> uss_pkw_from(const json& value) {
  if (!value.is_string()) return std::nullopt;
  return enum_from<UssPkw>(value.get<std::string>(), kUssPkwNames);
}

void apply_uss_slaves(const json& value, const std::string& where, Config& cfg,
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
    } else if (check_integer(entry["address"], at + ".address", 0, kMaxAddress, problems)) {
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
      if (check_integer(entry["pzd_words"], at + ".pzd_words", 0, kMaxPzd, problems)) {
        slave.pzd_words = static_cast<int>(entry["pzd_words"].get<std::int64_t>());
      } else {
        good = false;
      }
    }
    slaves.push_back(slave);
  }
  if (good) uss_section(cfg).slaves = std::move(slaves);
}

void apply_polling_list(const json& value, const std::string& where, Config& cfg,
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
    if (check_integer(value[i], at, 0, kMaxAddress, problems)) {
      list.push_back(static_cast<int>(value[i].get<std::int64_t>()));
    } else {
      good = false;
    }
  }
  if (good) uss_section(cfg).polling_list = std::move(list);
}

void apply_uss_speeds(const json& value, const std::string& where, Config& cfg,
                      Problems& problems) {
  const std::vector<std::string> names(config::kSpeedNames.begin(), config::kSpeedNames.end());
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
  if (good) uss_section(cfg).speeds = std::move(speeds);
}

// The uss.* keys that must agree with each other (only for a USS lift).
void check_uss(const Config& cfg, const json& /*document*/, Problems& problems) {
  const UssConfig& uss = uss_section(cfg);
  // The CAN encoder needs a CAN runner of its own; the USS lift has none in this version.
  if (cfg.position.source == PositionSource::can) {
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
  for (const auto& name : config::dcp3_speeds(cfg.travel.dcp3_speed_count)) needed.push_back(name);
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

std::string uss_summary(const Config& cfg) {
  std::ostringstream out;
  out << "drive:    uss on " << cfg.drive.device << " at " << uss_section(cfg).baud
      << " baud 8E1 (rs485 " << config::to_string(cfg.drive.rs485) << "), drive address "
      << uss_section(cfg).drive_address << ", PKW "
      << enum_name(uss_section(cfg).drive_pkw, kUssPkwNames) << ", PZD "
      << uss_section(cfg).drive_pzd_words << " words\n";
  out << "uss:      " << uss_section(cfg).slaves.size() << " other slave(s), polling list "
      << (uss_section(cfg).polling_list.empty() ? std::string("drive then each slave")
                                                : json(uss_section(cfg).polling_list).dump())
      << ", reply delay " << uss_section(cfg).reply_delay_ms << " ms\n";
  return out.str();
}

json slaves_json(const Config& cfg) {
  json out = json::array();
  for (const auto& slave : uss_section(cfg).slaves) {
    out.push_back({{"address", slave.address},
                   {"pkw", std::string(enum_name(slave.pkw, kUssPkwNames))},
                   {"pzd_words", slave.pzd_words}});
  }
  return out;
}

std::vector<Key> uss_keys() {
  std::vector<Key> t;
  t.push_back(config::custom_key(
      "uss.baud", "integer",
      "300, 600, 1200, 2400, 4800, 9600, 19200, 38400, 57600, 76800, 93750, 115200, 187500",
      "USS bus rate in baud; 8E1 characters (USS B 2.4, B 3.2)", apply_uss_baud,
      [](const Config& c) { return json(uss_section(c).baud); }));
  t.push_back(config::int_key("uss.drive_address", 0, kMaxAddress,
                              "USS address of the lift drive (ADR bits 0..4, USS A 4.3)",
                              config::kind_section<config::UssConfig>, &UssConfig::drive_address));
  t.push_back(config::enum_key("uss.drive_pkw", kUssPkwNames,
                               "the drive's PKW area: none, 3 or 4 words, or variable (USS C 4.1); "
                               "set the drive's own PKW parameter alike",
                               config::kind_section<config::UssConfig>, &UssConfig::drive_pkw));
  t.push_back(config::int_key("uss.drive_pzd_words", 2, kMaxPzd,
                              "PZD words of the drive (USS C 5.1): STW/ZSW and HSW/HIW at least",
                              config::kind_section<config::UssConfig>,
                              &UssConfig::drive_pzd_words));
  t.push_back(config::custom_key(
      "uss.slaves", "array of {address, pkw, pzd_words}",
      "at most 31 slaves besides the drive, addresses 0..31 unique, pkw \"0\" \"3\" \"4\" "
      "\"variable\" (default \"4\"), pzd_words 0..16 (default 2)",
      "other USS slaves on the bus (e.g. a door operator), polled for their parameters and "
      "process data",
      apply_uss_slaves, slaves_json));
  t.push_back(config::custom_key(
      "uss.polling_list", "array of integers",
      "at most 64 addresses of the drive and uss.slaves, any order, repeats allowed, the drive "
      "at least once; [] = the drive, then each slave",
      "the order in which the master polls the slaves (USS A 2.1)", apply_polling_list,
      [](const Config& c) { return json(uss_section(c).polling_list); }));
  t.push_back(config::int_key("uss.reply_delay_ms", 1, 20,
                              "longest wait for the start of a reply; never below the start pause "
                              "(USS A 5.2.1.1: at most 20 ms)",
                              config::kind_section<config::UssConfig>, &UssConfig::reply_delay_ms));
  t.push_back(config::int_key("uss.cycle_time_ms", 0, 6500,
                              "fixed time of one pass through the polling list; 0 = as fast as the "
                              "bus allows (USS A 5.1.1)",
                              config::kind_section<config::UssConfig>, &UssConfig::cycle_time_ms));
  t.push_back(
      config::int_key("uss.telegram_failures", 1, 100,
                      "consecutive failed telegrams of the drive that end a travel (like a DCP "
                      "link fault)",
                      config::kind_section<config::UssConfig>, &UssConfig::telegram_failures));
  t.push_back(config::int_key("uss.pkw_repeat_limit", 1, 1000,
                              "polls a parameter request is repeated without its reply before it "
                              "fails (USS C 4)",
                              config::kind_section<config::UssConfig>,
                              &UssConfig::pkw_repeat_limit));
  t.push_back(
      config::bool_key("uss.mirror_at_start",
                       "send each slave a mirror telegram as a link test at start (USS A 5.3)",
                       config::kind_section<config::UssConfig>, &UssConfig::mirror_at_start));
  t.push_back(config::int_key("uss.full_scale_raw", 1, 32767,
                              "main setpoint / actual value word that stands for uss.full_scale "
                              "(USS C 5.2.2: 0x4000 = 16384 = 100 %)",
                              config::kind_section<config::UssConfig>, &UssConfig::full_scale_raw));
  t.push_back(
      config::int_key("uss.full_scale", 1, 100000,
                      "the drive's unit at uss.full_scale_raw (100 for percent, 50 for Hz of a "
                      "50 Hz motor, ...)",
                      config::kind_section<config::UssConfig>, &UssConfig::full_scale));
  t.push_back(
      config::int_key("uss.profile_timeout_ms", 100, 30000,
                      "the drive reaches the state asked for in its status word within this, "
                      "or it is a drive fault (USS C 5.2.1)",
                      config::kind_section<config::UssConfig>, &UssConfig::profile_timeout_ms));
  t.push_back(config::custom_key(
      "uss.speeds", "object: speed -> setpoint",
      "V0 (crawl), VN (relevelling), VI (inspection) and every travelling speed of "
      "travel.dcp3_speed_count, each > 0 in uss.full_scale units and within a signed word once "
      "scaled",
      "main setpoint (HSW) of each speed, in the drive's unit", apply_uss_speeds,
      [](const Config& c) { return json(uss_section(c).speeds); }));
  return t;
}

}  // namespace

config::KindRules RegistryEntry::config_rules() {
  config::KindRules rules;
  rules.kind = drive::Kind::Uss;
  rules.keys = uss_keys();
  rules.check = check_uss;
  rules.summary = uss_summary;
  return rules;
}

}  // namespace liftd::uss
