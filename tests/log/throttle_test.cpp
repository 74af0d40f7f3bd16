// The journal throttle with made-up times: the first lines of an interval in full, the rest
// counted and summed up once the interval ends, and a quiet interval starting over.
#include <gtest/gtest.h>

#include "log/throttle.hpp"

namespace liftd::log {
namespace {

using namespace std::chrono_literals;

TEST(JournalThrottle, AFloodCostsTheBurstAndOneCountPerInterval) {
  Throttle t(3, 10s);
  MonoTime now = 100s;
  int full = 0;
  for (int i = 0; i < 1000; ++i) {  // 1000 occurrences in 1 s
    full += t.admit(1, now) ? 1 : 0;
    EXPECT_FALSE(t.suppressed(now)) << "no summary before the interval ends";
    now += 1ms;
  }
  EXPECT_EQ(full, 3);
  EXPECT_FALSE(t.suppressed(109s));
  EXPECT_EQ(t.suppressed(110s), 997U);
  EXPECT_FALSE(t.suppressed(111s)) << "one summary per interval";
  // The flood is over: the next occurrence is journalled in full again.
  EXPECT_TRUE(t.admit(1, 130s));
}

TEST(JournalThrottle, OccurrencesAfterTheIntervalBeforeTheSummaryAreInTheSummary) {
  Throttle t(1, 10s);
  EXPECT_TRUE(t.admit(1, 0s));
  EXPECT_FALSE(t.admit(5, 1s));
  EXPECT_FALSE(t.admit(2, 12s));  // the interval is over but its count not yet told
  EXPECT_EQ(t.suppressed(12s), 7U);
  EXPECT_TRUE(t.admit(1, 12s));
}

TEST(JournalThrottle, GrowthOfACounter) {
  Throttle t(1, 10s);
  EXPECT_EQ(t.growth(0), 0U);
  EXPECT_EQ(t.growth(5), 5U);
  EXPECT_EQ(t.growth(5), 0U);
  EXPECT_EQ(t.growth(9), 4U);
  EXPECT_EQ(t.admit(0, 1s), false) << "nothing happened";
}

}  // namespace
}  // namespace liftd::log
