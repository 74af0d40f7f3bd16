// The machine-stall witness of an e2e test binary: a reference link (tests/support/
// reference_link.hpp) at the daemons' cycle priority, in the test process, beside the daemons.
// When a daemon's travel ends on a fault that a stalled machine causes (replies held up past
// their deadline, frames that do not reach the drive), the test asks the witness whether it saw
// the same stall at the same time; only then is the fault the machine's.
#pragma once

#include <cstdint>

#include "common/mono_time.hpp"
#include "support/reference_link.hpp"

namespace liftd::e2e {

/// Periods in a row without a good exchange that witness a stall long enough for a drive to stop
/// the car on its own supervision (DCP 7.3: ten frames; the witness, at another phase and one
/// pty hop shorter than the drive's link, may see two fewer).
inline constexpr std::uint64_t kDriveStallRun = 8;

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

}  // namespace liftd::e2e
