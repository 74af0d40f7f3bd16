// A USS bus for a benchmark of another kind to run beside its own real-time thread (api-load-bench
// of tools/bench/dcp measures it against the DCP cycle under API load): uss::UssRunner and
// uss::Master at 38400 baud against three simulated slaves on a pty, as uss-bench runs them. This
// header names no USS type, so that the other kind's benchmark includes no lib/uss header (the
// layer check, tests/layering/check_layers.sh): a run reads the bus in the neutral types below.
#pragma once

#include <cstdint>
#include <memory>

#include "rt/histogram.hpp"

namespace liftd::bench {

/// The bus thread's counters a benchmark reads (those of uss::UssRunnerCounters).
struct UssBusCounters {
  std::uint64_t exchanges = 0;       ///< telegrams sent and finished (with or without reply)
  std::uint64_t reply_timeouts = 0;  ///< no reply by the master's deadline (A 5.2.1.1)
  std::uint64_t bad_replies = 0;     ///< replies the master rejected
};

/// A copy of the bus thread's statistics, taken on any thread.
struct UssBusStats {
  UssBusCounters counters;
  /// Wake-up minus send time of each sleep until a telegram is due, 1 us bins up to 20 ms
  /// (uss::UssRunnerStats::wake_lateness).
  rt::HistogramData wake_lateness;
};

/// A USS bus at 38400 baud (A 6.1) with three simulated slaves answering 1 ms after our BCC
/// (A 5.2.1.1): the bus thread at the priority given, the pty line thread one below.
class UssBus {
 public:
  static constexpr std::uint32_t kBaud = 38400;

  /// The bus thread at `priority`, its memory locked if `lock_memory`, on `cpu` (-1: any); the
  /// line thread one priority below on the same CPU. Throws std::runtime_error when the pty
  /// cannot be made.
  UssBus(int priority, bool lock_memory, int cpu);
  UssBus(const UssBus&) = delete;
  UssBus& operator=(const UssBus&) = delete;
  /// Stops both threads.
  ~UssBus();

  /// Starts the line thread, then the bus thread: 0, or the errno of the thread that did not
  /// start.
  int start();
  void stop();
  UssBusStats stats() const;

 private:
  struct Parts;  // the USS master, runner, simulated slaves and line (uss_bus.cpp)
  std::unique_ptr<Parts> parts_;
};

}  // namespace liftd::bench
