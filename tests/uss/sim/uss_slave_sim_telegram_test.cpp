// The simulated USS slave's telegram types, reception and timing, injected faults, and the bus.
#include "uss/sim/uss_slave_sim.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <initializer_list>
#include <optional>
#include <string>
#include <vector>

#include "uss/timing.hpp"
#include "uss_slave_sim_harness.hpp"

namespace {

// --------------------------------------------------------------- telegram types and reception

TEST(UssSlaveSim, AnswersOnlyItsOwnAddress) {
  Harness h(config(PkwLength::Four, 2));
  EXPECT_FALSE(h.exchange(telegram(4, {pke(1, 18), 0, 0, 0, 0, 0})));
  EXPECT_TRUE(h.exchange(telegram(5, {pke(1, 18), 0, 0, 0, 0, 0})));
}

TEST(UssSlaveSim, MirrorTelegramComesBackUnchanged) {
  Harness h(config(PkwLength::Four, 2));
  const Bytes m = telegram(0x40 | 5, {0x1234, 0x5678, 0x9ABC, 0xDEF0, 0x0102, 0x0304});
  const auto r = h.exchange(m);
  ASSERT_TRUE(r);
  EXPECT_EQ(hex(*r), hex(m));
  EXPECT_EQ(h.sim.stats().mirrors, 1U);
  EXPECT_FALSE(h.exchange(telegram(0x40 | 6, {0, 0, 0, 0, 0, 0})));
  EXPECT_EQ(h.sim.drive().stw, 0);  // the content is not evaluated
}

TEST(UssSlaveSim, BroadcastIsExecutedNeverAnswered) {
  Harness h(config(PkwLength::Four, 2));
  // Appendix: word a = flag + PZD1 + PZD2, word b = every STW bit.
  EXPECT_FALSE(h.exchange(telegram(0x20, {0x0007, 0xFFFF, 0, 0, 0x0406, 0x2000})));
  EXPECT_EQ(h.sim.state(), UssDriveState::ReadyToSwitchOn);
  EXPECT_EQ(h.sim.drive().hsw, 0x2000);
  // Only PZD2 enabled: the setpoint changes, STW stays.
  EXPECT_FALSE(h.exchange(telegram(0x20, {0x0005, 0, 0, 0, 0x0407, 0x1000})));
  EXPECT_EQ(h.sim.drive().stw, 0x0406);
  EXPECT_EQ(h.sim.drive().hsw, 0x1000);
  // Without the flag nothing is taken.
  EXPECT_FALSE(h.exchange(telegram(0x20, {0x0006, 0xFFFF, 0, 0, 0x0407, 0x0800})));
  EXPECT_EQ(h.sim.drive().hsw, 0x1000);
  // Bit masks: only STW bit 0 of PZD1.
  EXPECT_FALSE(h.exchange(telegram(0x20, {0x0003, 0x0001, 0, 0, 0x0401, 0})));
  EXPECT_EQ(h.sim.drive().stw, 0x0407);
  EXPECT_EQ(h.sim.state(), UssDriveState::Ready);
  EXPECT_EQ(h.sim.stats().broadcasts, 4U);
  EXPECT_EQ(h.sim.stats().replies, 0U);
}

TEST(UssSlaveSim, SpecialTelegramsEchoOrIgnore) {
  Harness h(config(PkwLength::Four, 2));
  // A fixed-length slave takes only telegrams of its length (A 5.2), specials included.
  const Bytes s = telegram(0x80 | 5, {0xCAFE, 0x0001, 2, 3, 4, 5});
  const auto r = h.exchange(s);
  ASSERT_TRUE(r);
  EXPECT_EQ(hex(*r), hex(s));
  EXPECT_FALSE(h.exchange(telegram(0xA0 | 5, {0xCAFE, 0, 0, 0, 0, 0})));  // special broadcast
  EXPECT_FALSE(h.exchange(telegram(0x80 | 6, {0xCAFE, 0, 0, 0, 0, 0})));
  EXPECT_EQ(h.sim.stats().specials, 2U);
  auto c = config(PkwLength::Four, 2);
  c.special = liftd::uss::sim::UssSpecialMode::Ignore;
  Harness ignore(c);
  EXPECT_FALSE(ignore.exchange(s));
}

TEST(UssSlaveSim, UndefinedAddressTypeNoReactionAndViolation) {
  Harness h(config(PkwLength::Four, 2));
  EXPECT_FALSE(h.exchange(telegram(0x60 | 5, {pke(1, 18), 0, 0, 0, 0x047F, 0})));
  EXPECT_FALSE(h.exchange(telegram(0xC0 | 5, {pke(1, 18), 0, 0, 0, 0x047F, 0})));
  EXPECT_EQ(h.sim.state(), UssDriveState::SwitchOnInhibit);
  const auto v = h.violations();
  ASSERT_EQ(v.size(), 2U);
  EXPECT_EQ(v[0].substr(0, 5), "A 4.3");
}

TEST(UssSlaveSim, RejectedTelegramsAreNotAnswered) {
  Harness h(config(PkwLength::Four, 2));
  Bytes bad_bcc = telegram(5, {pke(1, 18), 0, 0, 0, 0, 0});
  bad_bcc.back() ^= 0x01;
  EXPECT_FALSE(h.exchange(bad_bcc));
  EXPECT_FALSE(h.exchange(telegram(5, {pke(1, 18), 0, 0, 0, 0})));  // LGE 12 instead of 14
  h.send(telegram(5, {pke(1, 18), 0, 0, 0, 0, 0}), 5ms, 4);         // parity error on a byte
  EXPECT_FALSE(h.wait_reply());
  const auto& rx = h.sim.rx_counters();
  EXPECT_EQ(rx.bcc, 1U);
  EXPECT_EQ(rx.lge, 1U);
  EXPECT_EQ(rx.parity, 1U);
  EXPECT_TRUE(h.exchange(telegram(5, {pke(1, 18), 0, 0, 0, 0, 0})));
}

TEST(UssSlaveSim, VariableLengthRequestWithWrongPzdCountIsAViolation) {
  Harness h(config(PkwLength::Variable, 2));
  EXPECT_FALSE(h.exchange(telegram(5, {pke(1, 18), 0})));  // PKE IND only, no PZD
  EXPECT_EQ(h.violations().size(), 1U);
  EXPECT_TRUE(h.exchange(telegram(5, {pke(1, 18), 0, 0, 0, 0})));
}

TEST(UssSlaveSim, TelegramWithoutStartPauseAfterTheReplyIsDropped) {
  Harness h(config(PkwLength::Four, 2));
  ASSERT_TRUE(h.exchange(telegram(5, {pke(1, 18), 0, 0, 0, 0, 0})));
  // The reply ended at h.now; the next STX 1 character time later: no start pause (A 5.1.2).
  h.send(telegram(5, {pke(1, 18), 0, 0, 0, 0, 0}), 0ns);
  EXPECT_FALSE(h.wait_reply());
  const auto v = h.violations();
  ASSERT_EQ(v.size(), 1U);
  EXPECT_EQ(v[0].substr(0, 7), "A 5.1.2");
  // 2 character times of pause: fine.
  h.send(telegram(5, {pke(1, 18), 0, 0, 0, 0, 0}), liftd::uss::start_pause(kBaud));
  EXPECT_TRUE(h.wait_reply());
}

TEST(UssSlaveSim, TelegramBeforeTheReplyIsAViolation) {
  Harness h(config(PkwLength::Four, 2));
  h.send(telegram(5, {pke(1, 18), 0, 0, 0, 0, 0}));
  h.send(telegram(7, {pke(1, 18), 0, 0, 0, 0, 0}), 1ms);  // the reply was due after 2 ms
  EXPECT_FALSE(h.wait_reply());
  const auto v = h.violations();
  ASSERT_EQ(v.size(), 1U);
  EXPECT_EQ(v[0].substr(0, 3), "A 5");
}

// Characters reach the slave no earlier than the master sent them, but on a pseudo-terminal they
// can reach it much later: a request and the master's next telegram, sent 20 ms apart as A 5.2.1.1
// allows, may arrive together. The slave judges a timing rule only where a master keeping the
// spec's times was still bound to wait for its reply.
TEST(UssSlaveSim, TimingRulesBrokenOnlyByALateDeliveryAreCountedNotJudged) {
  Harness h(config(PkwLength::Four, 2));
  const Bytes request = telegram(5, {pke(1, 18), 0, 0, 0, 0, 0});
  ASSERT_TRUE(h.exchange(request));
  const MonoTime last_reply_end = h.now;
  // 40 ms of silence, then the request in one delivery, and the next telegram 1 ms after it
  // while the reply is pending: the master may have sent the request at once and given up on
  // the reply 20 ms later (A 5.2.1.1).
  h.now += 40ms;
  for (const auto x : request) h.sim.on_char({x, liftd::uss::LineError::None}, h.now);
  h.send(request, 1ms);
  EXPECT_TRUE(h.violations().empty());
  EXPECT_EQ(h.sim.stats().unjudged, 1U) << "A 5: telegram before the reply, not judged";
  // The second telegram is answered, late from the master's point of view; a telegram right
  // after that reply has no start pause but may come from a master that gave up on it.
  ASSERT_TRUE(h.wait_reply());
  EXPECT_GT(h.last.send_at, last_reply_end + 20ms);
  h.send(request, 0ns);
  EXPECT_FALSE(h.wait_reply());
  EXPECT_TRUE(h.violations().empty());
  EXPECT_EQ(h.sim.stats().unjudged, 2U) << "A 5.1.2: no start pause, not judged";
  EXPECT_EQ(h.sim.stats().violations, 0U);
}

TEST(UssSlaveSim, AMasterThatDoesNotWaitIsCaughtAfterEveryOnTimeReply) {
  Harness h(config(PkwLength::Four, 2));
  const Bytes request = telegram(5, {pke(1, 18), 0, 0, 0, 0, 0});
  ASSERT_TRUE(h.exchange(request));
  // A 5: the next telegram 1 ms after the request, while the reply (due after 2 ms) is pending.
  h.send(request);
  h.send(request, 1ms);
  auto v = h.violations();
  ASSERT_EQ(v.size(), 1U);
  EXPECT_EQ(v[0].substr(0, 4), "A 5:");
  ASSERT_TRUE(h.wait_reply());
  // A 5.1.2: a request 5 ms after the last reply, its reply, and the next STX straight after it
  // (about 17 ms after that last reply, before a master could give up on this one).
  ASSERT_TRUE(h.exchange(request));
  h.send(request, 0ns);
  v = h.violations();
  ASSERT_EQ(v.size(), 1U);
  EXPECT_EQ(v[0].substr(0, 7), "A 5.1.2");
  EXPECT_EQ(h.sim.stats().unjudged, 0U);
}

// ------------------------------------------------------------------------------ injected faults

TEST(UssSlaveSim, InjectedReplyFaults) {
  Harness h(config(PkwLength::Four, 2));
  const Bytes request = telegram(5, {pke(1, 18), 0, 0, 0, 0, 0});
  const auto good = h.exchange(request);
  ASSERT_TRUE(good);

  h.sim.inject(UssReplyFault::Silent, 2);
  EXPECT_FALSE(h.exchange(request));
  EXPECT_FALSE(h.exchange(request));
  EXPECT_TRUE(h.exchange(request));

  h.sim.inject(UssReplyFault::BadBcc, 1);
  auto r = h.exchange(request);
  ASSERT_TRUE(r);
  Bytes expected = *good;
  expected.back() ^= 0x01;
  EXPECT_EQ(hex(*r), hex(expected));

  h.sim.inject(UssReplyFault::BadLge, 1);
  r = h.exchange(request);
  ASSERT_TRUE(r);
  EXPECT_EQ((*r)[1], (*good)[1] + 1);
  std::uint8_t bcc = 0;
  for (std::size_t i = 0; i + 1 < r->size(); ++i) bcc ^= (*r)[i];
  EXPECT_EQ(bcc, r->back());

  h.sim.inject(UssReplyFault::Parity, 1);
  r = h.exchange(request);
  ASSERT_TRUE(r);
  EXPECT_EQ(hex(*r), hex(*good));
  EXPECT_EQ(h.last.parity_error_at, 2);

  h.sim.inject(UssReplyFault::Late, 1);
  r = h.exchange(request);
  ASSERT_TRUE(r);
  EXPECT_EQ(h.last.send_at - h.request_end, 25ms);
  EXPECT_EQ(h.sim.stats().faulted_replies, 6U);
  EXPECT_TRUE(h.violations().empty());  // the master repeated its request throughout
}

TEST(UssSlaveSim, StaleReplyAnswersThePreviousRequestOnce) {
  Harness h(config(PkwLength::Four, 0));
  EXPECT_EQ(h.words(5, {pke(1, 18), 0, 0, 0}), (Words{pke(1, 18), 0, 0, 0x0100}));
  h.sim.inject(UssReplyFault::Stale, 1);
  EXPECT_EQ(h.words(5, {pke(1, 52), 0, 0, 0}), (Words{pke(1, 18), 0, 0, 0x0100}));
  EXPECT_EQ(h.words(5, {pke(1, 52), 0, 0, 0}), (Words{pke(1, 52), 0, 0, 0x4000}));
  EXPECT_TRUE(h.violations().empty());
}

TEST(UssSlaveSim, ChangingTheRequestBeforeItsAnswerIsAViolation) {
  Harness h(config(PkwLength::Four, 0));
  h.sim.inject(UssReplyFault::Silent, 1);
  EXPECT_FALSE(h.exchange(telegram(5, {pke(1, 18), 0, 0, 0})));
  EXPECT_TRUE(h.exchange(telegram(5, {pke(1, 52), 0, 0, 0})));
  auto v = h.violations();
  ASSERT_EQ(v.size(), 1U);
  EXPECT_EQ(v[0].substr(0, 9), "C 4.2.1.1");
  // After the give-up count of unanswered repeats a change is the master's own reaction.
  auto c = config(PkwLength::Four, 0);
  c.pkw_give_up_repeats = 2;
  Harness g(c);
  g.sim.inject(UssReplyFault::Silent, 3);
  for (int i = 0; i < 3; ++i) EXPECT_FALSE(g.exchange(telegram(5, {pke(1, 18), 0, 0, 0})));
  EXPECT_TRUE(g.exchange(telegram(5, {pke(1, 52), 0, 0, 0})));
  EXPECT_TRUE(g.violations().empty());
}

TEST(UssSlaveSim, IndexBitsTheMasterMustLeaveZero) {
  Harness h(config(PkwLength::Four, 0));
  h.words(5, {pke(1, 18), 0x0001, 0, 0});   // IND bits 0..9 for a request without index
  h.words(5, {pke(6, 683), 0x0401, 0, 0});  // device bits 10..15
  h.words(5, {pke(2, 18), 0, 1, 5});        // word value with PWE1 != 0
  const auto v = h.violations();
  ASSERT_EQ(v.size(), 3U);
  EXPECT_EQ(v[0].substr(0, 5), "C 4.2");
  EXPECT_EQ(v[1].substr(0, 5), "C 4.2");
  EXPECT_EQ(v[2].substr(0, 7), "C 4.2.3");
}

// ------------------------------------------------------------------------------------- the bus

TEST(UssBusSim, RoutesByAddressAndRejectsDuplicates) {
  std::vector<UssSlaveConfig> slaves = {config(PkwLength::Four, 2, 1),
                                        config(PkwLength::Three, 2, 3)};
  liftd::uss::sim::UssBusSim bus(slaves, kBaud, MonoTime{1s});
  MonoTime now{2s};
  auto send = [&](const Bytes& b) {
    now += 5ms;
    for (const auto x : b) {
      now += liftd::uss::character_time(kBaud);
      bus.on_char({x, liftd::uss::LineError::None}, now);
    }
    UssReply r;
    for (int i = 0; i < 600; ++i) {
      now += 50us;
      bus.on_time(now);
      if (bus.take_reply(now, r)) {
        now = r.send_at + liftd::uss::transmission_time(kBaud, r.size);
        return std::optional<UssReply>(r);
      }
    }
    return std::optional<UssReply>();
  };
  auto r = send(telegram(1, {pke(1, 18), 0, 0, 0, 0, 0}));
  ASSERT_TRUE(r);
  EXPECT_EQ(r->address, 1);
  r = send(telegram(3, {pke(1, 18), 0, 0, 0, 0}));
  ASSERT_TRUE(r);
  EXPECT_EQ(r->address, 3);
  EXPECT_EQ(r->size, 14U);
  EXPECT_FALSE(send(telegram(2, {pke(1, 18), 0, 0, 0, 0})));
  EXPECT_FALSE(send(telegram(0x20, {1, 0xFFFF, 0, 0, 0x0406, 0})));  // broadcast
  EXPECT_EQ(bus.slave(1)->state(), UssDriveState::SwitchOnInhibit);  // flag without PZD1 bit
  EXPECT_EQ(bus.slave(3)->stats().broadcasts, 0U);  // 3-word PKW: other LGE, rejected
  slaves.push_back(config(PkwLength::Four, 2, 1));
  EXPECT_THROW(liftd::uss::sim::UssBusSim(slaves, kBaud, MonoTime{}), std::invalid_argument);
}

}  // namespace
