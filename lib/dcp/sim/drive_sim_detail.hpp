// What the parts of DriveSim (drive_sim.cpp, drive_sim_travel.cpp, drive_sim_channel.cpp) share:
// the DCP timings and limits the simulated drive keeps and small index helpers. Included only
// by those files.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>

#include "common/mono_time.hpp"
#include "dcp/frame.hpp"
#include "dcp/sim/drive_sim.hpp"

namespace liftd::dcp::sim::detail {

using namespace std::chrono_literals;
namespace cb = dcp::command_bit;
namespace sb = dcp::status_bit;

inline constexpr MonoTime kCycle = 15ms;           // DCP 7.2: one transfer cycle
inline constexpr double kLevellingSpeedMps = 0.3;  // DCP 4.1 S4: v < 0.3 m/s
inline constexpr double kUnlockingSpeedMps = 0.8;  // DCP 4.2.1.1 bit 0: v < 0.8 m/s
inline constexpr double kCrawlMarginM = 0.05;      // derived DCP3 distances: 50 mm of crawl
inline constexpr std::uint16_t kMax15 = 0x7FFF;    // DCP 3.5.3.4: 15-bit remaining distance
inline constexpr std::uint16_t kMax16 = 0xFFFF;    // DCP 3.5.3.4: 16-bit remaining distance
inline constexpr double kStillMps = 1e-6;          // below this the car counts as stationary
// DCP 7.2: two 15 ms cycles of lag between the master's position and the drive's.
inline constexpr std::chrono::duration<double> kPositionLag = 30ms;

inline std::size_t fault_index(ReplyFault f) {
  return static_cast<std::size_t>(f);
}
inline std::size_t cause_index(FaultCause c) {
  return static_cast<std::size_t>(c);
}

}  // namespace liftd::dcp::sim::detail
