// The DCP master link's requests, the I2 reset window, the display, error messages and drive data.
#include "dcp/master_link.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "master_link_harness.hpp"

namespace liftd::dcp {
namespace {

// ---- requests
// -------------------------------------------------------------------------------------

TEST(DcpMasterLink, CompletesRequestsWithTheDrivesReplies) {
  Harness h(dcp4_config());
  h.bring_up();
  ASSERT_EQ(h.link.submit(StartParamsRequest{MaxSpeed::V4, 300}, 1), SubmitResult::Accepted);
  ASSERT_EQ(h.link.submit(PositionRequest{15000}, 2), SubmitResult::Accepted);
  ASSERT_EQ(h.link.submit(PowerRequest{PowerSupply::Emergency, EnergySaving::Mode1}, 3),
            SubmitResult::Accepted);
  ASSERT_EQ(h.link.submit(KeypadPress{keypad_button::k1 | keypad_button::k3}, 4),
            SubmitResult::Accepted);
  ASSERT_GE(h.run_until([&] { return h.completions.size() == 4; }), 0);
  for (const auto& c : h.completions) EXPECT_EQ(c.result, RequestResult::Ok) << c.tag;
  EXPECT_EQ(h.completions[0].tag, 1U);
  EXPECT_EQ(h.completions[0].reply, DriveMessage(StartParamsReply{TravelKind::Short, 300, 143}));
  EXPECT_EQ(h.completions[1].reply, DriveMessage(PositionReply{true, 1234}));
  EXPECT_EQ(h.completions[2].reply,
            DriveMessage(PowerReply{PowerSupply::Emergency, EnergySaving::Mode1}));
  EXPECT_EQ(h.link.power_mode().supply, PowerSupply::Emergency);
  EXPECT_TRUE(h.completions[3].keypad);
  EXPECT_FALSE(h.completions[3].reply);
  EXPECT_EQ(h.drive.keypad, (std::vector<std::uint8_t>{0x14}));
}

TEST(DcpMasterLink, RequestWithoutReplyTimesOutAfterTheRequestTimeoutFromOurEtx) {
  Harness h;
  h.drive.mute = {MessageId::Load};
  h.bring_up();
  ASSERT_EQ(h.link.submit(LoadRequest{50}, 77), SubmitResult::Accepted);
  ASSERT_GE(h.run_until([&] { return !h.completions.empty(); }), 0);
  const Completion& c = h.completions[0];
  EXPECT_EQ(c.tag, 77U);
  EXPECT_EQ(c.id, MessageId::Load);
  EXPECT_EQ(c.result, RequestResult::Timeout);
  const MonoTime etx_at = h.drive.message_times.back();
  const MonoTime timeout = MasterLinkConfig{}.request_timeout;  // dcp.request_timeout_ms
  EXPECT_GE(c.at - etx_at, timeout);
  EXPECT_LT(c.at - etx_at, timeout + 15ms) << "within one cycle of the timeout";
  EXPECT_EQ(h.link.counters().request_timeouts, 1U);
  // The link itself stays up, and the next request goes through.
  EXPECT_EQ(h.link.state(), LinkState::Up);
  h.drive.mute.clear();
  ASSERT_EQ(h.link.submit(LoadRequest{50}, 78), SubmitResult::Accepted);
  ASSERT_GE(h.run_until([&] { return h.completions.size() == 2; }), 0);
  EXPECT_EQ(h.completions[1].result, RequestResult::Ok);
}

TEST(DcpMasterLink, UnansweredI6MeansMainsWithoutSaving) {
  // DCP 5.12.6.2.
  Harness h;
  h.drive.mute = {MessageId::Power};
  h.bring_up();
  ASSERT_EQ(h.link.submit(PowerRequest{PowerSupply::Emergency, EnergySaving::Off}, 5),
            SubmitResult::Accepted);
  ASSERT_GE(h.run_until([&] { return !h.completions.empty(); }), 0);
  EXPECT_EQ(h.completions[0].result, RequestResult::AssumedMains);
  EXPECT_EQ(h.completions[0].reply, DriveMessage(PowerReply{}));
  EXPECT_EQ(h.link.power_mode(), PowerReply{});
}

TEST(DcpMasterLink, SubmitRefusesWhatItCannotTake) {
  Harness h;
  EXPECT_EQ(h.link.submit(LoadRequest{10}, 1), SubmitResult::LinkNotUp);
  h.bring_up();
  EXPECT_EQ(h.link.submit(LoadRequest{1000}, 1), SubmitResult::Invalid);
  EXPECT_EQ(h.link.submit(KeypadPress{0x01}, 1), SubmitResult::Invalid);
  for (std::size_t i = 0; i < kRequestQueueSize; ++i) {
    EXPECT_EQ(h.link.submit(LoadRequest{10}, static_cast<RequestTag>(i)), SubmitResult::Accepted);
  }
  EXPECT_EQ(h.link.submit(LoadRequest{10}, 99), SubmitResult::QueueFull);
  ASSERT_GE(h.run_until([&] { return h.completions.size() == kRequestQueueSize; }), 0);
  for (std::size_t i = 0; i < kRequestQueueSize; ++i) {
    EXPECT_EQ(h.completions[i].tag, i);  // FIFO, one outstanding at a time
  }
}

TEST(DcpMasterLink, UnsolicitedReplyIsCountedAndIgnored) {
  Harness h;
  h.bring_up();
  h.drive.send_frame(ChannelMode::Expanded, bytes("I8"));
  h.run(5);
  EXPECT_EQ(h.link.counters().unmatched_replies, 1U);
  EXPECT_TRUE(h.completions.empty());
}

TEST(DcpMasterLink, MalformedReplyIsADecodeError) {
  Harness h;
  h.bring_up();
  h.drive.send_frame(ChannelMode::Expanded, bytes("I7x0030000143"));
  h.run(10);
  EXPECT_EQ(h.link.counters().decode_errors, 1U);
  const auto it = std::find_if(h.events.begin(), h.events.end(), [](const LinkEvent& e) {
    return e.kind == LinkEventKind::DecodeError;
  });
  ASSERT_NE(it, h.events.end());
  EXPECT_EQ(it->detail, to_string(MessageError::BadTravelKind));
}

// ---- I2 trip/fault reset (DCP 5.12.4)
// -------------------------------------------------------------

TEST(DcpMasterLink, ResetCanBeCancelledInsideTheWindow) {
  Harness h;
  h.bring_up();
  ASSERT_EQ(h.link.submit(SwitchRequest{SwitchFunction::Reset}, 1), SubmitResult::Accepted);
  ASSERT_GE(h.run_until([&] { return h.link.state() == LinkState::Resetting; }), 0);
  EXPECT_FALSE(h.link.travel_allowed());  // at rest: no new travel while the drive resets
  h.link.set_process(kB0B2, 0);
  ASSERT_EQ(h.completions.size(), 1U);
  EXPECT_EQ(h.completions[0].reply, DriveMessage(SwitchReply{SwitchFunction::Reset}));
  EXPECT_EQ(h.link.submit(LoadRequest{10}, 2), SubmitResult::LinkNotUp);
  ASSERT_EQ(h.link.submit(SwitchRequest{SwitchFunction::None}, 3), SubmitResult::Accepted);
  h.cycle();
  EXPECT_EQ(h.last()[0] & 0x07, 0);
  ASSERT_GE(h.run_until([&] { return h.up(); }), 0);
  EXPECT_EQ(h.drive.messages.back(), MasterMessage(SwitchRequest{SwitchFunction::None}));
  ASSERT_TRUE(h.drive.reset_reply_at);
  EXPECT_LT(h.drive.message_times.back() - *h.drive.reset_reply_at, 200ms)
      << "the cancel must reach the drive inside its 200 ms window";
  EXPECT_EQ(h.count_messages(MessageId::Init), 1);  // no re-initialisation
}

TEST(DcpMasterLink, ResetReinitialisesFiveSecondsLaterEvenThroughSilence) {
  Harness h;
  h.bring_up();
  ASSERT_EQ(h.link.submit(SwitchRequest{SwitchFunction::Reset}, 1), SubmitResult::Accepted);
  ASSERT_GE(h.run_until([&] { return h.link.state() == LinkState::Resetting; }), 0);
  const MonoTime reply_at = h.completions.at(0).at;
  h.run(14);  // 210 ms: the window has passed
  EXPECT_EQ(h.link.submit(SwitchRequest{SwitchFunction::None}, 2), SubmitResult::TooLate);
  h.drive.deaf_frames = 150;  // the drive restarts its software: 2.25 s without replies
  h.run(150);
  EXPECT_EQ(h.link.state(), LinkState::Resetting) << "an expected outage is no link fault";
  ASSERT_GE(h.run_until([&] { return h.link.state() == LinkState::Init; }), 0);
  const LinkEvent* init = h.last_state_change();
  ASSERT_NE(init, nullptr);
  EXPECT_GE(init->at - reply_at, 5000ms);
  EXPECT_LT(init->at - reply_at, 5015ms);
  h.bring_up();
  EXPECT_EQ(h.count_messages(MessageId::Init), 2);
}

TEST(DcpMasterLink, RefusedResetLeavesTheLinkUp) {
  Harness h;
  h.drive.accepts_reset = false;
  h.bring_up();
  ASSERT_EQ(h.link.submit(SwitchRequest{SwitchFunction::Reset}, 1), SubmitResult::Accepted);
  ASSERT_GE(h.run_until([&] { return !h.completions.empty(); }), 0);
  EXPECT_EQ(h.completions[0].reply, DriveMessage(SwitchReply{SwitchFunction::None}));
  EXPECT_EQ(h.link.state(), LinkState::Up);
}

// ---- display, error messages, drive data
// ------------------------------------------------------------

TEST(DcpMasterLink, ShowsTheDrivesDisplayAndClearsItOnANewStx) {
  Harness h;
  h.bring_up();
  std::vector<std::uint8_t> line{0x04, 0x08};
  const auto menu = bytes("Menu");
  line.insert(line.end(), menu.begin(), menu.end());
  h.drive.send_frame(ChannelMode::Remote, line);
  h.run(6);
  EXPECT_EQ(h.link.display().row_utf8(0), "Menu                ");
  h.drive.send_raw({0x02, 0x1F, 0x05, 0x08, 'X'});             // interrupted stream...
  h.drive.send_frame(ChannelMode::Remote, {0x06, 0x08, 'Y'});  // ...and a new STX
  h.run(8);
  EXPECT_EQ(h.link.display().row_utf8(0), std::string(20, ' '));
  EXPECT_EQ(h.link.display().row_utf8(1), std::string(20, ' '));
  EXPECT_EQ(h.link.display().row_utf8(2), "Y" + std::string(19, ' '));
}

TEST(DcpMasterLink, StxEtxFromTheDriveClearsTheDisplay) {
  Harness h;
  h.bring_up();
  h.drive.send_frame(ChannelMode::Remote, {0x04, 0x08, 'A'});
  h.drive.send_raw({0x02, 0x03});
  h.run(6);
  EXPECT_EQ(h.link.display().row_utf8(0), std::string(20, ' '));
  EXPECT_EQ(h.link.state(), LinkState::Up);
}

TEST(DcpMasterLink, QueuesDriveErrorMessagesWithTheirTime) {
  Harness h;
  h.bring_up();
  h.drive.send_frame(ChannelMode::DriveError, bytes("E023 Overtemp"));
  h.run(12);
  ASSERT_EQ(h.errors.size(), 1U);
  const auto chars = h.errors[0].text.chars();
  EXPECT_EQ(std::string(chars.begin(), chars.end()), "E023 Overtemp");
  // 16 bytes = 8 cycles; the ETX arrives with the reply of the 8th cycle.
  EXPECT_GT(h.errors[0].at, h.now - 12 * 15ms);
}

TEST(DcpMasterLink, DecodesDriveDataByTheConfirmedType) {
  Harness h;  // data-information-type '0': deceleration distance and extended status alternate
  h.bring_up();
  h.drive.data_word = 0x0123;
  h.cycle();
  ASSERT_TRUE(h.link.drive().deceleration);
  EXPECT_EQ(h.link.drive().deceleration->deceleration_distance_mm, 0x0123U);
  h.drive.data_word = 0x8001;
  h.cycle();
  ASSERT_TRUE(h.link.drive().extended);
  EXPECT_TRUE(h.link.drive().extended->below_unlocking_speed);
  EXPECT_EQ(h.link.drive().status, status_bit::kReady);
}

TEST(DcpMasterLink, CountsDataWordsThatDoNotFitTheType) {
  MasterLinkConfig c;
  c.data_info_type = DataInfoType::Extended;  // '2': extended status only (bit 15 set)
  Harness h(c);
  h.drive.data_word = 0x8000;
  h.bring_up();
  EXPECT_EQ(h.link.counters().data_word_errors, 0U);
  h.drive.data_word = 0x0100;
  h.cycle();
  EXPECT_EQ(h.link.counters().data_word_errors, 1U);
}

}  // namespace
}  // namespace liftd::dcp
