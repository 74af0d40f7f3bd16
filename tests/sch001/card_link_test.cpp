// The controller's side of the SCH001 link with a fake clock: every status frame answered,
// travel bits only with ERR = 0 and RDY = 1 (3d, 3e), the 10 s timeout and the card's commands
// that switch it (3f), frames that must never be acted on.
#include <gtest/gtest.h>

#include <chrono>
#include <vector>

#include "sch001/card_link.hpp"

namespace liftd::sch001 {
namespace {

using std::chrono::milliseconds;
using Bytes = std::vector<std::uint8_t>;

constexpr std::uint8_t kRdy = 0x02;
constexpr std::uint8_t kErr = 0x80;

can::Frame from_card(Bytes bytes) {
  return can::make_frame(0x581, bytes);
}
can::Frame status(std::uint8_t byte) {
  return from_card({0x61, byte});
}
Bytes answer_bytes(const can::Frame& f) {
  return {f.bytes().begin(), f.bytes().end()};
}

class CardLinkTest : public ::testing::Test {
 protected:
  CardLinkTest() : link_(CardLinkConfig{}, MonoTime{}) {
    Command c;
    c.bits.up = c.bits.hsp = c.bits.sfy = true;  // 0x15
    c.current_floor = 1;
    c.destination_floor = 4;
    link_.set_command(c);
  }
  /// The answer to a frame at `t_ms`.
  std::optional<Bytes> answer(const can::Frame& frame, int t_ms) {
    const FrameResult r = link_.on_frame(frame, milliseconds(t_ms));
    if (!r.answer) return std::nullopt;
    EXPECT_EQ(r.answer->id, 0x551U);
    return answer_bytes(*r.answer);
  }
  CardLink link_;
};

TEST_F(CardLinkTest, AnswersEveryStatusFrameWithTheCommand) {
  for (int i = 0; i < 5; ++i) {
    EXPECT_EQ(answer(status(kRdy), 100 * i), (Bytes{0x68, 0x15, 1, 4})) << i;
  }
  EXPECT_EQ(link_.counters().status_frames, 5U);
  EXPECT_EQ(link_.counters().answers, 5U);
  EXPECT_TRUE(link_.travel_allowed());
}

TEST_F(CardLinkTest, NoTravelBitWithErrOrWithoutRdyButTheFloorsStay) {
  EXPECT_EQ(answer(status(0x00), 0), (Bytes{0x68, 0x00, 1, 4}));           // not ready yet
  EXPECT_EQ(answer(status(kRdy | kErr), 100), (Bytes{0x68, 0x00, 1, 4}));  // ERR
  EXPECT_EQ(answer(status(kRdy), 200), (Bytes{0x68, 0x15, 1, 4}));
  // RDY falls: the answer to that very frame carries no travel command.
  EXPECT_EQ(answer(status(0x00), 300), (Bytes{0x68, 0x00, 1, 4}));
  EXPECT_FALSE(link_.travel_allowed());
  // Every other status bit leaves the decision to ERR and RDY alone.
  EXPECT_EQ(answer(status(0x7F & ~kErr), 400), (Bytes{0x68, 0x15, 1, 4}));
}

TEST_F(CardLinkTest, StatusChangesAreFlaggedOnce) {
  EXPECT_TRUE(link_.on_frame(status(kRdy), milliseconds(0)).status_changed);
  EXPECT_FALSE(link_.on_frame(status(kRdy), milliseconds(100)).status_changed);
  EXPECT_TRUE(link_.on_frame(status(kRdy | 0x10), milliseconds(200)).status_changed);  // T1
  ASSERT_TRUE(link_.status());
  EXPECT_TRUE(link_.status()->t1);
}

TEST_F(CardLinkTest, TimeoutTripsAfterTenSecondsOfSilence) {
  EXPECT_EQ(link_.on_frame(status(kRdy), milliseconds(1000)).change, LinkChange::FirstHeard);
  EXPECT_EQ(link_.on_tick(milliseconds(10'999)), LinkChange::None);
  EXPECT_EQ(link_.on_tick(milliseconds(11'000)), LinkChange::Silent);
  EXPECT_EQ(link_.on_tick(milliseconds(12'000)), LinkChange::None) << "reported once";
  EXPECT_TRUE(link_.silent());
  EXPECT_FALSE(link_.travel_allowed());
  EXPECT_EQ(link_.counters().timeouts, 1U);
  EXPECT_EQ(link_.on_frame(status(kRdy), milliseconds(13'000)).change, LinkChange::Recovered);
  EXPECT_TRUE(link_.travel_allowed());
}

TEST_F(CardLinkTest, TimeoutIsOnAtStartBeforeTheCardIsHeard) {
  EXPECT_TRUE(link_.timeout_enabled());
  EXPECT_EQ(link_.on_tick(milliseconds(9'999)), LinkChange::None);
  EXPECT_EQ(link_.on_tick(milliseconds(10'000)), LinkChange::Silent);
}

TEST_F(CardLinkTest, TheCardSwitchesTheTimeoutOffAndOn) {
  EXPECT_EQ(answer(from_card({0x5A}), 0), (Bytes{0x6B}));
  EXPECT_FALSE(link_.timeout_enabled());
  EXPECT_EQ(link_.on_tick(milliseconds(60'000)), LinkChange::None);
  EXPECT_EQ(answer(from_card({0x52}), 60'000), (Bytes{0x65}));
  EXPECT_TRUE(link_.timeout_enabled());
  // Runs from the last frame from the card (the 0x52 itself).
  EXPECT_EQ(link_.on_tick(milliseconds(69'999)), LinkChange::None);
  EXPECT_EQ(link_.on_tick(milliseconds(70'000)), LinkChange::Silent);
  EXPECT_EQ(link_.counters().timeout_commands, 2U);
}

TEST_F(CardLinkTest, FramesNeverActedOn) {
  EXPECT_EQ(answer(status(kRdy), 0), (Bytes{0x68, 0x15, 1, 4}));
  // Wrong length, unknown first byte, our own identifier, a stranger: no answer, and none of
  // them counts as the card being heard.
  EXPECT_FALSE(answer(from_card({0x61}), 5000));
  EXPECT_FALSE(answer(from_card({0x61, 0x80, 0x00}), 5000));
  EXPECT_FALSE(answer(from_card({0x33, 0x00}), 5000));
  EXPECT_FALSE(answer(can::make_frame(0x551, Bytes{0x61, 0x80}), 5000));
  EXPECT_FALSE(answer(can::make_frame(0x123, Bytes{0x61, 0x80}), 5000));
  EXPECT_EQ(link_.counters().wrong_length, 2U);
  EXPECT_EQ(link_.counters().unknown_first_byte, 1U);
  EXPECT_EQ(link_.counters().own_id, 1U);
  EXPECT_EQ(link_.counters().other_id, 1U);
  ASSERT_TRUE(link_.status());
  EXPECT_FALSE(link_.status()->err) << "a rejected frame changed the status";
  EXPECT_EQ(link_.on_tick(milliseconds(10'000)), LinkChange::Silent);
}

}  // namespace
}  // namespace liftd::sch001
