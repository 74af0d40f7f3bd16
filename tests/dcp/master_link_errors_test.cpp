// The DCP master link on transmission errors, supervision and channel timeouts (DCP 5.4, 6, 7.3).
#include "dcp/master_link.hpp"

#include <gtest/gtest.h>

#include <vector>

#include "master_link_harness.hpp"

namespace liftd::dcp {
namespace {

// ---- DCP 6: transmission errors ----------------------------------------------------------------

TEST(DcpMasterLink, BadChecksumReplySetsB7OnceAndKeepsTheMessage) {
  // DCP 6.1 a.
  Harness h;
  h.bring_up();
  h.link.set_process(0x05 | command_bit::kDirectionDown, 0x0ABC);
  h.cycle();
  h.drive.corrupt_replies = 1;
  h.cycle();  // this reply arrives corrupt
  h.cycle();  // -> B7 in this frame, same command and data
  const FrameBytes with_b7 = h.last();
  h.cycle();
  const FrameBytes after = h.last();
  EXPECT_EQ(with_b7[0], 0x05 | command_bit::kDirectionDown | command_bit::kReplyChecksumError);
  EXPECT_EQ(with_b7[1], 0x0A);
  EXPECT_EQ(with_b7[2], 0xBC);
  EXPECT_EQ(after[0], 0x05 | command_bit::kDirectionDown);
  EXPECT_EQ(h.link.counters().bad_checksum, 1U);
  EXPECT_EQ(h.link.counters().b7_sent, 1U);
  EXPECT_EQ(h.drive.b7_seen, 1);
}

TEST(DcpMasterLink, RepeatedReplyAfterB7IsConsumedExactlyOnce) {
  // DCP 6.2 b: the drive repeats its last reply after B7. A display line streamed through
  // several corrupt replies must arrive exactly: a byte consumed twice or lost would shift it.
  Harness h;
  h.bring_up();
  std::vector<std::uint8_t> line{0x04, 0x08};
  const auto text = bytes("0123456789ABCDEFGHIJ");
  line.insert(line.end(), text.begin(), text.end());
  h.drive.send_frame(ChannelMode::Remote, line);
  for (int i = 0; i < 30; ++i) {
    if (i == 2 || i == 5 || i == 6 || i == 11) h.drive.corrupt_replies = 1;
    h.cycle();
  }
  EXPECT_EQ(h.link.display().row_utf8(0), "0123456789ABCDEFGHIJ");
  EXPECT_EQ(h.link.counters().bad_checksum, 4U);
  EXPECT_EQ(h.link.counters().decode_errors, 0U);
  EXPECT_EQ(h.link.counters().channel_errors, 0U);
}

TEST(DcpMasterLink, MissingReplyDoesNotSetB7) {
  Harness h;
  h.bring_up();
  h.drive.lose_replies = 1;
  h.cycle();
  h.cycle();
  EXPECT_EQ(h.last()[0] & command_bit::kReplyChecksumError, 0);
  EXPECT_EQ(h.link.counters().missing_replies, 1U);
  EXPECT_EQ(h.link.counters().b7_sent, 0U);
}

TEST(DcpMasterLink, S7RepeatsOurLastChannelBytes) {
  // DCP 6.1 b: the drive saw our frame corrupt (S7): send the same two channel bytes again.
  Harness h;
  h.bring_up();
  ASSERT_EQ(h.link.submit(LoadRequest{25}, 1), SubmitResult::Accepted);
  h.cycle();  // STX 1C
  EXPECT_EQ(h.last()[3], 0x02);
  h.corrupt_masters = 1;
  h.cycle();  // 'I' '8', corrupted on the wire; the drive answers S7
  const FrameBytes lost = h.last();
  EXPECT_EQ(lost[3], 'I');
  h.cycle();
  EXPECT_EQ(h.last()[3], lost[3]);
  EXPECT_EQ(h.last()[4], lost[4]);
  ASSERT_GE(h.run_until([&] { return !h.completions.empty(); }), 0);
  EXPECT_EQ(h.completions[0].result, RequestResult::Ok);
  // The drive's stream holds the message exactly once.
  const auto tail = std::vector<std::uint8_t>(h.drive.stream.end() - 8, h.drive.stream.end());
  EXPECT_EQ(tail, (std::vector<std::uint8_t>{0x02, 0x1C, 'I', '8', '0', '2', '5', 0x03}));
  EXPECT_EQ(h.link.counters().s7_seen, 1U);
}

TEST(DcpMasterLink, EchoCollisionRepeatsOurChannelBytesWithoutB7) {
  // Our frame came back changed on an echoing line: the drive read it changed too and ignored
  // it (DCP 6.2 a). As for an S7 reply (DCP 6.1 b) our two channel bytes go again; no B7, whose
  // repeated reply would only bring back the drive's S7.
  Harness h;
  h.bring_up();
  ASSERT_EQ(h.link.submit(LoadRequest{25}, 1), SubmitResult::Accepted);
  h.cycle();  // STX 1C
  h.collide_masters = 1;
  h.cycle();  // 'I' '8', collides
  const FrameBytes lost = h.last();
  EXPECT_EQ(lost[3], 'I');
  h.cycle();
  EXPECT_EQ(h.last()[3], lost[3]);
  EXPECT_EQ(h.last()[4], lost[4]);
  EXPECT_EQ(h.last()[0] & command_bit::kReplyChecksumError, 0);
  ASSERT_GE(h.run_until([&] { return !h.completions.empty(); }), 0);
  EXPECT_EQ(h.completions[0].result, RequestResult::Ok);
  const auto tail = std::vector<std::uint8_t>(h.drive.stream.end() - 8, h.drive.stream.end());
  EXPECT_EQ(tail, (std::vector<std::uint8_t>{0x02, 0x1C, 'I', '8', '0', '2', '5', 0x03}));
  const LinkCounters c = h.link.counters();
  EXPECT_EQ(c.bad_exchanges, 1U);
  EXPECT_EQ(c.bad_checksum, 0U);
  EXPECT_EQ(c.b7_sent, 0U);
  EXPECT_EQ(c.missing_replies, 0U);
}

TEST(DcpMasterLink, EchoCollisionsCountTowardTheSupervision) {
  // DCP 7.3: a frame the drive received incorrectly counts like a lost one.
  Harness h;
  h.bring_up();
  h.collide_masters = 9;
  h.run(9);
  EXPECT_EQ(h.link.state(), LinkState::Up);
  EXPECT_EQ(h.link.counters().error_run, 9U);
  h.collide_masters = 1;
  h.cycle();
  EXPECT_EQ(h.link.state(), LinkState::Fault);
  EXPECT_EQ(h.link.counters().bad_exchanges, 10U);
}

TEST(DcpMasterLink, IgnoresS7InAReplyWithBadChecksum) {
  // DCP 6 note: B7/S7 of a frame with a bad checksum must not be acted on.
  Harness h;
  h.bring_up();
  ASSERT_EQ(h.link.submit(LoadRequest{25}, 1), SubmitResult::Accepted);
  const FrameBytes first = h.link.next_frame(h.now);
  EXPECT_EQ(first[3], 0x02);
  SlaveFrame s{status_bit::kReady | status_bit::kMessageChecksumError, 0x7F, 0xFF, 0, 0};
  FrameBytes reply = encode(s);
  reply[5] ^= 0x40;
  h.link.on_reply(reply, h.now + 5ms);
  h.now += 15ms;
  const FrameBytes second = h.link.next_frame(h.now);
  EXPECT_EQ(second[3], 'I');  // advanced, not repeated
  EXPECT_NE(second[0] & command_bit::kReplyChecksumError, 0);
  EXPECT_EQ(h.link.counters().s7_seen, 0U);
}

TEST(DcpMasterLink, ActsOnS7InAGoodReply) {
  Harness h;
  h.bring_up();
  ASSERT_EQ(h.link.submit(LoadRequest{25}, 1), SubmitResult::Accepted);
  const FrameBytes first = h.link.next_frame(h.now);
  const SlaveFrame s{status_bit::kReady | status_bit::kMessageChecksumError, 0x7F, 0xFF, 0, 0};
  h.link.on_reply(encode(s), h.now + 5ms);
  h.now += 15ms;
  const FrameBytes second = h.link.next_frame(h.now);
  EXPECT_EQ(second[3], first[3]);
  EXPECT_EQ(second[4], first[4]);
  EXPECT_EQ(second[0] & command_bit::kReplyChecksumError, 0);
}

// ---- DCP 7.3: supervision -----------------------------------------------------------------------

TEST(DcpMasterLink, FaultsAtExactlyTheTenthBadOrMissingReply) {
  Harness h;
  h.bring_up();
  h.link.set_process(kB0B2, 0);
  h.drive.corrupt_replies = 5;
  h.run(5);
  h.drive.deaf_frames = 4;
  h.run(4);  // nine in a row: bad checksums and missing replies count alike
  EXPECT_EQ(h.link.state(), LinkState::Up);
  EXPECT_EQ(h.link.counters().error_run, 9U);
  EXPECT_EQ(h.last()[0] & 0x07, kB0B2);
  h.drive.deaf_frames = 1;
  h.cycle();  // the tenth
  EXPECT_EQ(h.link.state(), LinkState::Fault);
  ASSERT_NE(h.last_state_change(), nullptr);
  EXPECT_EQ(h.last_state_change()->state, LinkState::Fault);
  h.cycle();
  EXPECT_EQ(h.last()[0] & 0x07, 0) << "B0..B2 off in the first frame after the fault";
  EXPECT_EQ(h.link.counters().link_faults, 1U);
  EXPECT_EQ(h.link.counters().longest_error_run, 10U);
}

TEST(DcpMasterLink, NineErrorsThenAGoodReplyStartAfresh) {
  Harness h;
  h.bring_up();
  h.drive.deaf_frames = 9;
  h.run(9);
  h.cycle();  // good
  h.drive.deaf_frames = 9;
  h.run(9);
  EXPECT_EQ(h.link.state(), LinkState::Up);
  EXPECT_EQ(h.link.counters().longest_error_run, 9U);
}

TEST(DcpMasterLink, RecoversAfterTenGoodStationaryRepliesAndReinitialises) {
  Harness h;
  h.bring_up();
  h.drive.deaf_frames = 10;
  h.run(10);
  ASSERT_EQ(h.link.state(), LinkState::Fault);
  h.run(1);  // the first frame after the fault is the drive's first good reply: 1 of 10
  h.run(8);  // 9 of 10
  EXPECT_EQ(h.link.state(), LinkState::Fault);
  h.drive.status |= status_bit::kTravelActive;  // not stationary: the count starts again
  h.run(3);
  h.drive.status &= static_cast<std::uint8_t>(~status_bit::kTravelActive);
  h.run(9);
  EXPECT_EQ(h.link.state(), LinkState::Fault);
  h.cycle();  // the tenth good stationary reply in a row
  EXPECT_EQ(h.link.state(), LinkState::Init);
  h.bring_up();
  EXPECT_EQ(h.count_messages(MessageId::Init), 2);
  EXPECT_EQ(h.count_messages(MessageId::DataInfo), 2);
}

TEST(DcpMasterLink, PortLostIsAFaultAtOnceAndFailsRequests) {
  Harness h;
  h.bring_up();
  h.link.set_process(kB0B2, 0);
  ASSERT_EQ(h.link.submit(LoadRequest{40}, 9), SubmitResult::Accepted);
  h.cycle();
  h.link.on_port_lost(h.now);
  h.drain();
  EXPECT_EQ(h.link.state(), LinkState::Fault);
  ASSERT_EQ(h.completions.size(), 1U);
  EXPECT_EQ(h.completions[0].tag, 9U);
  EXPECT_EQ(h.completions[0].result, RequestResult::LinkLost);
  h.cycle();
  EXPECT_EQ(h.last()[0] & 0x07, 0);
}

// ---- DCP 5.4: channel timeouts -------------------------------------------------------------

TEST(DcpMasterLink, StxWithoutEtxForOneSecondReinitialises) {
  Harness h;
  h.bring_up();
  h.drive.send_raw({0x02, 0x1C, 'I'});  // a frame that never ends
  h.cycle();                            // STX 1C reach us now (at now + 5 ms)
  const MonoTime stx_at = h.now - 15ms + 5ms;
  ASSERT_GE(h.run_until([&] { return h.link.state() != LinkState::Up; }), 0);
  const auto it = std::find_if(h.events.begin(), h.events.end(), [](const LinkEvent& e) {
    return e.kind == LinkEventKind::ChannelReset &&
           e.detail == to_string(ChannelReset::FrameTimeout);
  });
  ASSERT_NE(it, h.events.end());
  EXPECT_GE(it->at - stx_at, 1000ms);
  EXPECT_LT(it->at - stx_at, 1015ms);  // noticed in the first cycle after the second
  EXPECT_EQ(h.link.state(), LinkState::Init);
  h.bring_up();
  EXPECT_EQ(h.count_messages(MessageId::Init), 2);
}

TEST(DcpMasterLink, S7RepliesCountTowardTheSupervision) {
  // DCP 7.3: "10 successive messages are received incorrectly or were completely lost": the
  // drive answers each of our frames with S7, i.e. it received them incorrectly.
  Harness h;
  h.bring_up();
  h.corrupt_masters = 80;
  EXPECT_EQ(h.run_until([&] { return h.link.state() == LinkState::Fault; }, 100), 10);
  EXPECT_EQ(h.link.counters().s7_seen, 10U);
  EXPECT_EQ(h.link.counters().link_faults, 1U);
}

// ---- the channel is subordinate to the real-time channel (DCP 5.1, 5.4) --------------------

TEST(DcpMasterLink, ChannelTimeoutDuringATravelKeepsB0AndReinitialisesAtRest) {
  // DCP 5.1: "The communication data channel is subordinate to the real time channel". An STX
  // without ETX for 1 s (DCP 5.4) resets the channel; the travel goes on with B0/B2, and I0
  // runs again only once the car is at rest.
  Harness h;
  h.bring_up();
  h.link.set_process(kB0B2, 100);
  h.drive.status = status_bit::kReady | status_bit::kTravelActive | status_bit::kBrakeOpen;
  h.run(2);
  h.drive.send_raw({channel_char::kStx, channel_char::kModeExpanded, 'I'});
  const int inits_before = h.count_messages(MessageId::Init);
  h.run(80);  // 1.2 s: the frame timeout has fired
  EXPECT_GE(h.link.counters().deferred_resets, 1U);
  for (std::size_t i = h.sent.size() - 80; i < h.sent.size(); ++i) {
    EXPECT_EQ(h.sent[i][0] & kB0B2, kB0B2) << "frame " << i << " lost B0/B2 to a channel fault";
  }
  EXPECT_TRUE(h.link.travel_allowed());
  EXPECT_EQ(h.count_messages(MessageId::Init), inits_before) << "no handshake during a travel";
  // The car arrives: S1 falls, B0 goes; now the handshake runs again.
  h.drive.status = status_bit::kReady;
  h.link.set_process(0, 0);
  ASSERT_GE(h.run_until([&] { return h.count_messages(MessageId::Init) > inits_before; }), 0);
  ASSERT_GE(h.run_until([&] { return h.up(); }), 0);
}

TEST(DcpMasterLink, GarbageOnTheChannelNeverTouchesTheCommandByte) {
  Harness h;
  h.bring_up();
  h.link.set_process(kB0B2, 100);
  h.drive.status = status_bit::kReady | status_bit::kTravelActive | status_bit::kBrakeOpen;
  h.drive.send_raw({channel_char::kStx, 0x11, 'X', channel_char::kEtx, 0x05, 0x17});
  h.run(20);
  EXPECT_GE(h.link.counters().channel_errors, 1U);
  EXPECT_EQ(h.link.state(), LinkState::Up);
  for (std::size_t i = h.sent.size() - 20; i < h.sent.size(); ++i) {
    EXPECT_EQ(h.sent[i][0] & kB0B2, kB0B2) << "frame " << i;
  }
}

TEST(DcpMasterLink, ResetReplyDuringATravelKeepsB0) {
  // Issue reading of DCP 5.1 / 5.12.4: an I2 'R' reply resets the channel side, never the
  // running travel's B0/B2; the re-initialisation waits for rest.
  Harness h;
  h.bring_up();
  h.link.set_process(kB0B2, 100);
  h.drive.status = status_bit::kReady | status_bit::kTravelActive | status_bit::kBrakeOpen;
  h.run(1);
  ASSERT_EQ(h.link.submit(SwitchRequest{SwitchFunction::Reset}, 1), SubmitResult::Accepted);
  ASSERT_GE(h.run_until([&] { return h.link.state() == LinkState::Resetting; }), 0);
  h.run(400);  // past the 5 s re-initialisation delay
  EXPECT_TRUE(h.link.travel_allowed());
  EXPECT_EQ(h.sent.back()[0] & kB0B2, kB0B2);
  EXPECT_EQ(h.count_messages(MessageId::Init), 1) << "no I0 while the car travels";
  h.drive.status = status_bit::kReady;
  h.link.set_process(0, 0);
  ASSERT_GE(h.run_until([&] { return h.up(); }), 0);
  EXPECT_EQ(h.count_messages(MessageId::Init), 2);
}

TEST(DcpMasterLink, B7IsSentAgainWhenItsFrameGotAnS7Reply) {
  // DCP 6.1: after a bad reply we set B7; if that very frame reached the drive corrupted (S7),
  // the drive never saw our B7, so the next frame carries it again.
  Harness h;
  h.bring_up();
  h.drive.corrupt_replies = 1;
  h.cycle();  // reply corrupted -> B7 in the next frame
  h.corrupt_masters = 1;
  h.cycle();  // that frame (with B7) arrives corrupted: S7 reply
  ASSERT_NE(h.sent[h.sent.size() - 1][0] & command_bit::kReplyChecksumError, 0);
  h.cycle();
  EXPECT_NE(h.sent.back()[0] & command_bit::kReplyChecksumError, 0) << "B7 repeated";
  EXPECT_EQ(h.link.counters().b7_sent, 2U);
}

}  // namespace
}  // namespace liftd::dcp
