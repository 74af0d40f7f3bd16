// Over 800 lines: one case table per USS chapter (A 5.1-5.4, C 4.2.1) against one fake bus; split,
// the chapters would lose their shared fixture.
// The master engine against fake slaves on a fake clock: timing of A 5.1.2 / A 5.2.1.1, the
// polling list of A 5.1, the "sendet nicht" flag, the PKW channel of C 4.2.1, mirror (A 5.3),
// broadcast (A 3, appendix), special telegrams (A 5.4) and the fixed cycle time (A 5.1.1).
#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

#include "bus_harness.hpp"
#include "uss/pzd.hpp"
#include "uss/receiver.hpp"

namespace liftd::uss {
namespace {

using namespace std::chrono_literals;
using testing::Bus;
using testing::Bytes;
using testing::make_reply;
using testing::parse_request;
using testing::reply_pkw;
using testing::Sent;

MasterConfig one_slave(std::uint32_t baud = 38400, PkwLength pkw = PkwLength::Three,
                       std::uint8_t pzd = 2) {
  MasterConfig c;
  c.baud = baud;
  c.slaves = {SlaveConfig{5, pkw, pzd}};
  c.polling_list = {5};
  c.mirror_at_start = false;
  return c;
}

// Answers a poll of slave `address` (PKW 3 words, 2 PZD) with "keine Antwort" and ZSW/HIW.
Bytes idle_reply(std::uint8_t address, PkwLength len = PkwLength::Three,
                 std::vector<std::uint16_t> pzd = {0x0237, 0x1000}) {
  return make_reply(address, Pkw{}, len, std::move(pzd));
}

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
// Polling list and link state (A 5.1, A 5.2.1.1)

MasterConfig spec_polling_list() {
  // A 5.1 Bild 5.1: "Die Teilnehmer 0 und 1 werden doppelt so oft angesprochen".
  MasterConfig c;
  c.baud = 19200;
  c.mirror_at_start = false;
  for (const int a : {0, 1, 3, 5, 7, 21}) {
    c.slaves.push_back({static_cast<std::uint8_t>(a), PkwLength::None, 1});
  }
  c.polling_list = {0, 1, 3, 5, 0, 1, 7, 21};
  return c;
}

TEST(UssMasterPolling, FollowsThePollingListWithRepeats) {
  Bus bus(spec_polling_list());
  std::vector<std::uint8_t> order;
  for (int i = 0; i < 24; ++i) {
    const Sent s = bus.send();
    ASSERT_EQ(s.bytes.size(), 6U);  // STX LGE ADR, 1 PZD word, BCC
    const AddressByte adr = parse_adr(s.bytes[2]);
    EXPECT_EQ(adr.type, TelegramType::Normal);
    order.push_back(adr.slave);
    bus.reply(make_reply(adr.slave, Pkw{}, PkwLength::None, {0x0001}), 500us);
  }
  const std::vector<std::uint8_t> pass = {0, 1, 3, 5, 0, 1, 7, 21};
  for (std::size_t i = 0; i < order.size(); ++i) EXPECT_EQ(order[i], pass[i % 8]) << i;
  // Two passes complete when the third starts.
  EXPECT_EQ(bus.master.cycles(), 2U);
  EXPECT_EQ(bus.master.counters().polls, 24U);
  EXPECT_EQ(bus.master.rx_counters().good, 24U);
}

TEST(UssMasterPolling, SilentSlaveIsFlaggedStaysInTheListAndIsClearedByAGoodReply) {
  Bus bus(spec_polling_list());
  LinkChange change;
  // Pass 1: slave 3 does not answer.
  for (int i = 0; i < 8; ++i) {
    const Sent s = bus.send();
    const std::uint8_t a = parse_adr(s.bytes[2]).slave;
    if (a == 3) {
      bus.timeout();
    } else {
      bus.reply(make_reply(a, Pkw{}, PkwLength::None, {static_cast<std::uint16_t>(a)}), 500us);
    }
  }
  EXPECT_FALSE(bus.master.slave(3).responding);
  EXPECT_EQ(bus.master.slave(3).failures, 1U);
  EXPECT_EQ(bus.master.slave(0).pzd_in[0], 0U);
  EXPECT_EQ(bus.master.slave(21).pzd_in[0], 21U);
  // Every slave came up except 3, which is reported "does not send" (A 5.2.1.1).
  int up = 0;
  int down = 0;
  while (bus.master.poll_link_change(change)) {
    if (change.responding) {
      ++up;
    } else {
      ++down;
      EXPECT_EQ(change.address, 3);
    }
  }
  EXPECT_EQ(up, 5);
  EXPECT_EQ(down, 1);
  // Pass 2: still silent, still polled, no new report; pass 3: it answers.
  for (int pass = 2; pass <= 3; ++pass) {
    for (int i = 0; i < 8; ++i) {
      const Sent s = bus.send();
      const std::uint8_t a = parse_adr(s.bytes[2]).slave;
      if (a == 3 && pass == 2) {
        bus.timeout();
      } else {
        bus.reply(make_reply(a, Pkw{}, PkwLength::None, {0x0100}), 500us);
      }
    }
    if (pass == 2) {
      EXPECT_FALSE(bus.master.poll_link_change(change));
      EXPECT_EQ(bus.master.slave(3).consecutive_failures, 2U);
    }
  }
  ASSERT_TRUE(bus.master.poll_link_change(change));
  EXPECT_EQ(change.address, 3);
  EXPECT_TRUE(change.responding);
  EXPECT_TRUE(bus.master.slave(3).responding);
  EXPECT_EQ(bus.master.slave(3).consecutive_failures, 0U);
  EXPECT_EQ(bus.master.rx_counters().reply_timeout, 2U);
}

TEST(UssMasterPolling, AnUnusableReplyFlagsTheSlave) {
  struct Case {
    const char* name;
    Bytes (*reply)();
    std::uint64_t MasterCounters::*counter;
  };
  const Case cases[] = {
      {"bad BCC",
       [] {
         Bytes b = idle_reply(5);
         b.back() ^= 0x01;
         return b;
       },
       &MasterCounters::bad_replies},
      {"other slave's address", [] { return idle_reply(6); }, &MasterCounters::wrong_address},
      {"mirror bit in the reply",
       [] {
         Bytes b = idle_reply(5);
         b[2] |= kAdrMirror;
         b.back() ^= kAdrMirror;
         return b;
       },
       &MasterCounters::wrong_address},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    Bus bus(one_slave());
    bus.send();
    bus.reply(idle_reply(5));
    ASSERT_TRUE(bus.master.slave(5).responding);
    bus.send();
    bus.reply(c.reply());
    EXPECT_EQ(bus.master.last_outcome(), ExchangeOutcome::BadReply);
    EXPECT_FALSE(bus.master.slave(5).responding);
    EXPECT_EQ(bus.master.counters().*c.counter, 1U);
  }
}

TEST(UssMasterPolling, AnEchoCollisionEndsTheExchangeAsABadOneAndFlagsTheSlave) {
  // The runner read our telegram back changed on an echoing bus: the slave did not receive it
  // intact (A 5.2.2) and will not answer it. A bad exchange; the next telegram keeps a start
  // pause after the collision.
  Bus bus(one_slave());
  bus.send();
  bus.reply(idle_reply(5));
  ASSERT_TRUE(bus.master.slave(5).responding);
  bus.send();
  ASSERT_TRUE(bus.master.awaiting_reply());
  const MonoTime at = bus.t;
  bus.master.on_collision(at);
  EXPECT_FALSE(bus.master.awaiting_reply());
  EXPECT_EQ(bus.master.last_outcome(), ExchangeOutcome::BadReply);
  EXPECT_FALSE(bus.master.slave(5).responding);
  EXPECT_EQ(bus.master.counters().bad_replies, 1U);
  EXPECT_GE(bus.master.send_at(), at + bus.master.start_pause());
  bus.master.on_collision(at);  // nothing awaited: no effect
  EXPECT_EQ(bus.master.counters().bad_replies, 1U);
}

TEST(UssMasterPolling, WrongLengthForAFixedSlaveIsRejected) {
  // A 5.2: LGE must equal the fixed length of the slave (PKW 3 + PZD 2: LGE 12).
  Bus bus(one_slave());
  bus.send();
  bus.reply(make_reply(5, Pkw{}, PkwLength::Four, {1, 2}));
  EXPECT_EQ(bus.master.last_outcome(), ExchangeOutcome::BadReply);
  EXPECT_EQ(bus.master.rx_counters().lge, 1U);
}

TEST(UssMasterPolling, NoiseBeforeTheReplyDoesNotEndTheWait) {
  Bus bus(one_slave());
  const Sent s = bus.send();
  bus.master.on_char(RxChar{0x00, LineError::None}, s.end + 100us);  // A 5.2.3 counter 12
  EXPECT_TRUE(bus.master.awaiting_reply());
  bus.t = s.end + 2ms;
  bus.reply(idle_reply(5), 0ns);
  EXPECT_EQ(bus.master.last_outcome(), ExchangeOutcome::Reply);
  EXPECT_EQ(bus.master.rx_counters().no_stx, 1U);
}

TEST(UssMasterPolling, PzdGoesOutAndComesIn) {
  Bus bus(one_slave());
  const std::uint16_t stw = stw::kOn | stw::kNoOff2 | stw::kNoOff3 | stw::kControlByPlc;
  const std::vector<std::uint16_t> out = {stw, 0x2000};
  bus.master.set_pzd(5, out);
  const auto req = parse_request(bus.send().bytes, PkwLength::Three, 2);
  ASSERT_TRUE(req.ok);
  EXPECT_EQ(req.pzd, out);
  bus.reply(idle_reply(5, PkwLength::Three, {0x0637, 0x1FFF}));
  EXPECT_EQ(bus.master.slave(5).pzd_in_count, 2);
  EXPECT_EQ(bus.master.slave(5).pzd_in[0], 0x0637);
  EXPECT_EQ(bus.master.slave(5).pzd_in[1], 0x1FFF);
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

// ---------------------------------------------------------------------------------------------
// PKW channel (C 4.2.1)

Pkw read_request(std::uint16_t pnu) {
  Pkw p;
  p.id = request::kReadValue;
  p.pnu = pnu;
  p.pwe_count = 1;
  return p;
}

TEST(UssMasterPkw, RequestIsRepeatedUntilTheMatchingReplyStaleRepliesIgnored) {
  Bus bus(one_slave());
  ASSERT_TRUE(bus.master.submit_pkw(5, read_request(52), 77));
  EXPECT_TRUE(bus.master.slave(5).pkw_busy);
  EXPECT_FALSE(bus.master.submit_pkw(5, read_request(53), 78)) << "one request per slave";
  // C 8 example 2: read parameter 52; the slave first still answers the old request (PNU 51),
  // then "keine Antwort", then the value 4000 hex.
  const Pkw replies[] = {reply_pkw(reply::kValueWord, 51, PkwLength::Three, 0x1234),
                         reply_pkw(reply::kNone, 0, PkwLength::Three, 0),
                         reply_pkw(reply::kValueWord, 52, PkwLength::Three, 0x4000)};
  PkwResult result;
  for (const Pkw& r : replies) {
    EXPECT_FALSE(bus.master.poll_pkw_result(result));
    const auto req = parse_request(bus.send().bytes, PkwLength::Three, 2);
    ASSERT_TRUE(req.ok);
    EXPECT_EQ(req.pkw.id, request::kReadValue);  // the same request every time
    EXPECT_EQ(req.pkw.pnu, 52);
    bus.reply(make_reply(5, r, PkwLength::Three, {0, 0}));
  }
  ASSERT_TRUE(bus.master.poll_pkw_result(result));
  EXPECT_EQ(result.tag, 77U);
  EXPECT_EQ(result.address, 5);
  EXPECT_EQ(result.outcome, PkwResult::Outcome::Done);
  EXPECT_EQ(value(result.reply, PkwLength::Three, PkwWidth::Word), 0x4000U);
  EXPECT_EQ(bus.master.counters().pkw_stale_replies, 2U);
  EXPECT_FALSE(bus.master.slave(5).pkw_busy);
  // Done: the next poll carries "kein Auftrag" again, and a new request can start.
  EXPECT_EQ(parse_request(bus.send().bytes, PkwLength::Three, 2).pkw.id, request::kNone);
  bus.reply(idle_reply(5));
  EXPECT_TRUE(bus.master.submit_pkw(5, read_request(53), 78));
}

TEST(UssMasterPkw, TimeoutsCountAsRepeatsAndTheRequestEndsUnanswered) {
  MasterConfig c = one_slave();
  c.pkw_repeat_limit = 3;
  Bus bus(c);
  ASSERT_TRUE(bus.master.submit_pkw(5, read_request(52), 1));
  PkwResult result;
  bus.send();
  bus.timeout();
  bus.send();
  bus.reply(make_reply(5, reply_pkw(reply::kValueWord, 51, PkwLength::Three, 1), PkwLength::Three,
                       {0, 0}));
  EXPECT_FALSE(bus.master.poll_pkw_result(result));
  bus.send();
  bus.timeout();
  ASSERT_TRUE(bus.master.poll_pkw_result(result));
  EXPECT_EQ(result.outcome, PkwResult::Outcome::Unanswered);
  EXPECT_EQ(bus.master.counters().pkw_unanswered, 1U);
}

TEST(UssMasterPkw, ErrorAndNoAuthorityEndTheRequest) {
  // C 4.2.1.1: AK 7 with the error number in PWE (with 4 words in PWE2), AK 8 to a change.
  for (const PkwLength len : {PkwLength::Three, PkwLength::Four}) {
    Bus bus(one_slave(38400, len));
    Pkw write;
    write.id = request::kWriteWord;
    write.pnu = 18;
    set_value(write, len, PkwWidth::Word, 0x7000);
    ASSERT_TRUE(bus.master.submit_pkw(5, write, 9));
    const auto req = parse_request(bus.send().bytes, len, 2);
    EXPECT_EQ(req.pkw.pke(), 0x2012);  // AK 2, PNU 18
    bus.reply(make_reply(5, reply_pkw(reply::kError, 18, len, 2), len, {0, 0}));
    PkwResult result;
    ASSERT_TRUE(bus.master.poll_pkw_result(result));
    EXPECT_EQ(result.outcome, PkwResult::Outcome::Error);
    EXPECT_EQ(result.error_number, 2);  // "Wertgrenze überschritten"

    ASSERT_TRUE(bus.master.submit_pkw(5, write, 10));
    bus.send();
    bus.reply(make_reply(5, reply_pkw(reply::kNoAuthority, 18, len, 0), len, {0, 0}));
    ASSERT_TRUE(bus.master.poll_pkw_result(result));
    EXPECT_EQ(result.outcome, PkwResult::Outcome::NoAuthority);
    EXPECT_EQ(result.tag, 10U);
  }
}

TEST(UssMasterPkw, RequestsThatDoNotFitAreRefused) {
  Bus bus(one_slave(38400, PkwLength::Three));
  Pkw dword;
  dword.id = request::kWriteDword;
  dword.pnu = 4;
  set_value(dword, PkwLength::Three, PkwWidth::Dword, 0x40000000);
  EXPECT_FALSE(bus.master.submit_pkw(5, dword, 1)) << "C 7: a double word needs 4 PKW words";
  EXPECT_FALSE(bus.master.submit_pkw(5, Pkw{}, 1)) << "'kein Auftrag' is no request";
  EXPECT_FALSE(bus.master.submit_pkw(6, read_request(1), 1)) << "not configured";
  Bus none(one_slave(38400, PkwLength::None));
  EXPECT_FALSE(none.master.submit_pkw(5, read_request(1), 1)) << "no PKW area";
}

TEST(UssMasterPkw, SpontaneousReportIsSurfacedOnceAndAcknowledgedByTogglingBit11) {
  Bus bus(one_slave());
  // First contact: "keine Antwort" with bit 11 = 0.
  bus.send();
  bus.reply(idle_reply(5));
  ASSERT_TRUE(bus.master.submit_pkw(5, read_request(52), 3));

  auto poll = [&bus](const Pkw& reply) {
    const auto req = parse_request(bus.send().bytes, PkwLength::Three, 2);
    bus.reply(make_reply(5, reply, PkwLength::Three, {0, 0}));
    return req.pkw;
  };
  // C 4.2.1.2: the slave interrupts with a report and changes bit 11 (0 -> 1).
  const Pkw report1 = reply_pkw(reply::kSpontaneousWord, 100, PkwLength::Three, 5, true);
  Pkw sent = poll(report1);
  EXPECT_FALSE(sent.toggle);
  SpontaneousReport r;
  ASSERT_TRUE(bus.master.poll_spontaneous(r));
  EXPECT_EQ(r.address, 5);
  EXPECT_EQ(r.report.pnu, 100);
  EXPECT_EQ(value(r.report, PkwLength::Three, PkwWidth::Word), 5U);
  // The master acknowledges by changing its bit 11; the slave may repeat the report until it
  // has seen that: not surfaced again.
  sent = poll(report1);
  EXPECT_TRUE(sent.toggle) << "acknowledged with bit 11 = 1";
  EXPECT_EQ(sent.id, request::kReadValue) << "our request keeps being repeated";
  EXPECT_EQ(sent.pnu, 52);
  EXPECT_FALSE(bus.master.poll_spontaneous(r));
  EXPECT_EQ(bus.master.counters().spontaneous_repeats, 1U);
  // A second report: the slave changes bit 11 again (1 -> 0).
  const Pkw report2 = reply_pkw(reply::kSpontaneousArrayWord, 101, PkwLength::Three, 7, false, 3);
  sent = poll(report2);
  EXPECT_TRUE(sent.toggle);
  ASSERT_TRUE(bus.master.poll_spontaneous(r));
  EXPECT_EQ(r.report.pnu, 101);
  EXPECT_EQ(r.report.ind, 3);
  // Then the slave answers our request, with its current bit 11 (0).
  sent = poll(reply_pkw(reply::kValueWord, 52, PkwLength::Three, 0x4000, false));
  EXPECT_FALSE(sent.toggle) << "second acknowledgement: bit 11 back to 0";
  PkwResult result;
  ASSERT_TRUE(bus.master.poll_pkw_result(result));
  EXPECT_EQ(result.outcome, PkwResult::Outcome::Done);
  EXPECT_EQ(bus.master.counters().spontaneous, 2U);
}

TEST(UssMasterPkw, ReportsDoNotCountAgainstTheRepeatLimit) {
  MasterConfig c = one_slave();
  c.pkw_repeat_limit = 2;
  Bus bus(c);
  ASSERT_TRUE(bus.master.submit_pkw(5, read_request(52), 3));
  bool toggle = false;
  for (int i = 0; i < 4; ++i) {
    toggle = !toggle;
    bus.send();
    bus.reply(make_reply(5, reply_pkw(reply::kSpontaneousWord, 100, PkwLength::Three, 1, toggle),
                         PkwLength::Three, {0, 0}));
  }
  PkwResult result;
  EXPECT_FALSE(bus.master.poll_pkw_result(result));
  EXPECT_EQ(bus.master.counters().spontaneous, 4U);
}

TEST(UssMasterPkw, TheToggleOfARestartedSlaveIsAdoptedWhenItIsHeardAgain) {
  Bus bus(one_slave());
  bus.send();
  bus.reply(make_reply(5, reply_pkw(reply::kSpontaneousWord, 100, PkwLength::Three, 1, true),
                       PkwLength::Three, {0, 0}));
  SpontaneousReport r;
  ASSERT_TRUE(bus.master.poll_spontaneous(r));
  EXPECT_TRUE(parse_request(bus.send().bytes, PkwLength::Three, 2).pkw.toggle);
  bus.timeout();  // the slave restarts; its bit 11 is 0 again
  bus.send();
  bus.reply(idle_reply(5));
  EXPECT_FALSE(parse_request(bus.send().bytes, PkwLength::Three, 2).pkw.toggle);
  // Its next report (bit 11 -> 1) is new.
  bus.reply(make_reply(5, reply_pkw(reply::kSpontaneousWord, 100, PkwLength::Three, 2, true),
                       PkwLength::Three, {0, 0}));
  ASSERT_TRUE(bus.master.poll_spontaneous(r));
  EXPECT_EQ(value(r.report, PkwLength::Three, PkwWidth::Word), 2U);
}

TEST(UssMasterPkw, VariableLengthReplyWithText) {
  // C 8 example 7 shape: PKW_ANZ 127, no PZD; the reply carries 8 PWE words of text.
  MasterConfig c = one_slave(38400, PkwLength::Variable, 0);
  Bus bus(c);
  Pkw text;
  text.id = request::kText;
  text.pnu = 7;
  text.ind = make_text_ind(3, false);
  text.pwe_count = 1;
  ASSERT_TRUE(bus.master.submit_pkw(5, text, 1));
  const Sent s = bus.send();
  EXPECT_EQ(s.bytes.size(), 4U + 6U);  // PKE IND PWE1
  Pkw reply;
  reply.id = reply::kText;
  reply.pnu = 7;
  reply.ind = text.ind;
  reply.pwe_count = 8;
  const char* chars = "300 BAUD        ";
  for (int i = 0; i < 8; ++i) {
    reply.pwe[static_cast<std::size_t>(i)] =
        static_cast<std::uint16_t>((static_cast<unsigned char>(chars[2 * i]) << 8) |
                                   static_cast<unsigned char>(chars[2 * i + 1]));
  }
  bus.reply(make_reply(5, reply, PkwLength::Variable, {}));
  PkwResult result;
  ASSERT_TRUE(bus.master.poll_pkw_result(result));
  EXPECT_EQ(result.outcome, PkwResult::Outcome::Done);
  EXPECT_EQ(result.reply.pwe_count, 8);
  EXPECT_EQ(result.reply.pwe[0], 0x3330);  // "30"
}

// ---------------------------------------------------------------------------------------------
// Mirror (A 5.3)

TEST(UssMasterMirror, AtStartEverySlaveIsMirroredThenPolled) {
  MasterConfig c;
  c.baud = 38400;
  c.slaves = {SlaveConfig{1, PkwLength::Three, 2}, SlaveConfig{2, PkwLength::Four, 1}};
  c.polling_list = {1, 2};
  Bus bus(c);
  // Slave 1 sends the telegram back unchanged, slave 2 changes one byte.
  const Sent m1 = bus.send();
  EXPECT_EQ(m1.bytes[2], make_adr(1, TelegramType::Mirror));
  EXPECT_EQ(m1.bytes[2], 0x41);
  bus.reply(m1.bytes);
  const Sent m2 = bus.send();
  EXPECT_EQ(m2.bytes[2], 0x42);
  EXPECT_EQ(m2.bytes.size(), 4U + 8U + 2U);
  Bytes changed = m2.bytes;
  changed[5] ^= 0x10;
  changed.back() ^= 0x10;  // still a valid telegram, but not the same
  bus.reply(changed);
  // Then the polls (bit 6 clear).
  const Sent p = bus.send();
  EXPECT_EQ(p.bytes[2], 0x01);
  bus.reply(idle_reply(1));

  MirrorResult r;
  ASSERT_TRUE(bus.master.poll_mirror(r));
  EXPECT_EQ(r.tag, kStartMirrorTag);
  EXPECT_EQ(r.address, 1);
  EXPECT_TRUE(r.ok);
  EXPECT_EQ(r.round_trip, m1.end - m1.start + 1ms + transmission_time(38400, 14));
  ASSERT_TRUE(bus.master.poll_mirror(r));
  EXPECT_EQ(r.address, 2);
  EXPECT_FALSE(r.ok);
  EXPECT_FALSE(bus.master.slave(2).responding);
  EXPECT_EQ(bus.master.counters().mirror_mismatches, 1U);
  EXPECT_FALSE(bus.master.poll_mirror(r));
}

TEST(UssMasterMirror, OnRequestTheMirrorGoesOutAfterTheNextPoll) {
  Bus bus(one_slave());
  bus.send();
  bus.reply(idle_reply(5));
  ASSERT_TRUE(bus.master.request_mirror(5, 42));
  EXPECT_FALSE(bus.master.request_mirror(5, 43)) << "one pending mirror per slave";
  const Sent mirror = bus.send();
  EXPECT_EQ(parse_adr(mirror.bytes[2]).type, TelegramType::Mirror);
  bus.timeout();
  EXPECT_EQ(parse_adr(bus.send().bytes[2]).type, TelegramType::Normal);
  MirrorResult r;
  ASSERT_TRUE(bus.master.poll_mirror(r));
  EXPECT_EQ(r.tag, 42U);
  EXPECT_FALSE(r.ok);
  EXPECT_EQ(r.round_trip, 0ns);
}

// ---------------------------------------------------------------------------------------------
// Broadcast (A 3, appendix) and special telegrams (A 5.4)

TEST(UssMasterBroadcast, GoesOutBetweenPollsWithTheEnableArrayAndNoReplyIsAwaited) {
  Bus bus(one_slave());
  bus.send();
  bus.reply(idle_reply(5));
  // Appendix example 1: the same main setpoint to every drive: word a = 0000 0000 0000 0101.
  BroadcastEnable be;
  be.enable = true;
  be.pzd_words = pzd_word_bit(2);
  const std::vector<std::uint16_t> pzd = {0x047E, 0x2000};
  ASSERT_TRUE(bus.master.send_broadcast(be, pzd));
  const Sent b = bus.send();
  Bytes expected = {kStx, 14, 0x20, 0x00, 0x05, 0, 0, 0, 0, 0, 0, 0x04, 0x7E, 0x20, 0x00};
  expected.push_back(block_check(expected));
  EXPECT_EQ(b.bytes, expected);
  EXPECT_FALSE(bus.master.awaiting_reply()) << "A 3: no slave answers a broadcast";
  EXPECT_EQ(bus.master.last_outcome(), ExchangeOutcome::NoReplyExpected);
  EXPECT_EQ(bus.master.send_at(), b.end + start_pause(38400));
  EXPECT_EQ(parse_adr(bus.send().bytes[2]).type, TelegramType::Normal);
  EXPECT_EQ(bus.master.counters().broadcasts, 1U);
  EXPECT_FALSE(bus.master.send_broadcast(be, std::vector<std::uint16_t>(17, 0)));
}

TEST(UssMasterSpecial, PassesThePayloadThroughAndReturnsTheReply) {
  Bus bus(one_slave());
  bus.send();
  bus.reply(idle_reply(5));
  const Bytes payload = {0xAA, 0xBB, 0x02};
  ASSERT_TRUE(bus.master.send_special(3, false, payload, 11));
  ASSERT_TRUE(bus.master.send_special(3, true, payload, 12));
  const Sent s = bus.send();
  Bytes expected = {kStx, 5, 0x83, 0xAA, 0xBB, 0x02};
  expected.push_back(block_check(expected));
  EXPECT_EQ(s.bytes, expected);
  ASSERT_TRUE(bus.master.awaiting_reply());
  bus.reply(testing::make_telegram(0x83, Bytes{1, 2, 3, 4}));
  SpecialResult r;
  ASSERT_TRUE(bus.master.poll_special(r));
  EXPECT_EQ(r.tag, 11U);
  EXPECT_TRUE(r.answered);
  EXPECT_EQ(r.adr, 0x83);
  EXPECT_EQ(Bytes(r.data().begin(), r.data().end()), (Bytes{1, 2, 3, 4}));
  // One extra telegram after each poll: poll, then the special broadcast (bits 7 and 5).
  EXPECT_EQ(parse_adr(bus.send().bytes[2]).type, TelegramType::Normal);
  bus.reply(idle_reply(5));
  const Sent sb = bus.send();
  EXPECT_EQ(sb.bytes[2] & 0xE0, 0xA0);
  EXPECT_FALSE(bus.master.awaiting_reply());
  EXPECT_FALSE(bus.master.poll_special(r)) << "a special broadcast has no result";
}

// ---------------------------------------------------------------------------------------------
// Line errors (A 5.2.2): a character marked by the tty (termios PARMRK) rejects the telegram.

TEST(UssMasterLine, ACharacterMarkedWithAParityErrorRejectsTheReply) {
  Bus bus(one_slave());
  const Sent s = bus.send();
  Bytes raw = idle_reply(5);
  // The tty delivers the ADR byte with a parity error as 0xFF 0x00 ADR.
  raw.insert(raw.begin() + 2, {0xFF, 0x00});
  ParmrkDecoder decoder;
  std::vector<RxChar> chars(raw.size());
  chars.resize(decoder.decode(raw, chars));
  ASSERT_EQ(chars.size(), idle_reply(5).size());
  EXPECT_EQ(chars[2].error, LineError::Parity);
  MonoTime at = s.end + 1ms;
  for (const RxChar& c : chars) {
    at += bus.tz;
    bus.master.on_char(c, at);
    if (!bus.master.awaiting_reply()) break;
  }
  EXPECT_EQ(bus.master.last_outcome(), ExchangeOutcome::BadReply);
  EXPECT_EQ(bus.master.rx_counters().parity, 1U);
  EXPECT_EQ(bus.master.rx_counters().error_word & error_bit(RxError::Parity),
            error_bit(RxError::Parity));
  EXPECT_FALSE(bus.master.slave(5).responding);
}

// ---------------------------------------------------------------------------------------------
// Port handling

TEST(UssMasterLink, ResetLinkDropsTheExchangeAndRestartsTheStartPause) {
  Bus bus(one_slave());
  ASSERT_TRUE(bus.master.submit_pkw(5, read_request(52), 1));
  bus.send();
  const MonoTime lost = bus.t + 3ms;
  bus.master.reset_link(lost);
  EXPECT_FALSE(bus.master.awaiting_reply());
  EXPECT_EQ(bus.master.last_outcome(), ExchangeOutcome::Abandoned);
  EXPECT_EQ(bus.master.send_at(), lost + start_pause(38400));
  EXPECT_TRUE(bus.master.slave(5).pkw_busy);
  EXPECT_EQ(bus.master.slave(5).failures, 0U) << "a lost port is not the slave's fault";
}

TEST(UssMasterLink, AfterALostPortTheSlavesStatusWordsAreVoidUntilTheyAnswerAgain) {
  Bus bus(one_slave());
  const std::vector<std::uint16_t> out = {stw::kOn | stw::kNoOff2 | stw::kNoOff3, 0x2000};
  bus.master.set_pzd(5, out);
  bus.send();
  bus.reply(idle_reply(5, PkwLength::Three, {0x0637, 0x1FFF}));
  ASSERT_EQ(bus.master.slave(5).pzd_in_count, 2);
  ASSERT_TRUE(bus.master.slave(5).responding);
  bus.master.reset_link(bus.t + 1ms);  // the port went away and came back
  const SlaveState& s = bus.master.slave(5);
  EXPECT_EQ(s.pzd_in_count, 0) << "a status word from before the loss would still be read";
  EXPECT_EQ(s.pzd_in[0], 0);
  EXPECT_FALSE(s.responding);
  EXPECT_TRUE(s.heard) << "heard once since start stays true";
  bus.send();
  bus.reply(idle_reply(5, PkwLength::Three, {0x0237, 0}));
  EXPECT_EQ(bus.master.slave(5).pzd_in_count, 2);
  EXPECT_EQ(bus.master.slave(5).pzd_in[0], 0x0237);
}

}  // namespace
}  // namespace liftd::uss
