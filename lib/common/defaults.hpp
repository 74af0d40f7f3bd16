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

// dcp.* (the DCP link)
inline constexpr bool kExtendedPosition = true;  ///< ask for the extended I9 (DCP 5.12.3)
inline constexpr int kLinkFaultFrames = 10;      ///< DCP 7.3: bad replies that make a link fault
inline constexpr int kLinkRecoverFrames = 10;    ///< DCP 7.3: good replies that end it
inline constexpr int kRequestTimeoutMs = 2000;   ///< wait for an I-message reply

// inputs.*
inline constexpr int kInputsTimeoutMs = 500;  ///< older machine inputs count as lost

// sch001.* (the hydraulic unit behind the SCH001 card)
inline constexpr int kStarDeltaMs = 1500;    ///< motor on until all motors run (SFY)
inline constexpr int kSlowdownUpMm = 500;    ///< fast speed up ends this far below the level
inline constexpr int kSlowdownDownMm = 700;  ///< fast speed down ends this far above it
inline constexpr int kSlowdownV3Mm = 1000;   ///< V3 up ends this far below the level
inline constexpr int kSlowdownV4Mm = 1500;   ///< V4 up ends this far below the level
inline constexpr int kStopToleranceMm = 3;   ///< the slow approach stops within this
inline constexpr int kRelevelStartMm = 10;   ///< hydraulic relevelling starts this far off
inline constexpr int kMaxTravelMs = 45000;   ///< motor run-time limiter
inline constexpr bool kHydraulicAutoRelevel = true;  ///< relevel a sinking car by itself

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
