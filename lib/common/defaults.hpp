// The one set of default values for every setting that both the configuration file and a
// library's own settings struct carry. config::Config (and so the config table in
// docs/config.md) and the structs the sequencers, links and simulators are built from all take
// their defaults from here, so a test that builds a controller directly runs the lift the daemon
// runs. Plain constants: no JSON, no parsing, usable by the real-time code's headers.
#pragma once

#include <cstdint>

namespace liftd::defaults {

// travel.* (DCP travel sequencing)
inline constexpr int kLevelToleranceMm = 5;          ///< the car counts as level within this
inline constexpr int kRelevelThresholdMm = 15;       ///< drift that starts a relevelling
inline constexpr bool kRelevelElectricStop = false;  ///< DCP 9.2.3.1 (false) or 9.2.3.2 (true)
inline constexpr bool kUseStartParameters = true;    ///< I7 before a DCP4 travel (DCP 5.12.7)
inline constexpr int kFastStartTimeoutMs = 3000;     ///< longest fast start hold (DCP 12)
inline constexpr int kCallStopMs = 1500;             ///< at a served call: the doors' time to open
inline constexpr int kInspectionHoldMs = 500;        ///< hold-to-run repeat time
/// DCP3 by position: B2 goes off this far before the level, the drive's stop from crawl (V0 of
/// 0.05 m/s on a soft stop of about 0.3 s is some 8 mm; the simulated drive's is 7.7 mm).
inline constexpr int kDcp3StopLeadMm = 8;
inline constexpr int kDcp3SpeedCount = 2;    ///< DCP 3.5.3.7: V4 and V3
inline constexpr int kDcp3DecelV4Mm = 2500;  ///< DCP 8.1: SV4
inline constexpr int kDcp3DecelV3Mm = 1200;  ///< DCP 8.1: SV3

// inputs.*
inline constexpr int kInputsTimeoutMs = 500;  ///< older machine inputs count as lost

// The motor run-time limiter of a travel (the hydraulic unit's sch001.max_travel_ms; the USS
// lift's own): a travel still running after it ends as a fault.
inline constexpr int kMaxTravelMs = 45000;  ///< run-time limiter

// Each drive kind's own defaults are in its folder: lib/<kind>/defaults.hpp.

}  // namespace liftd::defaults
