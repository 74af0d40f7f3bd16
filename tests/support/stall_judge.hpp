// Judging a real-time test on a shared machine: a try whose failures came while a witness saw
// the machine stall (a reference link at the cycle's priority missing exchanges, or the cycle's
// own records far apart) cannot say anything about the code, so it is run again; a failure of
// the code comes back on a try without a stall and is reported. When the machine stalled in
// every try (a machine loaded on purpose: tools/test.sh --under-load), the test is skipped with
// every failure printed: no try could judge the code.
#pragma once

#include <gtest/gtest-spi.h>
#include <gtest/gtest.h>

#include <cstdio>
#include <functional>
#include <string>
#include <utility>

namespace liftd::testing {

/// What a try's witness saw: `stalled` when the machine held the test's real-time threads up
/// long enough to explain a fault, `what` for the report.
struct StallVerdict {
  bool stalled = false;
  std::string what;
};

/// Fills `verdict` from `witness` when it goes out of scope, so that a try an ASSERT ended
/// early is judged too. Declare it after the objects the witness reads.
class StallWitnessScope {
 public:
  StallWitnessScope(StallVerdict& verdict, std::function<StallVerdict()> witness)
      : verdict_(verdict), witness_(std::move(witness)) {}
  ~StallWitnessScope() { verdict_ = witness_(); }
  StallWitnessScope(const StallWitnessScope&) = delete;
  StallWitnessScope& operator=(const StallWitnessScope&) = delete;

 private:
  StallVerdict& verdict_;
  std::function<StallVerdict()> witness_;
};

/// Runs `body(StallVerdict&)` (a whole scenario with its own rig) up to three times: a try
/// that failed while its verdict says the machine stalled is printed as a note and not judged.
template <class Body>
void judged_unless_machine_stalled(Body body) {
  constexpr int kTries = 3;
  for (int attempt = 1;; ++attempt) {
    ::testing::TestPartResultArray results;
    StallVerdict verdict;
    {
      const ::testing::ScopedFakeTestPartResultReporter intercept(
          ::testing::ScopedFakeTestPartResultReporter::INTERCEPT_ONLY_CURRENT_THREAD, &results);
      body(verdict);
    }
    bool failed = false;
    for (int i = 0; i < results.size(); ++i) {
      failed = failed || results.GetTestPartResult(i).failed();
    }
    if (failed && verdict.stalled) {
      std::printf("[ stalled  ] try %d: %s; not judged:\n", attempt, verdict.what.c_str());
      for (int i = 0; i < results.size(); ++i) {
        const auto& r = results.GetTestPartResult(i);
        if (r.failed()) {
          std::printf("%s:%d: %s\n", r.file_name() ? r.file_name() : "?", r.line_number(),
                      r.message());
        }
      }
      if (attempt < kTries) continue;
      GTEST_SKIP() << "the machine stalled in each of " << kTries
                   << " tries: not judged (the failures are printed above)";
    }
    for (int i = 0; i < results.size(); ++i) {
      const auto& r = results.GetTestPartResult(i);
      if (r.failed()) {
        // The message as it was reported (ADD_FAILURE_AT would add a "Failed" line).
        const std::string message =
            std::string(r.message()) +
            (verdict.what.empty() ? std::string() : "\n(" + verdict.what + ")");
        GTEST_MESSAGE_AT_(r.file_name() ? r.file_name() : "?", r.line_number(), message.c_str(),
                          ::testing::TestPartResult::kNonFatalFailure);
      } else if (r.skipped()) {
        GTEST_SKIP() << r.message();
      }
    }
    return;
  }
}

}  // namespace liftd::testing
