// The machine-stall witness of an e2e test binary: a reference link (tests/support/
// reference_link.hpp) at the daemons' cycle priority, in the test process, beside the daemons.
// When a daemon's travel ends on a fault that a stalled machine causes (replies held up past
// their deadline, frames that do not reach the drive), the test asks the witness whether it saw
// the same stall at the same time; only then is the fault the machine's.
#pragma once

#include <gtest/gtest-spi.h>
#include <gtest/gtest.h>

#include <cstdint>
#include <cstdio>
#include <string>

#include "common/mono_time.hpp"
#include "support/reference_link.hpp"

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
/// (kDriveStallRun periods in a row): then that try cannot be judged, its failures are printed
/// as notes and the scenario runs again, at most three times in all. A failure of the code
/// comes back on a try without a stall and is reported; the last try is always judged.
template <class Body>
void judged_unless_stalled(Body body) {
  constexpr int kTries = 3;
  (void)machine_witness();  // watching from the first try's start
  for (int attempt = 1;; ++attempt) {
    ::testing::TestPartResultArray results;
    const MonoTime from = mono_now();
    {
      const ::testing::ScopedFakeTestPartResultReporter intercept(
          ::testing::ScopedFakeTestPartResultReporter::INTERCEPT_ONLY_CURRENT_THREAD, &results);
      body();
    }
    const std::uint64_t stall = machine_witness().longest_miss_run_during(from, mono_now());
    bool failed = false;
    for (int i = 0; i < results.size(); ++i) {
      failed = failed || results.GetTestPartResult(i).failed();
    }
    if (failed && stall >= kDriveStallRun && attempt < kTries) {
      std::printf("[ stalled  ] try %d: the witness missed %llu periods in a row; not judged:\n",
                  attempt, static_cast<unsigned long long>(stall));
      for (int i = 0; i < results.size(); ++i) {
        const auto& r = results.GetTestPartResult(i);
        if (r.failed()) {
          std::printf("%s:%d: %s\n", r.file_name() ? r.file_name() : "?", r.line_number(),
                      r.message());
        }
      }
      continue;
    }
    for (int i = 0; i < results.size(); ++i) {
      const auto& r = results.GetTestPartResult(i);
      if (r.failed()) {
        // The message as it was reported (ADD_FAILURE_AT would add a "Failed" line).
        const std::string message =
            std::string(r.message()) + (stall > 0 ? "\n(the witness missed at most " +
                                                        std::to_string(stall) + " periods in a row)"
                                                  : std::string());
        GTEST_MESSAGE_AT_(r.file_name() ? r.file_name() : "?", r.line_number(), message.c_str(),
                          ::testing::TestPartResult::kNonFatalFailure);
      } else if (r.skipped()) {
        GTEST_SKIP() << r.message();
      }
    }
    return;
  }
}

}  // namespace liftd::e2e
