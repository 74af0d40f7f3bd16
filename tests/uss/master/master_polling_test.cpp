// The USS master's polling list and link state, mirror, broadcast, special telegrams and the line.
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
