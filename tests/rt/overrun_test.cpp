// The cycle's decisions on late wake-ups (send, send late, skip) and the journal lines made of
// skip runs, from made-up lateness values and event times: no real clock involved.
#include <gtest/gtest.h>

#include <chrono>
#include <optional>
#include <stdexcept>
#include <vector>

#include "echo_engine.hpp"
#include "rt/cycle_runner.hpp"
#include "rt/overrun_journal.hpp"

namespace liftd::rt {
namespace {

using std::chrono::microseconds;
using std::chrono::milliseconds;
using std::chrono::nanoseconds;
using std::chrono::seconds;

constexpr nanoseconds kPeriod = milliseconds(15);  // DCP 7.2
constexpr nanoseconds kWindow = microseconds(1375);

TEST(RtWakeDecision, SpecSlackIsPeriodMinusReplyDeadline) {
  // DCP 7.2: 15 ms - 13.625 ms.
  EXPECT_EQ(max_send_window(milliseconds(15), microseconds(13625)), microseconds(1375));
  EXPECT_EQ(max_send_window(milliseconds(10), milliseconds(12)), nanoseconds(0));
  EXPECT_EQ(CycleConfig{}.send_window, microseconds(1375));
  EXPECT_EQ(kOnTimeBudget, microseconds(500));
}

TEST(RtWakeDecision, SendOnTimeSendLateOrSkipByLateness) {
  struct Case {
    nanoseconds lateness;
    bool send;
    bool late;
    std::uint64_t skipped;
  };
  const Case cases[] = {
      {nanoseconds(-3000), true, false, 0},   // early (clock granularity)
      {microseconds(0), true, false, 0},      //
      {microseconds(500), true, false, 0},    // the on-time budget itself
      {microseconds(501), true, true, 0},     // late send
      {microseconds(1375), true, true, 0},    // the last moment the spec allows
      {microseconds(1376), false, false, 1},  // beyond the slack: skip this one
      {microseconds(14999), false, false, 1},
      {milliseconds(15), false, false, 2},  // the next period began as well
      {milliseconds(37), false, false, 3},
  };
  for (const Case& c : cases) {
    const WakeDecision d = decide_wake(c.lateness, kWindow, kPeriod);
    EXPECT_EQ(d.send, c.send) << c.lateness.count();
    EXPECT_EQ(d.late, c.late) << c.lateness.count();
    EXPECT_EQ(d.skipped, c.skipped) << c.lateness.count();
  }
}

TEST(RtWakeDecision, ASmallerWindowSkipsSooner) {
  const WakeDecision d = decide_wake(microseconds(600), microseconds(500), kPeriod);
  EXPECT_FALSE(d.send);
  EXPECT_EQ(d.skipped, 1U);
}

TEST(RtWakeDecision, RunnerRefusesAWindowBeyondTheSpecSlack) {
  testing::EchoEngine engine;
  CycleConfig c;
  c.send_window = microseconds(1376);
  try {
    CycleRunner runner(c, engine);
    FAIL() << "accepted a 1376 us window";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(),
                 "cycle send window 1376 us is out of range: allowed 0..1375 us (period minus "
                 "reply deadline, DCP 7.2)");
  }
  c.send_window = microseconds(1375);
  EXPECT_NO_THROW(CycleRunner(c, engine));
  c.send_window = nanoseconds(-1);
  EXPECT_THROW(CycleRunner(c, engine), std::invalid_argument);
}

CycleEvent start(MonoTime at, std::uint64_t count, nanoseconds late) {
  CycleEvent e;
  e.kind = CycleEventKind::SkipRunStarted;
  e.time = at;
  e.count = count;
  e.lateness = late;
  return e;
}

CycleEvent end(MonoTime at, std::uint64_t count, nanoseconds worst) {
  CycleEvent e;
  e.kind = CycleEventKind::SkipRunEnded;
  e.time = at;
  e.count = count;
  e.lateness = worst;
  return e;
}

const MonoTime t0 = MonoTime(seconds(1000));

TEST(RtOverrunJournal, ASingleSkipIsInfoWithStartAndSummary) {
  OverrunJournal j(kPeriod);
  const auto a = j.on_event(start(t0, 1, microseconds(2100)));
  ASSERT_TRUE(a);
  EXPECT_FALSE(a->warn);
  EXPECT_EQ(a->event, "overrun_started");
  EXPECT_EQ(a->text,
            "cycle overrun: woke 2100 us late, beyond the send window; 1 cycle(s) skipped");
  const auto b = j.on_event(end(t0 + kPeriod, 1, microseconds(2100)));
  ASSERT_TRUE(b);
  EXPECT_FALSE(b->warn);
  EXPECT_EQ(b->event, "overrun_ended");
  EXPECT_EQ(b->text,
            "cycle overrun ended: 1 cycle(s) skipped in the run, worst wake-up 2100 us late");
}

TEST(RtOverrunJournal, ThreeInARowWarns) {
  OverrunJournal j(kPeriod);
  // Starts as one skip (INFO), grows to three before a cycle is sent: the summary warns.
  ASSERT_FALSE(j.on_event(start(t0, 1, microseconds(2000)))->warn);
  const auto b = j.on_event(end(t0 + 3 * kPeriod, 3, milliseconds(4)));
  ASSERT_TRUE(b);
  EXPECT_TRUE(b->warn);
  // A run that starts with three skipped periods at once warns at its start.
  const auto c = j.on_event(start(t0 + seconds(100), 3, milliseconds(37)));
  ASSERT_TRUE(c);
  EXPECT_TRUE(c->warn);
}

TEST(RtOverrunJournal, InfoAtMostOnceAMinuteAndTheNextLineCountsWhatWasLeftOut) {
  OverrunJournal j(kPeriod);
  // One single skip every 20 s: far below 1 % (1 of 667 cycles in 10 s), never in a row.
  std::vector<bool> logged;
  for (int i = 0; i < 7; ++i) {
    const MonoTime at = t0 + seconds(20 * i);
    const auto s = j.on_event(start(at, 1, microseconds(1500)));
    const auto e = j.on_event(end(at + kPeriod, 1, microseconds(1500)));
    logged.push_back(s.has_value());
    EXPECT_EQ(s.has_value(), e.has_value()) << i;  // a summary only for a logged start
    if (s) {
      EXPECT_FALSE(s->warn);
    }
    if (i == 3) {
      ASSERT_TRUE(s);
      EXPECT_EQ(s->text,
                "cycle overrun: woke 1500 us late, beyond the send window; 1 cycle(s) skipped "
                "(2 earlier run(s) with 2 skipped cycle(s) not logged)");
    }
  }
  EXPECT_EQ(logged, (std::vector<bool>{true, false, false, true, false, false, true}));
}

TEST(RtOverrunJournal, OnePercentOverTenSecondsWarns) {
  OverrunJournal j(kPeriod);
  // 10 s = 666.7 cycles; 1 % is 6.67 skipped cycles: the seventh single skip within 10 s warns.
  for (int i = 0; i < 7; ++i) {
    const MonoTime at = t0 + seconds(i);
    const auto s = j.on_event(start(at, 1, microseconds(1500)));
    const auto e = j.on_event(end(at + kPeriod, 1, microseconds(1500)));
    if (i == 0) {
      ASSERT_TRUE(s);
      EXPECT_FALSE(s->warn);
    } else if (i < 6) {
      EXPECT_FALSE(s) << i;
      EXPECT_FALSE(e) << i;
    } else {
      ASSERT_TRUE(s);
      EXPECT_TRUE(s->warn);
      ASSERT_TRUE(e);
      EXPECT_TRUE(e->warn);
      EXPECT_EQ(e->text,
                "cycle overrun ended: 1 cycle(s) skipped in the run, worst wake-up 1500 us "
                "late; 7 cycle(s) skipped in the last 10 s");
    }
  }
  // Ten seconds later the window has forgotten them; the minute is not over: nothing.
  EXPECT_DOUBLE_EQ(j.skip_rate(t0 + seconds(20)), 0.0);
  EXPECT_FALSE(j.on_event(start(t0 + seconds(20), 1, microseconds(1500))));
}

TEST(RtOverrunJournal, ASummaryWithoutItsStartIsStillJudged) {
  OverrunJournal j(kPeriod);
  const auto e = j.on_event(end(t0, 4, milliseconds(50)));
  ASSERT_TRUE(e);
  EXPECT_TRUE(e->warn);
  EXPECT_FALSE(j.on_event(CycleEvent{}));  // other kinds are not its business
}

}  // namespace
}  // namespace liftd::rt
