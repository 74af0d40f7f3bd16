// Turns the cycle's skip-run events into journal lines that are news, not noise: one line when
// a run of skipped cycles begins and a summary when it ends, at WARN only when skips come often
// enough to threaten the drive's link supervision, otherwise at INFO at most once a minute.
// Runs on the io thread (never on the cycle thread); the clock is the events' own time, so
// tests drive it with made-up events.
#pragma once

#include <chrono>
#include <cstdint>
#include <deque>
#include <optional>
#include <string>
#include <utility>

#include "common/mono_time.hpp"
#include "rt/cycle_runner.hpp"

namespace liftd::rt {

/// One line to write to the journal.
struct OverrunLine {
  bool warn = false;  ///< WARN (threatens the link supervision) or INFO
  std::string event;  ///< journal event name: "overrun_started" or "overrun_ended"
  std::string text;   ///< the message
};

class OverrunJournal {
 public:
  /// DCP 7.3: the drive ends a travel after 10 bad or missing frames; three skipped cycles in a
  /// row already use up a third of that.
  static constexpr std::uint64_t kWarnRun = 3;
  /// Skips over the last kRateWindow at or above this share of cycles (1 %) warn as well.
  static constexpr double kWarnRate = 0.01;
  static constexpr std::chrono::seconds kRateWindow{10};
  /// INFO lines (runs below the WARN rule) at most this often.
  static constexpr std::chrono::seconds kInfoInterval{60};

  /// `period` is the cycle period (DCP 7.2: 15 ms), for the skip rate.
  explicit OverrunJournal(std::chrono::nanoseconds period) : period_(period) {}

  /// Feeds a SkipRunStarted or SkipRunEnded event; returns the line to write, if any. Other
  /// events return nothing.
  std::optional<OverrunLine> on_event(const CycleEvent& event);

  /// Share of cycles skipped over the kRateWindow before `now` (0..1).
  double skip_rate(MonoTime now);

 private:
  void add_skips(MonoTime at, std::uint64_t count);

  std::chrono::nanoseconds period_;
  std::deque<std::pair<MonoTime, std::uint64_t>> recent_;  // (time, skipped) in the window
  std::uint64_t recent_total_ = 0;
  bool in_run_ = false;
  std::uint64_t run_counted_ = 0;  // skips of the current run already in recent_
  bool run_logged_ = false;        // the current run's start line was written
  bool info_written_ = false;
  MonoTime last_info_{};
  std::uint64_t quiet_runs_ = 0;     // runs not logged since the last INFO line
  std::uint64_t quiet_skipped_ = 0;  // their skipped cycles
};

}  // namespace liftd::rt
