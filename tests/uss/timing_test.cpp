// USS timing (A 5.1.1, A 5.1.2 Tabelle 5.1, A 6.1-6.3).
#include <gtest/gtest.h>

#include <array>

#include "uss/timing.hpp"

namespace liftd::uss {
namespace {

using std::chrono::nanoseconds;

TEST(UssTiming, CharacterTime) {
  // A 6.1: tz = 11 * 1000 / baud ms; rounded up to whole ns.
  EXPECT_EQ(character_time(38400), nanoseconds(286459));   // 286.458 33 us
  EXPECT_EQ(character_time(9600), nanoseconds(1145834));   // 1.145 833 ms
  EXPECT_EQ(character_time(187500), nanoseconds(58667));   // 58.666 7 us
  EXPECT_EQ(character_time(11000), nanoseconds(1000000));  // exact
  EXPECT_EQ(character_time(0), nanoseconds(0));
}

TEST(UssTiming, StartPauseMatchesTabelle51) {
  // A 5.1.2 Tabelle 5.1 gives 2 tz rounded up to 0.01 ms.
  struct Case {
    std::uint32_t baud;
    std::int64_t ns;        // 2 * 11 / baud, rounded up to ns
    std::int64_t table_us;  // Tabelle 5.1 in us
  };
  for (const Case& c : {Case{9600, 2291667, 2300}, Case{19200, 1145834, 1150},
                        Case{38400, 572917, 580}, Case{187500, 117334, 120}}) {
    EXPECT_EQ(start_pause(c.baud).count(), c.ns) << c.baud;
    const std::int64_t rounded_up_10us = (c.ns + 9999) / 10000 * 10;
    EXPECT_EQ(rounded_up_10us, c.table_us) << c.baud;
  }
}

TEST(UssTiming, ResidualTimes) {
  // A 6.2: (n + 3) tz; A 6.3: 1.5 (n + 3) tz; n = payload characters.
  // 38400 baud, n = 10: 13 tz = 3.723 958 3 ms, max 19.5 tz = 5.585 937 5 ms.
  EXPECT_EQ(flush_residual_time(38400, 10), nanoseconds(3723959));
  EXPECT_EQ(max_residual_time(38400, 10), nanoseconds(5585938));
  EXPECT_EQ(max_residual_time_for_lge(38400, 12), max_residual_time(38400, 10));
  // n = 252 (the value loaded at STX for variable length, A 5.2.1.2): 382.5 tz at 9600.
  EXPECT_EQ(max_residual_time(9600, 252), nanoseconds(438281250));
  // 11000 baud: tz = 1 ms exactly; n = 0: 4.5 ms.
  EXPECT_EQ(max_residual_time(11000, 0), nanoseconds(4500000));
  EXPECT_EQ(max_residual_time_for_lge(11000, 2), nanoseconds(4500000));
  EXPECT_EQ(max_residual_time_for_lge(11000, 0), nanoseconds(4500000));
}

TEST(UssTiming, TransmissionTime) {
  EXPECT_EQ(transmission_time(11000, 14), nanoseconds(14000000));
  EXPECT_EQ(transmission_time(38400, 14), nanoseconds(4010417));  // 14 * 286.458 33 us
  EXPECT_EQ(transmission_time(38400, 0), nanoseconds(0));
}

TEST(UssTiming, ExpectedCycleTime) {
  // 11000 baud (tz = 1 ms): two slaves with 14-byte telegrams, 5 ms reply delay each, and a
  // broadcast of 16 bytes without a reply:
  // 2 x (2 + 14 + 5 + 14) + (2 + 16) = 70 + 18 = 88 ms.
  const std::array<Exchange, 3> list{Exchange{14, 14, std::chrono::milliseconds(5)},
                                     Exchange{14, 14, std::chrono::milliseconds(5)},
                                     Exchange{16, 0, std::chrono::milliseconds(5)}};
  EXPECT_EQ(expected_cycle_time(11000, list), std::chrono::milliseconds(88));
  EXPECT_EQ(expected_cycle_time(11000, {}), nanoseconds(0));
}

}  // namespace
}  // namespace liftd::uss
