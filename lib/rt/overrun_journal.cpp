#include "rt/overrun_journal.hpp"

#include <algorithm>

namespace liftd::rt {
void OverrunJournal::add_skips(MonoTime at, std::uint64_t count) {
  if (count == 0) return;
  recent_.emplace_back(at, count);
  recent_total_ += count;
}

double OverrunJournal::skip_rate(MonoTime now) {
  while (!recent_.empty() && now - recent_.front().first > kRateWindow) {
    recent_total_ -= recent_.front().second;
    recent_.pop_front();
  }
  const auto period = std::max<std::int64_t>(period_.count(), 1);
  const double cycles = static_cast<double>(std::chrono::nanoseconds(kRateWindow).count()) /
                        static_cast<double>(period);
  return static_cast<double>(recent_total_) / cycles;
}

std::optional<OverrunLine> OverrunJournal::on_event(const CycleEvent& event) {
  if (event.kind == CycleEventKind::SkipRunStarted) {
    in_run_ = true;
    run_counted_ = event.count;
    add_skips(event.time, event.count);
    const double rate = skip_rate(event.time);
    const bool warn = event.count >= kWarnRun || rate >= kWarnRate;
    const bool info_due = !info_written_ || event.time - last_info_ >= kInfoInterval;
    if (!warn && !info_due) {
      run_logged_ = false;
      ++quiet_runs_;
      quiet_skipped_ += event.count;
      return std::nullopt;
    }
    run_logged_ = true;
    OverrunLine line;
    line.warn = warn;
    line.event = "overrun_started";
    line.text = describe(event);
    if (quiet_runs_ > 0) {
      line.text += " (" + std::to_string(quiet_runs_) + " earlier run(s) with " +
                   std::to_string(quiet_skipped_) + " skipped cycle(s) not logged)";
    }
    if (!warn) {
      info_written_ = true;
      last_info_ = event.time;
    }
    quiet_runs_ = 0;
    quiet_skipped_ = 0;
    return line;
  }
  if (event.kind == CycleEventKind::SkipRunEnded) {
    // A summary whose start never arrived (the cycle's queue was full) is a run of its own.
    if (!in_run_) {
      run_counted_ = 0;
      run_logged_ = false;
    }
    in_run_ = false;
    if (event.count > run_counted_) add_skips(event.time, event.count - run_counted_);
    const std::uint64_t run_extra = event.count > run_counted_ ? event.count - run_counted_ : 0;
    run_counted_ = 0;
    const double rate = skip_rate(event.time);
    const bool warn = event.count >= kWarnRun || rate >= kWarnRate;
    if (!warn && !run_logged_) {
      quiet_skipped_ += run_extra;
      return std::nullopt;
    }
    OverrunLine line;
    line.warn = warn;
    line.event = "overrun_ended";
    line.text = describe(event);
    if (rate >= kWarnRate) {
      line.text += "; " + std::to_string(recent_total_) + " cycle(s) skipped in the last " +
                   std::to_string(kRateWindow.count()) + " s";
    }
    return line;
  }
  return std::nullopt;
}

}  // namespace liftd::rt
