// The USS lift's section of the configuration file (`uss.*`): the USS bus and its drive.
// Its keys, checks and summary are in config_rules.cpp; the loader holds it in
// config::Config::kinds (lib/config/config.hpp), read with uss_section().
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "common/defaults.hpp"
#include "config/config.hpp"
#include "drive/drive.hpp"
#include "uss/defaults.hpp"

namespace liftd::config {

/// Length of a USS slave's PKW area (USS C 4.1): none, 3 or 4 words, or variable.
enum class UssPkw : std::uint8_t { none, three, four, variable };

/// One USS slave besides the drive on the same bus (e.g. a door operator): `uss.slaves[]`.
struct UssSlave {
  int address = 0;            ///< 0..31 (USS A 4.3)
  UssPkw pkw = UssPkw::four;  ///< its PKW area
  int pzd_words = 2;          ///< 0..16 PZD words (USS C 5.1)
  friend bool operator==(const UssSlave&, const UssSlave&) = default;
};

/// `uss.*`: the USS bus and the drive on it.
struct UssConfig {
  static constexpr drive::Kind kKind = drive::Kind::Uss;  ///< the kind it belongs to

  int baud = defaults::kUssBaud;    ///< uss.baud
  int drive_address = 0;            ///< uss.drive_address
  UssPkw drive_pkw = UssPkw::four;  ///< uss.drive_pkw
  int drive_pzd_words = 2;          ///< uss.drive_pzd_words (STW/ZSW, HSW/HIW at least)
  std::vector<UssSlave> slaves;     ///< uss.slaves: other slaves on the bus
  std::vector<int> polling_list;    ///< uss.polling_list; empty: drive, then each slave
  int reply_delay_ms = defaults::kUssReplyDelayMs;          ///< uss.reply_delay_ms
  int cycle_time_ms = 0;                                    ///< uss.cycle_time_ms, 0 = none
  int telegram_failures = defaults::kUssTelegramFailures;   ///< uss.telegram_failures
  int pkw_repeat_limit = defaults::kUssPkwRepeatLimit;      ///< uss.pkw_repeat_limit
  bool mirror_at_start = true;                              ///< uss.mirror_at_start
  int full_scale_raw = defaults::kUssFullScaleRaw;          ///< uss.full_scale_raw
  int full_scale = defaults::kUssFullScale;                 ///< uss.full_scale
  int profile_timeout_ms = defaults::kUssProfileTimeoutMs;  ///< uss.profile_timeout_ms
  /// uss.speeds: speed name -> main setpoint in the drive's unit (uss.full_scale).
  std::map<std::string, double> speeds = {{"V0", defaults::kUssSpeedV0Percent},
                                          {"VN", defaults::kUssSpeedVnPercent},
                                          {"VI", defaults::kUssSpeedViPercent},
                                          {"V3", defaults::kUssSpeedV3Percent},
                                          {"V4", defaults::kUssSpeedV4Percent}};
};

/// The `uss.*` section of `config` (its defaults until the file sets a key).
inline const UssConfig& uss_section(const Config& config) {
  return config.kinds.get<UssConfig>();
}
/// The `uss.*` section of `config`, to change.
inline UssConfig& uss_section(Config& config) {
  return config.kinds.get<UssConfig>();
}

}  // namespace liftd::config
