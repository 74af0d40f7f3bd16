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
  LineEcho,        ///< drive.echo auto found out whether the line echoes: `count` 1 yes, 0 no
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

/// An event the non-real-time side must get even if the queue was full when it happened (a port
/// loss behind a burst of skip-run events the reader has not taken yet): held here and offered
/// again at every try. Another event while one is held is added to its `count` (same kind only:
/// the runners hold port losses, nothing else), never dropped. Real-time safe: plain data.
struct HeldEvent {
  CycleEvent event{};
  bool held = false;

  /// Queues `e`, or holds it when the queue is full.
  template <class Queue>
  void push(Queue& queue, const CycleEvent& e) noexcept {
    retry(queue);
    if (held) {
      event.count += e.count;
      event.error_number = e.error_number;
      return;
    }
    if (!queue.try_push(e)) {
      event = e;
      held = true;
    }
  }
  /// Offers the held event again; call it once per cycle.
  template <class Queue>
  void retry(Queue& queue) noexcept {
    if (held && queue.try_push(event)) held = false;
  }
};

/// A readable line for an event (for the log).
std::string describe(const CycleEvent& event);

}  // namespace liftd::rt
