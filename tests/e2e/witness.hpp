// The machine-stall witness of an e2e test binary: a reference link (tests/support/
// reference_link.hpp) at the daemons' cycle priority, in the test process, beside the daemons.
// When a daemon's travel ends on a fault that a stalled machine causes (replies held up past
// their deadline, frames that do not reach the drive), the test asks the witness whether it saw
// the same stall at the same time; only then is the fault the machine's.
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <string>

#include "common/mono_time.hpp"
#include "support/reference_link.hpp"
#include "support/stall_judge.hpp"

namespace liftd::e2e {

using liftd::testing::kDriveStallRun;

/// Started on first use (SCHED_FIFO 80 where permitted), stopped at exit.
inline liftd::testing::ReferenceLink& machine_witness() {
  static liftd::testing::ReferenceLink link;
  static const int started = link.start(80, false);
  (void)started;
  return link;
}

/// Everything the witness missed or skipped so far.
inline std::uint64_t witness_misses() {
  return machine_witness().missing() + machine_witness().skipped();
}

/// Runs `body` (a whole scenario: it starts its own daemon) and reports its failures, unless
/// they came while the witness saw a stall long enough for a drive to stop the car on its own
/// (kDriveStallRun periods in a row): then that try is not judged and runs again
/// (tests/support/stall_judge.hpp).
template <class Body>
void judged_unless_stalled(Body body) {
  (void)machine_witness();  // watching from the first try's start
  liftd::testing::judged_unless_machine_stalled([&](liftd::testing::StallVerdict& verdict) {
    const MonoTime from = mono_now();
    const liftd::testing::StallWitnessScope witness(verdict, [from] {
      const std::uint64_t run = machine_witness().longest_miss_run_during(from, mono_now());
      return liftd::testing::StallVerdict{
          run >= kDriveStallRun,
          run > 0 ? "the witness missed at most " + std::to_string(run) + " periods in a row"
                  : std::string()};
    });
    body();
  });
}

}  // namespace liftd::e2e
