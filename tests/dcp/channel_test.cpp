// The communication channel byte stream (DCP 5.3 to 5.10): framing, resets, both 1 s timeouts,
// and the two-bytes-per-cycle transmitter. Time comes from a fake clock.
#include "dcp/channel.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "dcp/dcp_test_util.hpp"

namespace liftd::dcp {
namespace {

using namespace std::chrono_literals;
using test::bytes;
constexpr std::uint8_t STX = 0x02;
constexpr std::uint8_t ETX = 0x03;

// Feeds bytes two per 15 ms cycle starting at `start`; returns every status in order.
struct Fed {
  std::vector<ParseStatus> statuses;
  MonoTime end{};
};
Fed feed_cycles(ChannelParser& parser, const std::vector<std::uint8_t>& in, MonoTime start) {
  Fed out;
  MonoTime t = start;
  for (std::size_t i = 0; i < in.size(); ++i) {
    t = start + 15ms * static_cast<long>(i / 2);  // DCP 5.3: two channel bytes per cycle
    out.statuses.push_back(parser.feed(in[i], t));
  }
  out.end = t;
  return out;
}

std::vector<std::uint8_t> frame_bytes(std::uint8_t mode, std::string_view payload) {
  std::vector<std::uint8_t> v;
  v.reserve(payload.size() + 3);
  v.push_back(STX);
  v.push_back(mode);
  for (char c : payload) v.push_back(static_cast<std::uint8_t>(c));
  v.push_back(ETX);
  return v;
}

TEST(DcpChannelParser, CompletesAnExpandedFrameAtEtx) {
  ChannelParser parser;
  const auto fed = feed_cycles(parser, frame_bytes(0x1C, "I3"), 0ms);
  ASSERT_EQ(fed.statuses.size(), 5U);
  for (std::size_t i = 0; i + 1 < fed.statuses.size(); ++i) {
    EXPECT_EQ(fed.statuses[i], ParseStatus::NeedMore) << i;
  }
  EXPECT_EQ(fed.statuses.back(), ParseStatus::Complete);
  EXPECT_EQ(parser.frame().mode, ChannelMode::Expanded);
  EXPECT_EQ(
      std::vector<std::uint8_t>(parser.frame().payload().begin(), parser.frame().payload().end()),
      bytes("I3"));
  EXPECT_FALSE(parser.in_frame());
}

TEST(DcpChannelParser, IdleBytesBetweenFramesAreNothing) {
  ChannelParser parser;
  for (int i = 0; i < 50; ++i) EXPECT_EQ(parser.feed(0x00, 15ms * i), ParseStatus::NeedMore);
}

TEST(DcpChannelParser, SkipsIdleFillInTextFramesButKeepsKeypadNone) {
  ChannelParser parser;
  // Expanded frame with 0x00 fill between characters: the fill carries nothing.
  const std::vector<std::uint8_t> expanded{STX, 0x00, 0x1C, 'I', 0x00, '8', ETX};
  EXPECT_EQ(feed_cycles(parser, expanded, 0ms).statuses.back(), ParseStatus::Complete);
  EXPECT_EQ(parser.frame().length, 2U);
  // Keypad "no button" (DCP 5.6.3) is the byte 0x00 inside STX 1F ... ETX.
  const std::vector<std::uint8_t> keypad{STX, 0x1F, 0x00, ETX};
  EXPECT_EQ(feed_cycles(parser, keypad, 100ms).statuses.back(), ParseStatus::Complete);
  EXPECT_EQ(parser.frame().mode, ChannelMode::Remote);
  ASSERT_EQ(parser.frame().length, 1U);
  EXPECT_EQ(parser.frame().data[0], 0x00);
}

TEST(DcpChannelParser, StxEtxResetsTheChannel) {
  ChannelParser parser;
  EXPECT_EQ(parser.feed(STX, 0ms), ParseStatus::NeedMore);
  EXPECT_EQ(parser.feed(ETX, 0ms), ParseStatus::Reset);
  EXPECT_EQ(parser.reset_reason(), ChannelReset::StxEtx);
  EXPECT_FALSE(parser.in_frame());
}

TEST(DcpChannelParser, RejectsMalformedStreamsWithAReason) {
  // Legend: what is wrong -> bytes fed -> index of the byte that is reported Bad -> reason.
  struct Case {
    const char* what;
    std::vector<std::uint8_t> in;
    std::size_t bad_at;
    ChannelError error;
  };
  std::vector<std::uint8_t> overflow{STX, 0x1F};
  overflow.insert(overflow.end(), kMaxChannelPayload + 1, 'A');
  overflow.push_back(ETX);
  const std::vector<Case> cases = {
      {"data character between frames", {0x00, 'A'}, 1, ChannelError::DataOutsideFrame},
      {"ETX between frames", {ETX}, 0, ChannelError::DataOutsideFrame},
      {"line control byte between frames", {0x04}, 0, ChannelError::DataOutsideFrame},
      {"STX then a data character", {STX, 'I', '3', ETX}, 1, ChannelError::MissingMode},
      {"STX then the reserved mode 0x1D", {STX, 0x1D, 'x', ETX}, 1, ChannelError::ReservedMode},
      {"STX then 0x05 (no mode)", {STX, 0x05, ETX}, 1, ChannelError::UnknownMode},
      {"STX then 0x01", {STX, 0x01, ETX}, 1, ChannelError::UnknownMode},
      {"one byte more than the limit", overflow, kMaxChannelPayload + 2, ChannelError::Overflow},
      {"new STX before ETX",
       {STX, 0x1F, 0x04, 'A', STX, 0x1F, 'B', ETX},
       4,
       ChannelError::StxInFrame},
  };
  for (const auto& c : cases) {
    ChannelParser parser;
    const auto fed = feed_cycles(parser, c.in, 0ms);
    for (std::size_t i = 0; i < fed.statuses.size(); ++i) {
      if (i == c.bad_at) {
        EXPECT_EQ(fed.statuses[i], ParseStatus::Bad) << c.what;
      } else {
        EXPECT_NE(fed.statuses[i], ParseStatus::Bad) << c.what << " byte " << i;
      }
    }
    // Feed the case again up to the bad byte to read its reason.
    ChannelParser again;
    ParseStatus last = ParseStatus::NeedMore;
    for (std::size_t i = 0; i <= c.bad_at; ++i) last = again.feed(c.in[i], 0ms);
    EXPECT_EQ(last, ParseStatus::Bad) << c.what;
    EXPECT_EQ(again.error(), c.error) << c.what << ": got " << to_string(again.error());
  }
}

TEST(DcpChannelParser, RecoversAfterABadFrame) {
  ChannelParser parser;
  std::vector<std::uint8_t> in{STX, 'x', 'y', ETX};
  const auto good = frame_bytes(0x1E, "E12");
  in.insert(in.end(), good.begin(), good.end());
  const auto fed = feed_cycles(parser, in, 0ms);
  EXPECT_EQ(fed.statuses[1], ParseStatus::Bad);
  EXPECT_EQ(fed.statuses.back(), ParseStatus::Complete);
  EXPECT_EQ(parser.frame().mode, ChannelMode::DriveError);
}

TEST(DcpChannelParser, NewStxInADisplayStreamNamesTheDroppedMode) {
  // DCP 5.7: another STX before ETX: the display is to be cleared and the stream restarts.
  ChannelParser parser;
  const std::vector<std::uint8_t> in{STX, 0x1F, 0x04, 0x08, 'A', STX, 0x1F, 0x05, 'B', ETX};
  std::vector<ParseStatus> seen;
  for (std::size_t i = 0; i < in.size(); ++i) {
    seen.push_back(parser.feed(in[i], 0ms));
    if (i == 5) {
      EXPECT_EQ(seen.back(), ParseStatus::Bad);
      EXPECT_EQ(parser.error(), ChannelError::StxInFrame);
      EXPECT_EQ(parser.dropped_mode(), ChannelMode::Remote);
    }
  }
  EXPECT_EQ(seen.back(), ParseStatus::Complete);
  EXPECT_EQ(parser.frame().length, 2U);  // 0x05 'B'
}

TEST(DcpChannelParser, AcceptsTheLongestFrameInsideOneSecond) {
  // 131 payload bytes + STX + mode + ETX = 134 bytes = 67 cycles: ETX arrives at 990 ms.
  ChannelParser parser;
  std::vector<std::uint8_t> in{STX, 0x1F};
  in.insert(in.end(), kMaxChannelPayload, 'A');
  in.push_back(ETX);
  const auto fed = feed_cycles(parser, in, 0ms);
  EXPECT_EQ(fed.end, 990ms);
  EXPECT_EQ(fed.statuses.back(), ParseStatus::Complete);
  EXPECT_EQ(parser.frame().length, kMaxChannelPayload);
}

TEST(DcpChannelParser, ResetsOneSecondAfterStxWithoutEtx) {
  // DCP 5.4: no ETX within 1 s of STX.
  ChannelParser parser;
  EXPECT_EQ(parser.feed(STX, 0ms), ParseStatus::NeedMore);
  EXPECT_EQ(parser.feed(0x1C, 0ms), ParseStatus::NeedMore);
  EXPECT_EQ(parser.feed('I', 15ms), ParseStatus::NeedMore);
  // The peer keeps exchanging idle fill, so the idle timer never runs out...
  for (int cycle = 2; cycle * 15 < 1000; ++cycle) {
    EXPECT_EQ(parser.feed(0x00, 15ms * cycle), ParseStatus::NeedMore) << cycle;
  }
  // ...but the frame timer does, at exactly 1000 ms after STX.
  EXPECT_EQ(parser.poll(999ms), ParseStatus::NeedMore);
  EXPECT_EQ(parser.poll(1000ms), ParseStatus::Reset);
  EXPECT_EQ(parser.reset_reason(), ChannelReset::FrameTimeout);
  EXPECT_EQ(parser.dropped_mode(), ChannelMode::Expanded);
  EXPECT_FALSE(parser.in_frame());
  // The old frame's ETX now is a stray byte.
  EXPECT_EQ(parser.feed(ETX, 1005ms), ParseStatus::Bad);
}

TEST(DcpChannelParser, FrameTimeoutAlsoFiresInsideFeed) {
  ChannelParser parser;
  parser.feed(STX, 0ms);
  parser.feed(0x1F, 0ms);
  parser.feed('A', 500ms);
  // The next byte comes too late: the reset is reported, the byte belongs to no frame.
  EXPECT_EQ(parser.feed('B', 1000ms), ParseStatus::Reset);
  EXPECT_EQ(parser.reset_reason(), ChannelReset::FrameTimeout);
}

TEST(DcpChannelParser, ResetsOnceAfterOneSecondWithoutExchange) {
  // DCP 5.4: no exchange for 1 s.
  ChannelParser parser;
  parser.feed(0x00, 0ms);
  EXPECT_EQ(parser.poll(999ms), ParseStatus::NeedMore);
  EXPECT_EQ(parser.poll(1000ms), ParseStatus::Reset);
  EXPECT_EQ(parser.reset_reason(), ChannelReset::IdleTimeout);
  EXPECT_EQ(parser.poll(1500ms), ParseStatus::NeedMore);  // reported once per silence
  parser.feed(0x00, 1600ms);
  EXPECT_EQ(parser.poll(2599ms), ParseStatus::NeedMore);
  EXPECT_EQ(parser.poll(2600ms), ParseStatus::Reset);
}

TEST(DcpChannelParser, IdleTimeoutDropsAHalfFrame) {
  ChannelParser parser;
  parser.feed(STX, 0ms);
  parser.feed(0x1E, 0ms);
  parser.feed('E', 10ms);
  EXPECT_EQ(parser.poll(1010ms), ParseStatus::Reset);
  EXPECT_FALSE(parser.in_frame());
}

TEST(DcpChannelTransmitter, SendsTwoBytesPerCyclePaddedWithIdle) {
  ChannelTransmitter tx;
  EXPECT_FALSE(tx.busy());
  EXPECT_EQ(tx.next_pair(), (ChannelPair{0x00, 0x00}));
  ASSERT_TRUE(tx.start(ChannelMode::Expanded, bytes("I3")));
  EXPECT_TRUE(tx.busy());
  EXPECT_EQ(tx.next_pair(), (ChannelPair{STX, 0x1C}));
  EXPECT_EQ(tx.next_pair(), (ChannelPair{'I', '3'}));
  EXPECT_TRUE(tx.busy());
  EXPECT_EQ(tx.next_pair(), (ChannelPair{ETX, 0x00}));  // odd length: ETX padded with idle
  EXPECT_FALSE(tx.busy());
  EXPECT_EQ(tx.next_pair(), (ChannelPair{0x00, 0x00}));
}

TEST(DcpChannelTransmitter, EvenLengthFrameEndsWithoutPadding) {
  ChannelTransmitter tx;
  ASSERT_TRUE(tx.start(ChannelMode::Remote, std::vector<std::uint8_t>{0x04}));
  EXPECT_EQ(tx.next_pair(), (ChannelPair{STX, 0x1F}));
  EXPECT_EQ(tx.next_pair(), (ChannelPair{0x04, ETX}));
  EXPECT_FALSE(tx.busy());
}

TEST(DcpChannelTransmitter, RepeatsTheLastPairWithoutAdvancing) {
  // DCP 6.1 b: S7 seen -> the same communication bytes again.
  ChannelTransmitter tx;
  ASSERT_TRUE(tx.start(ChannelMode::Expanded, bytes("I8025")));
  EXPECT_EQ(tx.next_pair(), (ChannelPair{STX, 0x1C}));
  EXPECT_EQ(tx.next_pair(), (ChannelPair{'I', '8'}));
  EXPECT_EQ(tx.repeat_pair(), (ChannelPair{'I', '8'}));
  EXPECT_EQ(tx.repeat_pair(), (ChannelPair{'I', '8'}));
  EXPECT_EQ(tx.next_pair(), (ChannelPair{'0', '2'}));
  EXPECT_EQ(tx.next_pair(), (ChannelPair{'5', ETX}));
  EXPECT_EQ(tx.repeat_pair(), (ChannelPair{'5', ETX}));
}

TEST(DcpChannelTransmitter, RefusesWhileBusyOrTooLong) {
  ChannelTransmitter tx;
  ASSERT_TRUE(tx.start(ChannelMode::Expanded, bytes("I3")));
  EXPECT_FALSE(tx.start(ChannelMode::Expanded, bytes("I8")));
  EXPECT_FALSE(tx.start_reset());
  tx.clear();
  EXPECT_EQ(tx.next_pair(), (ChannelPair{0x00, 0x00}));
  std::vector<std::uint8_t> too_long(kMaxChannelPayload + 1, 'A');
  EXPECT_FALSE(tx.start(ChannelMode::Remote, too_long));
  ASSERT_TRUE(tx.start_reset());
  EXPECT_EQ(tx.next_pair(), (ChannelPair{STX, ETX}));  // DCP 5.10
}

TEST(DcpChannel, TransmitterAndParserAgreeOnEveryPayloadLength) {
  for (std::size_t length = 0; length <= kMaxChannelPayload; ++length) {
    std::vector<std::uint8_t> payload(length);
    for (std::size_t i = 0; i < length; ++i) payload[i] = static_cast<std::uint8_t>(0x20 + i % 96);
    ChannelTransmitter tx;
    ChannelParser rx;
    ASSERT_TRUE(tx.start(ChannelMode::DriveError, payload));
    ParseStatus last = ParseStatus::NeedMore;
    int cycle = 0;
    bool complete = false;
    while (tx.busy()) {
      for (std::uint8_t b : tx.next_pair()) {
        last = rx.feed(b, 15ms * cycle);
        if (last == ParseStatus::Complete) complete = true;
      }
      ++cycle;
    }
    // length 0 is STX 1E ETX: an empty frame completes; its decoder rejects it
    ASSERT_TRUE(complete) << length;
    EXPECT_EQ(std::vector<std::uint8_t>(rx.frame().payload().begin(), rx.frame().payload().end()),
              payload);
  }
}

}  // namespace
}  // namespace liftd::dcp
