// The hydraulic lift's section of the configuration file (`sch001.*`): the SCH001 card.
// Its keys, checks and summary are in config_rules.cpp; the loader holds it in
// config::Config::kinds (lib/config/config.hpp), read with sch001_section().
#pragma once

#include <cstdint>

#include "common/defaults.hpp"
#include "config/config.hpp"
#include "drive/drive.hpp"
#include "sch001/defaults.hpp"

namespace liftd::config {

/// Which signal is the SCH001 unit's fast speed down (card parameters P435 / P453).
enum class FastDown : std::uint8_t { hsp, sp3 };

/// `sch001.*`: the SCH001 card and the hydraulic unit behind it.
struct Sch001Config {
  static constexpr drive::Kind kKind = drive::Kind::Sch001;  ///< the kind it belongs to

  int base = 0;                        ///< sch001.base: card parameter P479 (0 = 0x550)
  int controller_node = 49;            ///< sch001.controller_node: card parameter P480
  bool single_unit = true;             ///< sch001.single_unit: one power unit (AVV, PNP2 valid)
  FastDown fast_down = FastDown::hsp;  ///< sch001.fast_down
  bool has_v3 = false;                 ///< sch001.has_v3
  bool has_v4 = false;                 ///< sch001.has_v4
  int star_delta_ms = defaults::kStarDeltaMs;           ///< sch001.star_delta_ms
  int slowdown_up_mm = defaults::kSlowdownUpMm;         ///< sch001.slowdown_up_mm
  int slowdown_down_mm = defaults::kSlowdownDownMm;     ///< sch001.slowdown_down_mm
  int slowdown_v3_mm = defaults::kSlowdownV3Mm;         ///< sch001.slowdown_v3_mm
  int slowdown_v4_mm = defaults::kSlowdownV4Mm;         ///< sch001.slowdown_v4_mm
  int stop_tolerance_mm = defaults::kStopToleranceMm;   ///< sch001.stop_tolerance_mm
  int relevel_start_mm = defaults::kRelevelStartMm;     ///< sch001.relevel_start_mm
  int max_travel_ms = defaults::kMaxTravelMs;           ///< sch001.max_travel_ms
  bool auto_relevel = defaults::kHydraulicAutoRelevel;  ///< sch001.auto_relevel
};

/// The `sch001.*` section of `config` (its defaults until the file sets a key).
inline const Sch001Config& sch001_section(const Config& config) {
  return config.kinds.get<Sch001Config>();
}
/// The `sch001.*` section of `config`, to change.
inline Sch001Config& sch001_section(Config& config) {
  return config.kinds.get<Sch001Config>();
}

}  // namespace liftd::config
