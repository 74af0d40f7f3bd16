// The master engine against fake slaves on a fake clock: timing of A 5.1.2 / A 5.2.1.1, the
// polling list of A 5.1, the "sendet nicht" flag, the PKW channel of C 4.2.1, mirror (A 5.3),
// broadcast (A 3, appendix), special telegrams (A 5.4) and the fixed cycle time (A 5.1.1).
#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

#include "bus_harness.hpp"
#include "master_fixture.hpp"
#include "uss/pzd.hpp"
#include "uss/receiver.hpp"

namespace liftd::uss {
namespace {

// ---------------------------------------------------------------------------------------------
// Configuration

struct BadConfig {
  const char* name;
  void (*change)(MasterConfig&);
  const char* text;  // part of the message
};

TEST(UssMasterConfig, RefusesWhatTheSpecForbidsWithAClearText) {
  const BadConfig cases[] = {
      {"reply delay above 20 ms", [](MasterConfig& c) { c.reply_delay = 20ms + 1ns; },
       "above the 20 ms maximum (A 5.2.1.1)"},
      {"reply delay below the start pause at 9600",
       [](MasterConfig& c) {
         c.baud = 9600;
         c.reply_delay = 2291666ns;  // start pause 2.291667 ms (A 5.1.2)
       },
       "below the start pause of 2291 us at 9600 baud (A 5.2.1.1"},
      {"empty polling list", [](MasterConfig& c) { c.polling_list.clear(); },
       "polling list is empty"},
      {"unknown address in the list",
       [](MasterConfig& c) {
         c.polling_list = {5, 6};
       },
       "polling list entry 6 is not a configured slave"},
      {"address 32", [](MasterConfig& c) { c.slaves[0].address = 32; }, "above 31 (A 4.3"},
      {"address twice", [](MasterConfig& c) { c.slaves.push_back(c.slaves[0]); },
       "configured twice"},
      {"17 PZD words", [](MasterConfig& c) { c.slaves[0].pzd_words = 17; }, "at most 16"},
      {"PKW length 5", [](MasterConfig& c) { c.slaves[0].pkw = static_cast<PkwLength>(5); },
       "none of 0, 3, 4, 127"},
      {"cycle time 0", [](MasterConfig& c) { c.cycle_time = 0ns; }, "cycle time must be above 0"},
      {"repeat limit 0", [](MasterConfig& c) { c.pkw_repeat_limit = 0; }, "pkw_repeat_limit"},
      {"baud 0", [](MasterConfig& c) { c.baud = 0; }, "baud rate 0"},
  };
  for (const BadConfig& bad : cases) {
    MasterConfig c = one_slave();
    bad.change(c);
    try {
      Master m(c);
      ADD_FAILURE() << bad.name << ": accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(bad.text), std::string::npos)
          << bad.name << ": " << e.what();
    }
  }
}

TEST(UssMasterConfig, AcceptsAReplyDelayEqualToTheStartPauseAnd20Ms) {
  for (const std::uint32_t baud : {9600U, 38400U, 187500U}) {
    MasterConfig c = one_slave(baud);
    c.reply_delay = start_pause(baud);
    EXPECT_NO_THROW(Master{c});
    c.reply_delay = 20ms;
    EXPECT_NO_THROW(Master{c});
  }
}

// ---------------------------------------------------------------------------------------------
// Timing (A 5.1.2, A 5.2.1.1, A 6.1)

struct TimingRow {
  std::uint32_t baud;
  std::int64_t tz_ns;           // A 6.1: 11 * 1e9 / baud, rounded up
  std::int64_t start_pause_ns;  // A 5.1.2: 2 tz
  double table_ms;              // A 5.1.2 Tabelle 5.1 (rounded to 0.01 ms)
};

constexpr TimingRow kTiming[] = {
    {9600, 1145834, 2291667, 2.30},
    {38400, 286459, 572917, 0.58},
    {187500, 58667, 117334, 0.12},
};

TEST(UssMasterTiming, StartPauseBeforeEveryStxIsTwoCharacterTimes) {
  for (const TimingRow& row : kTiming) {
    SCOPED_TRACE(row.baud);
    Bus bus(one_slave(row.baud));
    ASSERT_EQ(bus.tz.count(), row.tz_ns);
    ASSERT_EQ(bus.master.start_pause().count(), row.start_pause_ns);
    // Tabelle 5.1 rounds the minimum up to 0.01 ms.
    EXPECT_LE(static_cast<double>(row.start_pause_ns) / 1e6, row.table_ms);
    EXPECT_GT(static_cast<double>(row.start_pause_ns) / 1e6, row.table_ms - 0.01);

    // The first telegram after the port opened keeps a full start pause.
    const MonoTime opened = bus.t;
    EXPECT_EQ(bus.master.send_at(), opened + row.start_pause_ns * 1ns);
    const Sent first = bus.send();
    EXPECT_EQ(first.start, opened + row.start_pause_ns * 1ns);
    // 2 + 3 PKW words + 2 PZD words: 14 bytes on the line (A 4.2: LGE + 2).
    ASSERT_EQ(first.bytes.size(), 14U);
    EXPECT_EQ(first.end - first.start, transmission_time(row.baud, 14));
    EXPECT_EQ(transmission_time(row.baud, 14).count(),
              (14 * 11'000'000'000LL + row.baud - 1) / row.baud);

    // After a reply: the last character's stamp plus the start pause.
    const MonoTime last = bus.reply(idle_reply(5), 1ms);
    ASSERT_FALSE(bus.master.awaiting_reply());
    EXPECT_EQ(bus.master.send_at(), last + row.start_pause_ns * 1ns);
    EXPECT_EQ(bus.send().start, last + row.start_pause_ns * 1ns);
  }
}

TEST(UssMasterTiming, ReplyDelayDeadlineIsTheStxStartWithinTheDelay) {
  for (const TimingRow& row : kTiming) {
    for (const auto delay : {20ms, 5ms}) {
      SCOPED_TRACE(std::to_string(row.baud) + " baud, delay " + std::to_string(delay.count()));
      MasterConfig c = one_slave(row.baud);
      c.reply_delay = delay;
      Bus bus(c);
      const Sent s = bus.send();
      ASSERT_TRUE(bus.master.awaiting_reply());
      // A 5.2.1.1: the STX must begin within the reply delay after the BCC; a character is
      // stamped when complete, one character time later. First late instant = + 1 ns.
      const MonoTime deadline = s.end + delay + row.tz_ns * 1ns + 1ns;
      EXPECT_EQ(bus.master.deadline(), deadline);
      bus.master.on_time(deadline - 1ns);
      EXPECT_TRUE(bus.master.awaiting_reply());
      bus.master.on_time(deadline);
      EXPECT_FALSE(bus.master.awaiting_reply());
      EXPECT_EQ(bus.master.last_outcome(), ExchangeOutcome::Timeout);
      EXPECT_EQ(bus.master.rx_counters().reply_timeout, 1U);
      EXPECT_EQ(bus.master.rx_counters().error_word, error_bit(RxError::ReplyTimeout));
      // The line was quiet since our BCC: the next poll goes out at once.
      EXPECT_EQ(bus.master.send_at(), s.end + start_pause(row.baud));
    }
  }
}

TEST(UssMasterTiming, StxStampedExactlyAtTheLimitIsAcceptedOneNanosecondLaterIsNot) {
  for (const bool late : {false, true}) {
    Bus bus(one_slave(9600));
    const Sent s = bus.send();
    const MonoTime stx_at = s.end + 20ms + bus.tz + (late ? 1ns : 0ns);
    const Bytes reply = idle_reply(5);
    MonoTime at = stx_at;
    for (const std::uint8_t b : reply) {
      bus.master.on_char(RxChar{b, LineError::None}, at);
      at += bus.tz;
    }
    EXPECT_EQ(bus.master.last_outcome(), late ? ExchangeOutcome::Timeout : ExchangeOutcome::Reply);
    EXPECT_EQ(bus.master.slave(5).responding, !late);
  }
}

TEST(UssMasterTiming, AReplyDeliveredAllAtOnceStillOccupiesTheLineForItsCharacters) {
  // A pty hands the whole reply over in one read: the line is taken as busy until the telegram
  // could have ended, k character times after the STX began (A 6.2), then the start pause.
  Bus bus(one_slave(38400));
  const Sent s = bus.send();
  const MonoTime at = s.end + 2ms;
  const Bytes reply = idle_reply(5);
  bus.reply_at_once(reply, at);
  ASSERT_EQ(bus.master.last_outcome(), ExchangeOutcome::Reply);
  EXPECT_EQ(bus.master.send_at(), at - character_time(38400) +
                                      transmission_time(38400, reply.size()) + start_pause(38400));
}

TEST(UssMasterTiming, ResidualTimeIsSupervisedAfterTheStx) {
  Bus bus(one_slave(38400));
  const Sent s = bus.send();
  const Bytes reply = idle_reply(5);
  const MonoTime stx = s.end + 1ms;
  bus.master.on_char(RxChar{reply[0], LineError::None}, stx);
  // A 6.3: 1.5 * (n + 3) tz from the STX, n = 10 payload bytes; first late instant + 1 ns.
  const MonoTime residual = stx + max_residual_time(38400, 10) + 1ns;
  EXPECT_EQ(bus.master.deadline(), residual);
  bus.master.on_time(residual);
  EXPECT_EQ(bus.master.last_outcome(), ExchangeOutcome::BadReply);
  EXPECT_EQ(bus.master.rx_counters().residual_time, 1U);
  EXPECT_FALSE(bus.master.slave(5).responding);
}

TEST(UssMasterTiming, ExpectedCycleTimeFollowsTheSpecRules) {
  MasterConfig c;
  c.baud = 38400;
  c.mirror_at_start = false;
  c.slaves = {SlaveConfig{1, PkwLength::Four, 2}, SlaveConfig{2, PkwLength::Three, 2},
              SlaveConfig{3, PkwLength::None, 6}};
  c.polling_list = {1, 2, 1, 3};
  c.reply_delay = 10ms;
  const auto sp = start_pause(38400);
  // Telegram bytes: 4 + PKW + PZD bytes (A 4.2), request and reply the same length (C 7);
  // without an expected reply delay the maximum wait is taken (A 5.1.1).
  auto ex = [&](std::size_t bytes, std::chrono::nanoseconds delay) {
    return sp + transmission_time(38400, bytes) + delay + transmission_time(38400, bytes);
  };
  EXPECT_EQ(Master(c).expected_cycle_time(),
            ex(16, 10ms) + ex(14, 10ms) + ex(16, 10ms) + ex(16, 10ms));
  c.expected_reply_delay = 1ms;
  EXPECT_EQ(Master(c).expected_cycle_time(), ex(16, 1ms) + ex(14, 1ms) + ex(16, 1ms) + ex(16, 1ms));
  c.cycle_time = 100ms;
  EXPECT_EQ(Master(c).expected_cycle_time(), 100ms);
}

// ---------------------------------------------------------------------------------------------
// Fixed cycle time (A 5.1.1)

TEST(UssMasterCycle, FixedCycleTimeWaitsForTheEndOfTheCycle) {
  MasterConfig c;
  c.baud = 38400;
  c.mirror_at_start = false;
  c.slaves = {SlaveConfig{1, PkwLength::Three, 2}, SlaveConfig{2, PkwLength::Three, 2}};
  c.polling_list = {1, 2};
  c.cycle_time = 50ms;
  Bus bus(c);
  MonoTime pass_start{};
  for (int pass = 0; pass < 4; ++pass) {
    for (int i = 0; i < 2; ++i) {
      const MonoTime due = bus.master.send_at();
      const Sent s = bus.send();
      if (i == 0 && pass > 0) {
        // A 5.1.1: the new pass begins when the defined cycle time has elapsed.
        EXPECT_EQ(due, pass_start + 50ms);
        EXPECT_EQ(s.start, pass_start + 50ms);
        EXPECT_EQ(bus.master.last_cycle_time(), 50ms);
      }
      if (i == 0) pass_start = s.start;
      bus.reply(idle_reply(parse_adr(s.bytes[2]).slave), 1ms);
    }
  }
  EXPECT_EQ(bus.master.cycles(), 3U);
}

TEST(UssMasterCycle, WithoutFixedCycleTheCycleIsTheSumOfTheExchanges) {
  MasterConfig c = one_slave(38400);
  c.expected_reply_delay = 1ms;
  Bus bus(c);
  bus.send();
  bus.reply(idle_reply(5), 1ms);  // the STX begins 1 ms after our BCC
  bus.send();
  // Start pause + 14 characters + 1 ms + 14 characters (A 5.1.1 Bild 5.2), exactly.
  EXPECT_EQ(bus.master.last_cycle_time(), bus.master.expected_cycle_time());
}

}  // namespace
}  // namespace liftd::uss
