// The hydraulic (SCH001) lift's defaults: the defaults of its configuration section and of the
// library structs that carry the same settings (the rule of lib/common/defaults.hpp, which holds
// the shared ones), so a test that builds the controller directly runs the lift a default
// configuration gives the daemon.
#pragma once

namespace liftd::defaults {

// sch001.* (the hydraulic unit behind the SCH001 card)
inline constexpr int kStarDeltaMs = 1500;    ///< motor on until all motors run (SFY)
inline constexpr int kSlowdownUpMm = 500;    ///< fast speed up ends this far below the level
inline constexpr int kSlowdownDownMm = 700;  ///< fast speed down ends this far above it
inline constexpr int kSlowdownV3Mm = 1000;   ///< V3 up ends this far below the level
inline constexpr int kSlowdownV4Mm = 1500;   ///< V4 up ends this far below the level
inline constexpr int kStopToleranceMm = 3;   ///< the slow approach stops within this
inline constexpr int kRelevelStartMm = 10;   ///< hydraulic relevelling starts this far off
inline constexpr bool kHydraulicAutoRelevel = true;  ///< relevel a sinking car by itself

}  // namespace liftd::defaults
