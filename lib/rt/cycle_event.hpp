// The events a real-time runner (the DCP cycle, the USS bus) reports to the non-real-time side:
// its thread's start, its port's opens and losses, skipped cycles. Plain data, so that they
// cross an SPSC queue without allocation.
#pragma once

#include <array>
#include <chrono>
#include <cstdint>
#include <string>

#include "common/mono_time.hpp"

namespace liftd::rt {

/// Kinds of events the cycle reports to the non-real-time side.
enum class CycleEventKind : std::uint8_t {
  ThreadStatus,    ///< real-time wishes refused at start (text in describe())
  PortOpened,      ///< device opened (error_number: RS485/low-latency notes in text)
  PortOpenFailed,  ///< open failed; will retry (text names device, call and errno)
  PortLost,        ///< device lost (error_number = errno)
  SkipRunStarted,  ///< a run of skipped cycles began: `count` skipped, `lateness` of the wake
  SkipRunEnded,    ///< the run ended (a cycle was sent): `count` skipped in all, worst `lateness`
};

/// One event. Plain data so it can cross the SPSC queue without allocation.
struct CycleEvent {
  CycleEventKind kind = CycleEventKind::PortLost;  ///< what happened
  MonoTime time{};                                 ///< when
  int error_number = 0;                            ///< errno where relevant
  std::uint64_t count = 0;                         ///< e.g. skipped cycles
  std::chrono::nanoseconds lateness{0};            ///< skip runs: wake-up lateness
  std::array<char, 240> text{};                    ///< message (filled off the cycle thread)
};

/// A readable line for an event (for the log).
std::string describe(const CycleEvent& event);

}  // namespace liftd::rt
