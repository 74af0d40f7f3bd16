// The USS lift's defaults: the defaults of its configuration section and of the library structs
// that carry the same settings (the rule of lib/common/defaults.hpp, which holds the shared ones),
// so a test that builds the controller directly runs the lift a default configuration gives the
// daemon.
#pragma once

namespace liftd::defaults {

// USS drive (drive.kind "uss"): the uss.* keys and lib/uss.
inline constexpr int kUssBaud = 38400;  ///< USS B 2.4: one of the recommended rates
/// USS A 5.2.1.1: the master waits at most 20 ms for the start of a reply.
inline constexpr int kUssReplyDelayMs = 20;
inline constexpr int kUssTelegramFailures = 3;  ///< failed telegrams of the drive that end a travel
// Main setpoints in percent of the drive's full scale (USS C 5.2.2), by DCP speed name.
inline constexpr double kUssSpeedV0Percent = 5.0;     ///< crawl
inline constexpr double kUssSpeedVnPercent = 3.0;     ///< relevelling
inline constexpr double kUssSpeedViPercent = 30.0;    ///< inspection
inline constexpr double kUssSpeedV3Percent = 60.0;    ///< intermediate speed
inline constexpr double kUssSpeedV4Percent = 100.0;   ///< fast speed
inline constexpr int kUssContactorMs = 100;           ///< contactors closed before ON
inline constexpr int kUssBrakeReleaseMs = 300;        ///< brake lifting time before the setpoint
inline constexpr int kUssBrakeApplyMs = 300;          ///< brake falling time before OFF1
inline constexpr double kUssStandstillPercent = 0.5;  ///< |actual value| at or below: standstill
inline constexpr int kUssStandstillTimeoutMs = 5000;  ///< setpoint 0 to standstill
inline constexpr int kUssCrawlTimeoutMs = 30000;      ///< longest crawl before a quick stop
inline constexpr int kUssPkwRepeatLimit = 10;    ///< polls a PKW request is repeated unanswered
inline constexpr int kUssFullScaleRaw = 0x4000;  ///< USS C 5.2.2: 0x4000 = 100 %
inline constexpr int kUssFullScale = 100;        ///< what kUssFullScaleRaw stands for (percent)
/// The drive reaches a state the profile asks for within this (USS C 5.2.1), or it is a fault.
inline constexpr int kUssProfileTimeoutMs = 2000;

}  // namespace liftd::defaults
