// The USS receive side (A 5.2): start pause + STX, LGE, residual time with a fake clock at the
// exact boundary, BCC, character errors, counters and error word (A 5.2.3), what happens to the
// bytes after a rejection, telegrams back to back. 11000 baud makes a character exactly 1 ms.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "support/heap_hooks.hpp"
#include "uss/receiver.hpp"

namespace liftd::uss {
namespace {

using namespace std::chrono_literals;
using Kind = RxResult::Kind;

constexpr std::uint32_t kBaud = 11000;  // tz = 1 ms, start pause 2 ms (A 6.1, A 5.1.2)
constexpr MonoTime kT0 = 1s;

// Example 2 of C 8.1 (read P52, 3 PKW words, 2 PZD words) to slave 1; BCC by hand:
// 02^0C=0E ^01=0F ^10=1F ^34=2B ^00 ^00 ^00 ^00 =2B ^04=2F ^7F=50 ^20=70 ^00=70.
const std::vector<std::uint8_t> kGood{0x02, 0x0C, 0x01, 0x10, 0x34, 0x00, 0x00,
                                      0x00, 0x00, 0x04, 0x7F, 0x20, 0x00, 0x70};

struct Fed {
  std::vector<RxResult> results;
  MonoTime next;  // stamp after the last character + 1 tz
};

// Feeds bytes one character time apart, the first stamped `at`.
Fed feed_all(Receiver& rx, const std::vector<std::uint8_t>& bytes, MonoTime at,
             std::chrono::nanoseconds step = 1ms) {
  Fed fed{{}, at};
  for (std::uint8_t b : bytes) {
    fed.results.push_back(rx.feed(RxChar{b, LineError::None}, fed.next));
    fed.next += step;
  }
  return fed;
}

std::chrono::milliseconds ms(std::size_t i) {
  return std::chrono::milliseconds(static_cast<std::int64_t>(i));
}

std::uint64_t reasons(const RxCounters& c) {
  return c.framing + c.overrun + c.parity + c.no_stx + c.residual_time + c.bcc + c.lge;
}

TEST(UssReceiver, GoodTelegramVariableLength) {
  Receiver rx(kBaud);
  const Fed fed = feed_all(rx, kGood, kT0);
  for (std::size_t i = 0; i + 1 < fed.results.size(); ++i) {
    EXPECT_EQ(fed.results[i].kind, Kind::Pending) << i;
  }
  EXPECT_EQ(fed.results.back().kind, Kind::Complete);
  const Telegram t = rx.telegram();
  EXPECT_EQ(t.adr, 0x01);
  ASSERT_EQ(t.payload.size(), 10U);
  EXPECT_EQ(t.payload[0], 0x10);
  EXPECT_EQ(t.payload[9], 0x00);
  EXPECT_EQ(std::vector<std::uint8_t>(rx.bytes().begin(), rx.bytes().end()), kGood);
  EXPECT_EQ(rx.counters().good, 1U);
  EXPECT_EQ(rx.counters().rejected, 0U);
  EXPECT_EQ(rx.counters().error_word, 0);
  EXPECT_FALSE(rx.receiving());
}

TEST(UssReceiver, FixedLengthAccepted) {
  Receiver rx(kBaud);
  rx.set_expected_lge(12);
  EXPECT_EQ(feed_all(rx, kGood, kT0).results.back().kind, Kind::Complete);
}

// One rejection per A 5.2.2 error (and A 5.2.3 bit): which character ends the telegram, which
// counter counts it.
TEST(UssReceiver, EachErrorRejectedAndCounted) {
  struct Case {
    std::string name;
    std::uint8_t expected_lge;
    std::vector<RxChar> chars;  // 1 ms apart from kT0
    std::size_t rejected_at;    // index of the character whose feed() returns Rejected
    RxError error;
    std::uint64_t RxCounters::*counter;
  };
  auto with = [](std::vector<std::uint8_t> bytes, std::size_t i, LineError e) {
    std::vector<RxChar> out;
    for (std::uint8_t b : bytes) out.push_back(RxChar{b, LineError::None});
    out[i].error = e;
    return out;
  };
  auto plain = [&with](std::vector<std::uint8_t> bytes) {
    return with(std::move(bytes), 0, LineError::None);
  };
  std::vector<std::uint8_t> bad_bcc = kGood;
  bad_bcc.back() ^= 0x01;
  const std::vector<Case> cases{
      {"parity in payload", 0, with(kGood, 5, LineError::Parity), 5, RxError::Parity,
       &RxCounters::parity},
      {"framing in ADR", 0, with(kGood, 2, LineError::Framing), 2, RxError::Framing,
       &RxCounters::framing},
      {"break counts as framing", 0, with(kGood, 7, LineError::Break), 7, RxError::Framing,
       &RxCounters::framing},
      {"overrun in BCC", 0, with(kGood, 13, LineError::Overrun), 13, RxError::Overrun,
       &RxCounters::overrun},
      {"parity in LGE", 0, with(kGood, 1, LineError::Parity), 1, RxError::Parity,
       &RxCounters::parity},
      {"parity on first character", 0, with(kGood, 0, LineError::Parity), 0, RxError::Parity,
       &RxCounters::parity},
      {"wrong BCC", 0, plain(bad_bcc), 13, RxError::Bcc, &RxCounters::bcc},
      {"fixed LGE differs", 10, plain(kGood), 1, RxError::Lge, &RxCounters::lge},
      {"fixed LGE 1 never matches", 1, plain({0x02, 0x01, 0x01, 0x00}), 1, RxError::Lge,
       &RxCounters::lge},
      {"variable LGE 0", 0, plain({0x02, 0x00, 0x01}), 1, RxError::Lge, &RxCounters::lge},
      {"variable LGE 1", 0, plain({0x02, 0x01, 0x01}), 1, RxError::Lge, &RxCounters::lge},
      {"variable LGE 255", 0, plain({0x02, 0xFF, 0x01}), 1, RxError::Lge, &RxCounters::lge},
      {"first character no STX", 0, plain({0x03, 0x0C, 0x01}), 0, RxError::NoStx,
       &RxCounters::no_stx},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    Receiver rx(kBaud);
    rx.set_expected_lge(c.expected_lge);
    MonoTime at = kT0;
    for (std::size_t i = 0; i < c.chars.size(); ++i, at += 1ms) {
      const RxResult r = rx.feed(c.chars[i], at);
      if (i == c.rejected_at) {
        EXPECT_EQ(r, (RxResult{Kind::Rejected, c.error})) << i;
      } else {
        EXPECT_EQ(r.kind, Kind::Pending) << i;  // the rest of the telegram is ignored
      }
    }
    const RxCounters& n = rx.counters();
    EXPECT_EQ(n.*(c.counter), 1U);
    EXPECT_EQ(n.rejected, 1U);
    EXPECT_EQ(reasons(n), 1U);
    EXPECT_EQ(n.good, 0U);
    EXPECT_EQ(n.error_word, error_bit(c.error));
    EXPECT_FALSE(rx.receiving());
    // The next telegram after a start pause is taken.
    rx.set_expected_lge(0);
    EXPECT_EQ(feed_all(rx, kGood, at + 2ms).results.back().kind, Kind::Complete);
    EXPECT_EQ(rx.counters().good, 1U);
  }
}

TEST(UssReceiver, ErrorWordBitsAreThoseOfA523) {
  EXPECT_EQ(error_bit(RxError::Framing), 0x01);
  EXPECT_EQ(error_bit(RxError::Overrun), 0x02);
  EXPECT_EQ(error_bit(RxError::Parity), 0x04);
  EXPECT_EQ(error_bit(RxError::NoStx), 0x08);
  EXPECT_EQ(error_bit(RxError::Bcc), 0x10);
  EXPECT_EQ(error_bit(RxError::ResidualTime), 0x20);
  EXPECT_EQ(error_bit(RxError::Lge), 0x40);
  EXPECT_EQ(error_bit(RxError::ReplyTimeout), 0x80);
  for (int e = 0; e <= 7; ++e) EXPECT_NE(to_string(static_cast<RxError>(e)), "?");
}

TEST(UssReceiver, ResidualTimeExactBoundaryFixedLength) {
  // Fixed LGE 12: n = 10, max residual 1.5 * 13 tz = 19.5 ms from the STX (A 6.3), loaded at STX
  // (A 5.2.1.2). 13 more characters follow the STX.
  for (const auto& [last_at, kind] :
       {std::pair{kT0 + 19500us, Kind::Complete}, std::pair{kT0 + 19500us + 1ns, Kind::Rejected}}) {
    Receiver rx(kBaud);
    rx.set_expected_lge(12);
    EXPECT_EQ(rx.feed({0x02}, kT0).kind, Kind::Pending);
    ASSERT_TRUE(rx.deadline());
    EXPECT_EQ(*rx.deadline(), kT0 + 19500us + 1ns);  // first late instant
    for (std::size_t i = 1; i + 1 < kGood.size(); ++i) {
      EXPECT_EQ(rx.feed({kGood[i]}, kT0 + ms(i)).kind, Kind::Pending);
    }
    const RxResult r = rx.feed({kGood.back()}, last_at);
    EXPECT_EQ(r.kind, kind);
    if (kind == Kind::Rejected) {
      EXPECT_EQ(r.error, RxError::ResidualTime);
      EXPECT_EQ(rx.counters().residual_time, 1U);
      EXPECT_EQ(rx.counters().error_word, error_bit(RxError::ResidualTime));
    }
  }
}

TEST(UssReceiver, ResidualTimeVariableLengthReloadedAtLge) {
  Receiver rx(kBaud);
  EXPECT_EQ(rx.feed({0x02}, kT0).kind, Kind::Pending);
  // A 5.2.1.2: at STX the value for 252 payload characters: 1.5 * 255 tz = 382.5 ms.
  EXPECT_EQ(*rx.deadline(), kT0 + 382500us + 1ns);
  EXPECT_EQ(rx.feed({0x0C}, kT0 + 1ms).kind, Kind::Pending);
  // After LGE 12 (n = 10): 19.5 ms.
  EXPECT_EQ(*rx.deadline(), kT0 + 19500us + 1ns);
  EXPECT_EQ(rx.check_time(kT0 + 19500us).kind, Kind::Pending);
  EXPECT_EQ(rx.check_time(kT0 + 19500us + 1ns), (RxResult{Kind::Rejected, RxError::ResidualTime}));
  EXPECT_FALSE(rx.deadline());
  EXPECT_EQ(rx.counters().residual_time, 1U);
  // The rest of the late telegram follows after more than a start pause: it is a new burst that
  // does not begin with STX, counted once as NoStx, not once per character.
  for (std::size_t i = 2; i < kGood.size(); ++i) {
    const RxResult r = rx.feed({kGood[i]}, kT0 + 20ms + ms(i));
    EXPECT_EQ(r.kind, i == 2 ? Kind::Rejected : Kind::Pending) << i;
  }
  EXPECT_EQ(rx.counters().rejected, 2U);
  EXPECT_EQ(rx.counters().no_stx, 1U);
  EXPECT_EQ(rx.check_time(kT0 + 1h).kind, Kind::Pending);  // nothing in progress
}

TEST(UssReceiver, ResidualTimeAt38400Baud) {
  // 38400 baud, LGE 12: 1.5 * 13 * 11 / 38400 s = 5 585 937.5 ns, rounded up.
  Receiver rx(38400);
  (void)rx.feed({0x02}, kT0);
  (void)rx.feed({0x0C}, kT0 + 286us);
  EXPECT_EQ(*rx.deadline(), kT0 + 5585938ns + 1ns);
}

TEST(UssReceiver, LateCharacterAfterPauseStartsNextTelegram) {
  Receiver rx(kBaud);
  // A telegram that stops after ADR, then (after the deadline and a pause) a new STX.
  (void)feed_all(rx, {0x02, 0x0C, 0x01}, kT0);
  const RxResult late = rx.feed({0x02}, kT0 + 40ms);
  EXPECT_EQ(late, (RxResult{Kind::Rejected, RxError::ResidualTime}));
  EXPECT_TRUE(rx.receiving());
  MonoTime at = kT0 + 41ms;
  RxResult last;
  for (std::size_t i = 1; i < kGood.size(); ++i, at += 1ms) last = rx.feed({kGood[i]}, at);
  EXPECT_EQ(last.kind, Kind::Complete);
  EXPECT_EQ(rx.counters().rejected, 1U);
  EXPECT_EQ(rx.counters().good, 1U);
}

TEST(UssReceiver, BytesAfterRejectionIgnoredUntilStartPause) {
  Receiver rx(kBaud);
  // Bad LGE: the remaining bytes (including STX values) arrive without a pause and are part of
  // the rejected telegram: no new start, no further count.
  std::vector<std::uint8_t> stream{0x02, 0xFF, 0x02, 0x0C, 0x01, 0x02, 0x06};
  const Fed fed = feed_all(rx, stream, kT0);
  EXPECT_EQ(fed.results[1], (RxResult{Kind::Rejected, RxError::Lge}));
  for (std::size_t i = 2; i < fed.results.size(); ++i)
    EXPECT_EQ(fed.results[i].kind, Kind::Pending);
  EXPECT_FALSE(rx.receiving());
  EXPECT_EQ(rx.counters().rejected, 1U);
  // A whole good telegram right after (gap 1 tz, no pause) is still not taken...
  const Fed glued = feed_all(rx, kGood, fed.next);
  for (const RxResult& r : glued.results) EXPECT_EQ(r.kind, Kind::Pending);
  EXPECT_EQ(rx.counters().good, 0U);
  EXPECT_EQ(rx.counters().rejected, 1U);
  // ...but after a start pause it is.
  EXPECT_EQ(feed_all(rx, kGood, glued.next - 1ms + 2ms).results.back().kind, Kind::Complete);
  EXPECT_EQ(rx.counters().good, 1U);
}

TEST(UssReceiver, BackToBackTelegrams) {
  // Stamp gap from the last BCC to the next STX: start pause (2 tz) is enough; 1 ns less is not
  // a telegram start ("Erst ein STX mit vorangegangener Startpause", A 5.1.2).
  {
    Receiver rx(kBaud);
    MonoTime at = kT0;
    for (int i = 0; i < 3; ++i) {
      const Fed fed = feed_all(rx, kGood, at);
      EXPECT_EQ(fed.results.back().kind, Kind::Complete) << i;
      at = fed.next - 1ms + 2ms;
    }
    EXPECT_EQ(rx.counters().good, 3U);
    EXPECT_EQ(rx.counters().rejected, 0U);
  }
  {
    Receiver rx(kBaud);
    const Fed first = feed_all(rx, kGood, kT0);
    EXPECT_EQ(first.results.back().kind, Kind::Complete);
    const Fed second = feed_all(rx, kGood, first.next - 1ms + 2ms - 1ns);
    EXPECT_EQ(second.results[0], (RxResult{Kind::Rejected, RxError::NoStx}));
    for (std::size_t i = 1; i < second.results.size(); ++i) {
      EXPECT_EQ(second.results[i].kind, Kind::Pending);
    }
    EXPECT_EQ(rx.counters().good, 1U);
    EXPECT_EQ(rx.counters().no_stx, 1U);
    EXPECT_EQ(rx.counters().rejected, 1U);
  }
  {
    // Without the start-pause check, telegrams may follow each other directly.
    Receiver rx(kBaud);
    rx.set_start_pause_check(false);
    std::vector<std::uint8_t> two = kGood;
    two.insert(two.end(), kGood.begin(), kGood.end());
    const Fed fed = feed_all(rx, two, kT0);
    EXPECT_EQ(fed.results[13].kind, Kind::Complete);
    EXPECT_EQ(fed.results[27].kind, Kind::Complete);
    EXPECT_EQ(rx.counters().good, 2U);
  }
}

TEST(UssReceiver, GarbageBurstCountedOnce) {
  Receiver rx(kBaud);
  const Fed fed = feed_all(rx, {0x55, 0x02, 0x0C, 0x66, 0x02}, kT0);
  EXPECT_EQ(fed.results[0], (RxResult{Kind::Rejected, RxError::NoStx}));
  EXPECT_EQ(rx.counters().no_stx, 1U);
  EXPECT_EQ(rx.counters().rejected, 1U);
  // A second burst after a pause is counted again.
  (void)feed_all(rx, {0x55, 0x55}, fed.next + 5ms);
  EXPECT_EQ(rx.counters().no_stx, 2U);
}

TEST(UssReceiver, RestartDropsTelegramAndTrustsNextStx) {
  Receiver rx(kBaud);
  (void)feed_all(rx, {0x02, 0x0C, 0x01, 0x10}, kT0);
  EXPECT_TRUE(rx.receiving());
  rx.restart();
  EXPECT_FALSE(rx.receiving());
  EXPECT_FALSE(rx.deadline());
  // The next STX is taken even 1 us after the last character.
  EXPECT_EQ(feed_all(rx, kGood, kT0 + 4ms + 1us).results.back().kind, Kind::Complete);
  EXPECT_EQ(rx.counters().rejected, 0U);
  EXPECT_EQ(rx.counters().good, 1U);
}

TEST(UssReceiver, ReplyTimeoutIsNoRejectedTelegram) {
  Receiver rx(kBaud);
  rx.count_reply_timeout();
  rx.count_reply_timeout();
  EXPECT_EQ(rx.counters().reply_timeout, 2U);
  EXPECT_EQ(rx.counters().rejected, 0U);
  EXPECT_EQ(rx.counters().error_word, 0x80);
  rx.clear_error_word();
  EXPECT_EQ(rx.counters().error_word, 0);
  EXPECT_EQ(rx.counters().reply_timeout, 2U);
  rx.reset_counters();
  EXPECT_EQ(rx.counters(), RxCounters{});
}

TEST(UssReceiver, TelegramSurvivesNextTelegramInProgress) {
  Receiver rx(kBaud);
  const Fed fed = feed_all(rx, kGood, kT0);
  (void)feed_all(rx, {0x02, 0x06, 0x09}, fed.next + 2ms);
  EXPECT_EQ(rx.telegram().adr, 0x01);
  EXPECT_EQ(rx.telegram().payload.size(), 10U);
}

TEST(UssReceiver, LongestTelegram) {
  // A 4.2: 252 payload bytes, LGE 254, 256 bytes in all.
  std::vector<std::uint8_t> t{0x02, 0xFE, 0x00};
  t.insert(t.end(), 252, 0xAA);
  t.push_back(0xFC);  // 02 ^ FE ^ 00 ^ (AA an even number of times) = FC
  Receiver rx(kBaud);
  const Fed fed = feed_all(rx, t, kT0, 100us);
  EXPECT_EQ(fed.results.back().kind, Kind::Complete);
  EXPECT_EQ(rx.telegram().payload.size(), 252U);
}

TEST(UssReceiver, NoAllocationWhileReceiving) {
  if (!LIFTD_HEAP_HOOKS) GTEST_SKIP() << "heap hooks are off under sanitizers";
  Receiver rx(kBaud);
  MonoTime at = kT0;
  heap_hooks::reset();
  heap_hooks::counting = true;
  for (int i = 0; i < 100; ++i) {
    for (std::uint8_t b : kGood) {
      (void)rx.feed(RxChar{b, LineError::None}, at);
      at += 1ms;
    }
    (void)rx.feed(RxChar{0x00, LineError::Parity}, at);
    (void)rx.check_time(at + 1s);
    at += 3ms;
  }
  heap_hooks::counting = false;
  EXPECT_EQ(heap_hooks::calls(), 0U);
  EXPECT_EQ(rx.counters().good, 100U);
}

}  // namespace
}  // namespace liftd::uss
