// When the cycle first looks for a reply (rt/reply_watch.hpp), from made-up reply times: the
// spec's bounds (DCP 7.2), learning a drive's steady delay, the probe that finds a drive got
// quicker, and forgetting on a new port. No clock, no line.
#include "rt/reply_watch.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <cstddef>
#include <vector>

#include "io/serial_port.hpp"
#include "rt/cycle_runner.hpp"

namespace liftd::rt {
namespace {

using std::chrono::microseconds;
using std::chrono::nanoseconds;

// DCP 7.1: 10 bits at 38400 baud. DCP 2: a reply is 6 bytes.
const nanoseconds kChar = io::character_time(io::SerialSettings{});
const nanoseconds kReplyOnLine = kChar * 6;

ReplyWatch dcp_watch() {
  const CycleConfig c;
  return ReplyWatch(c.reply_earliest_start + kReplyOnLine, c.reply_latest_start + kReplyOnLine);
}

TEST(RtReplyWatch, TheSpecBoundsAreDcp72sSendStartsPlusTheReplyOnTheLine) {
  const CycleConfig c;
  EXPECT_EQ(c.reply_earliest_start, nanoseconds(2'062'400));  // DCP 7.2 earliest send start
  EXPECT_EQ(c.reply_latest_start, nanoseconds(11'562'500));   // DCP 7.2 latest send start
  // The earliest complete reply: 2.0624 ms + 6 x 260.4 us = 3.625 ms.
  EXPECT_NEAR(static_cast<double>((c.reply_earliest_start + kReplyOnLine).count()), 3'625'000.0,
              1'000.0);
  // Latest: 13.125 ms, half a millisecond before the deadline (the drive's driver off).
  EXPECT_NEAR(static_cast<double>((c.reply_latest_start + kReplyOnLine).count()), 13'125'000.0,
              1'000.0);
  EXPECT_LT(c.reply_latest_start + kReplyOnLine, c.reply_deadline);
}

TEST(RtReplyWatch, WithNothingLearnedTheFirstLookIsAtTheEarliest) {
  const ReplyWatch w = dcp_watch();
  const CycleConfig c;
  EXPECT_EQ(w.first_look(), c.reply_earliest_start + kReplyOnLine);
}

TEST(RtReplyWatch, FirstLookFollowsTheDrivesRepliesWithinTheSpecBounds) {
  const CycleConfig c;
  const nanoseconds earliest = c.reply_earliest_start + kReplyOnLine;
  const nanoseconds latest = c.reply_latest_start + kReplyOnLine;
  struct WatchCase {
    const char* what;
    std::vector<nanoseconds> seen;  // where the replies were found complete, oldest first
    nanoseconds first_look;
  };
  const WatchCase cases[] = {
      {"one reply", {microseconds(5190)}, microseconds(5190)},
      {"the soonest of those remembered",
       {microseconds(6750), microseconds(5190), microseconds(6750)},
       microseconds(5190)},
      {"never before the spec's earliest", {microseconds(1000)}, earliest},
      {"never after the spec's latest", {microseconds(13600)}, latest},
      // One slow reply moves nothing; 16 in a row (a quarter of a second) do.
      {"one slow reply", {microseconds(4000), microseconds(9000)}, microseconds(4000)},
      {"sixteen slow replies",
       {microseconds(4000), microseconds(9000), microseconds(9000), microseconds(9000),
        microseconds(9000), microseconds(9000), microseconds(9000), microseconds(9000),
        microseconds(9000), microseconds(9000), microseconds(9000), microseconds(9000),
        microseconds(9000), microseconds(9000), microseconds(9000), microseconds(9000),
        microseconds(9000)},
       microseconds(9000)},
  };
  for (const WatchCase& k : cases) {
    ReplyWatch w = dcp_watch();
    for (const nanoseconds s : k.seen) w.note_complete(s);
    EXPECT_EQ(w.first_look(), k.first_look) << k.what;
  }
}

TEST(RtReplyWatch, MissingRepliesTeachNothing) {
  ReplyWatch w = dcp_watch();
  w.note_complete(microseconds(6000));
  for (int i = 0; i < 20; ++i) w.note_no_reply();
  EXPECT_EQ(w.first_look(), microseconds(6000));
}

TEST(RtReplyWatch, EverySixtyFourthExchangeLooksAtTheEarliestAndLearnsAQuickerDrive) {
  ReplyWatch w = dcp_watch();
  const nanoseconds earliest = w.first_look();
  std::size_t probes = 0;
  for (std::uint32_t i = 1; i < ReplyWatch::kProbeInterval; ++i) {
    w.note_complete(microseconds(8000));
    if (w.first_look() == earliest) ++probes;
  }
  EXPECT_EQ(probes, 0U);
  w.note_complete(microseconds(8000));  // the 64th exchange
  EXPECT_EQ(w.first_look(), earliest);  // the probe
  // The drive now answers sooner: the probe's look finds it at 4.2 ms, and the next exchange
  // looks there.
  w.note_complete(microseconds(4200));
  EXPECT_EQ(w.first_look(), microseconds(4200));
}

TEST(RtReplyWatch, ANewPortIsLearnedAgain) {
  ReplyWatch w = dcp_watch();
  const nanoseconds earliest = w.first_look();
  w.note_complete(microseconds(9000));
  ASSERT_EQ(w.first_look(), microseconds(9000));
  w.forget();
  EXPECT_EQ(w.first_look(), earliest);
}

}  // namespace
}  // namespace liftd::rt
