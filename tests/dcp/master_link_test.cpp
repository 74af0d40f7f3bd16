// Over 800 lines: every DCP 6/7 rule of the link engine against one scripted drive; split, the
// rules would lose their shared fixture.
// The master link engine against a scripted fake drive, with a fake clock: handshake, DCP 6
// error handling, DCP 7.3 supervision, channel timeouts, I3 at day change, requests and timeouts,
// the I2 reset window.
#include "dcp/master_link.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <functional>
#include <string>
#include <vector>

#include "dcp/dcp_test_util.hpp"
#include "fake_drive.hpp"

namespace liftd::dcp {
namespace {

using namespace std::chrono_literals;
using test::bytes;
using test::FakeDrive;

constexpr std::uint8_t kB0B2 = command_bit::kDriveEnable | command_bit::kStopSwitch;

// One link, one fake drive, one fake clock; a cycle is 15 ms (DCP 2).
struct Harness {
  explicit Harness(MasterLinkConfig c = {}) : link(c) {}

  MasterLink link;
  FakeDrive drive;
  MonoTime now = 1000ms;
  int corrupt_masters = 0;  ///< corrupt the next N master frames on the wire
  /// The next N master frames collide on an echoing line: corrupted on the wire for the drive,
  /// and the master reads its echo back changed (on_bad_reply), whatever the drive answers.
  int collide_masters = 0;
  std::vector<FrameBytes> sent;
  std::vector<Completion> completions;
  std::vector<LinkEvent> events;
  std::vector<DriveErrorEvent> errors;

  void cycle() {
    const FrameBytes frame = link.next_frame(now);
    sent.push_back(frame);
    FrameBytes wire = frame;
    if (corrupt_masters > 0) {
      --corrupt_masters;
      wire[5] ^= 0x01;
    }
    const bool collided = collide_masters > 0;
    if (collided) {
      --collide_masters;
      wire[1] ^= 0x10;
    }
    const auto reply = drive.exchange(wire, now);
    if (collided) {
      link.on_bad_reply(now + 2ms);  // the echo differed: read while sending (DCP 7.2)
    } else if (reply) {
      link.on_reply(*reply, now + 5ms);  // DCP 7.2: reply well inside the cycle
    } else {
      link.on_no_reply(now + 14ms);
    }
    drain();
    now += 15ms;
  }
  void run(int cycles) {
    for (int i = 0; i < cycles; ++i) cycle();
  }
  // Runs until pred() holds; returns the cycles it took, or -1 after `max`.
  int run_until(const std::function<bool()>& pred, int max = 400) {
    for (int i = 0; i < max; ++i) {
      if (pred()) return i;
      cycle();
    }
    return pred() ? max : -1;
  }
  void drain() {
    while (auto c = link.pop_completion()) completions.push_back(*c);
    while (auto e = link.pop_event()) events.push_back(*e);
    while (auto d = link.pop_drive_error()) errors.push_back(*d);
  }
  bool up() const { return link.state() == LinkState::Up; }
  void bring_up() {
    ASSERT_GE(run_until([&] { return up(); }), 0) << "handshake never finished";
  }
  const FrameBytes& last() const { return sent.back(); }
  int count_messages(MessageId id) const {
    return static_cast<int>(std::count_if(drive.messages.begin(), drive.messages.end(),
                                          [&](const auto& m) { return message_id(m) == id; }));
  }
  const LinkEvent* last_state_change() const {
    for (auto it = events.rbegin(); it != events.rend(); ++it) {
      if (it->kind == LinkEventKind::StateChanged) return &*it;
    }
    return nullptr;
  }
};

MasterLinkConfig dcp4_config() {
  MasterLinkConfig c;
  c.maker = {'B', 'P'};
  c.version = 123;
  c.software_date = {15, 6, 25};
  c.language = {'D', 'E'};
  c.data_info_type = DataInfoType::Decel15;
  c.extended_position = true;
  return c;
}

// ---- handshake ----------------------------------------------------------------------------

TEST(DcpMasterLink, StartsDownWithTravelBitsForcedOff) {
  Harness h;
  h.drive.deaf_frames = 1000;
  h.link.set_process(0x7F, 0x1234);
  h.run(20);
  EXPECT_EQ(h.link.state(), LinkState::Down);
  EXPECT_FALSE(h.link.travel_allowed());
  for (const auto& f : h.sent) {
    EXPECT_EQ(f[0], 0x78);  // B0..B2 cleared, B3..B6 as set, B7 ours
    EXPECT_EQ(f[1], 0x12);
    EXPECT_EQ(f[2], 0x34);
    EXPECT_EQ(f[3], 0x00);  // channel idle while nobody answers
    EXPECT_EQ(f[4], 0x00);
  }
}

TEST(DcpMasterLink, HandshakeSendsResetI0I1I3InOrderThenAllowsTravel) {
  Harness h(dcp4_config());
  h.link.set_civil_time({2026, 11, 22, 3, 4, 5});
  h.link.set_process(kB0B2, 0x0100);
  int cycles = 0;
  while (!h.up() && cycles < 200) {
    h.cycle();
    ++cycles;
    if (!h.up()) {
      EXPECT_EQ(h.last()[0] & 0x07, 0) << "B0..B2 must stay off before the handshake";
    }
  }
  ASSERT_TRUE(h.up());
  // DCP 5.10 reset first, then the three messages of DCP 5.12.2, 5.12.3, 5.12.5.
  EXPECT_EQ(h.drive.resets_seen, 1);
  const std::vector<std::uint8_t> head(h.drive.stream.begin(), h.drive.stream.begin() + 20);
  std::vector<std::uint8_t> expected{0x02, 0x03, 0x02, 0x1C};
  const auto i0 = bytes("I0BP0123150625DE");
  expected.insert(expected.end(), i0.begin(), i0.end());
  EXPECT_EQ(head, expected);
  ASSERT_EQ(h.drive.messages.size(), 3U);
  EXPECT_EQ(h.drive.messages[0],
            MasterMessage(InitRequest{{'B', 'P'}, 123, {15, 6, 25}, {'D', 'E'}}));
  EXPECT_EQ(h.drive.messages[1], MasterMessage(DataInfoRequest{true, DataInfoType::Decel15}));
  EXPECT_EQ(h.drive.messages[2], MasterMessage(DateTimeRequest{{2026, 11, 22, 3, 4, 5}}));
  EXPECT_EQ(h.link.protocol(), Protocol::Dcp4);
  ASSERT_TRUE(h.link.drive_info());
  EXPECT_EQ(h.link.drive_info()->maker, (Code2{'Z', 'A'}));
  EXPECT_EQ(h.link.active_data_info_type(), DataInfoType::Decel15);
  EXPECT_TRUE(h.link.extended_position_active());
  EXPECT_TRUE(h.link.travel_allowed());
  h.cycle();
  EXPECT_EQ(h.last()[0], kB0B2);
}

TEST(DcpMasterLink, ExtendedPositionNeedsTheDrivesConsent) {
  Harness h(dcp4_config());
  h.drive.supports_extended = false;
  h.bring_up();
  EXPECT_FALSE(h.link.extended_position_active());
}

TEST(DcpMasterLink, CommunicationChannelOnlyDriveNeverTravels) {
  Harness h;
  h.drive.init.dcp_type = Protocol::ComChan;
  h.link.set_process(kB0B2, 0);
  h.bring_up();
  EXPECT_EQ(h.link.protocol(), Protocol::ComChan);
  EXPECT_FALSE(h.link.travel_allowed());
  h.cycle();
  EXPECT_EQ(h.last()[0] & 0x07, 0);
}

TEST(DcpMasterLink, DCP3DriveIsReported) {
  Harness h;
  h.drive.init.dcp_type = Protocol::Dcp3;
  h.bring_up();
  EXPECT_EQ(h.link.protocol(), Protocol::Dcp3);
  EXPECT_TRUE(h.link.travel_allowed());
}

TEST(DcpMasterLink, RestartsTheHandshakeWhenI0GetsNoReply) {
  Harness h;
  h.drive.mute = {MessageId::Init};
  ASSERT_GE(h.run_until([&] { return h.count_messages(MessageId::Init) == 2; }), 0);
  EXPECT_EQ(h.link.state(), LinkState::Init);
  EXPECT_EQ(h.link.counters().request_timeouts, 1U);
  h.drive.mute.clear();
  h.bring_up();
  EXPECT_EQ(h.drive.resets_seen, 3);  // each attempt starts with STX ETX
}

TEST(DcpMasterLink, HandshakeWithoutWallClockSkipsI3UntilOneIsGiven) {
  Harness h;
  h.bring_up();
  EXPECT_EQ(h.count_messages(MessageId::DateTime), 0);
  h.link.set_civil_time({2026, 1, 2, 3, 4, 5});
  ASSERT_GE(h.run_until([&] { return h.count_messages(MessageId::DateTime) == 1; }), 0);
}

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

// ---- I3
// -------------------------------------------------------------------------------------------

TEST(DcpMasterLink, SendsI3AgainAtTheDayChangeOnly) {
  Harness h;
  h.link.set_civil_time({2026, 11, 22, 23, 59, 50});
  h.bring_up();
  ASSERT_EQ(h.count_messages(MessageId::DateTime), 1);
  h.link.set_civil_time({2026, 11, 22, 23, 59, 59});
  h.run(40);
  EXPECT_EQ(h.count_messages(MessageId::DateTime), 1);
  h.link.set_civil_time({2026, 11, 23, 0, 0, 0});
  ASSERT_GE(h.run_until([&] { return h.count_messages(MessageId::DateTime) == 2; }), 0);
  EXPECT_EQ(h.drive.messages.back(), MasterMessage(DateTimeRequest{{2026, 11, 23, 0, 0, 0}}));
  h.run(20);
  EXPECT_TRUE(std::any_of(h.events.begin(), h.events.end(),
                          [](const LinkEvent& e) { return e.kind == LinkEventKind::TimeSent; }));
  h.link.set_civil_time({2026, 11, 23, 0, 0, 1});
  h.run(40);
  EXPECT_EQ(h.count_messages(MessageId::DateTime), 2);
}

TEST(DcpMasterLink, IgnoresAnInvalidWallClock) {
  Harness h;
  h.link.set_civil_time({2026, 2, 30, 0, 0, 0});
  h.bring_up();
  EXPECT_EQ(h.count_messages(MessageId::DateTime), 0);
}

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

// ---- config -----------------------------------------------------------------------------------

TEST(DcpMasterLinkConfig, NamesTheBadSetting) {
  // Legend: one wrong setting -> the constructor refuses it with a message.
  std::vector<std::pair<const char*, std::function<void(MasterLinkConfig&)>>> cases = {
      {"zero fault count", [](MasterLinkConfig& c) { c.fault_after_bad_frames = 0; }},
      {"zero recovery count", [](MasterLinkConfig& c) { c.recover_after_good_frames = 0; }},
      {"maker in lower case",
       [](MasterLinkConfig& c) {
         c.maker = {'l', 'd'};
       }},
      {"language with digit",
       [](MasterLinkConfig& c) {
         c.language = {'E', '1'};
       }},
      {"version of five digits", [](MasterLinkConfig& c) { c.version = 10000; }},
      {"date 31.04.",
       [](MasterLinkConfig& c) {
         c.software_date = {31, 4, 26};
       }},
      {"data-information-type '5'",
       [](MasterLinkConfig& c) { c.data_info_type = static_cast<DataInfoType>('5'); }},
      {"zero request timeout", [](MasterLinkConfig& c) { c.request_timeout = 0ms; }},
      {"reinit inside the cancel window",
       [](MasterLinkConfig& c) { c.reinit_after_reset = c.reset_cancel_window; }},
  };
  EXPECT_TRUE(config_error(MasterLinkConfig{}).empty());
  for (auto& [what, change] : cases) {
    MasterLinkConfig c;
    change(c);
    EXPECT_FALSE(config_error(c).empty()) << what;
    EXPECT_THROW(MasterLink{c}, std::invalid_argument) << what;
  }
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

// ---- tolerant handshake (DCP 5.12.2, 5.12.3.1) --------------------------------------------------

TEST(DcpMasterLink, DriveThatIgnoresI1RunsWithTypeZero) {
  // DCP 5.12.3.1: "If no message ('I' '1') is transmitted by the lift controller, the
  // data-information-type will be set to '0' on both controllers."
  MasterLinkConfig c;
  c.data_info_type = DataInfoType::Decel16;
  Harness h(c);
  h.drive.mute.insert(MessageId::DataInfo);
  ASSERT_GE(h.run_until([&] { return h.up(); }, 400), 0);
  EXPECT_TRUE(h.link.travel_allowed());
  EXPECT_EQ(h.link.active_data_info_type(), DataInfoType::Alternating);
  EXPECT_EQ(h.count_messages(MessageId::Init), 1) << "no restart for a missing I1 reply";
  EXPECT_NE(std::find_if(h.events.begin(), h.events.end(),
                         [](const LinkEvent& e) { return e.kind == LinkEventKind::Tolerated; }),
            h.events.end());
}

TEST(DcpMasterLink, OddI0FieldsAreAcceptedForTheirDcpType) {
  // An older drive: version "1.00" and date "000000" in its I0 reply (DCP 5.12.2.2 wants four
  // digits and DDMMYY). Its DCP type '3' is readable, so the link comes up as DCP3.
  Harness h;
  h.drive.mute.insert(MessageId::Init);
  ASSERT_GE(h.run_until([&] { return h.count_messages(MessageId::Init) == 1; }), 0);
  h.drive.send_frame(ChannelMode::Expanded, bytes("I0ZA1.00000000"
                                                  "3DE"));
  ASSERT_GE(h.run_until([&] { return h.up(); }), 0);
  EXPECT_TRUE(h.link.travel_allowed());
  EXPECT_EQ(h.link.protocol(), Protocol::Dcp3);
  ASSERT_TRUE(h.link.drive_info());
  EXPECT_EQ(h.link.drive_info()->anomalies, init_anomaly::kVersion | init_anomaly::kDate);
}

TEST(DcpMasterLink, UnknownDcpTypeKeepsTravelsOffAndSaysWhy) {
  Harness h;
  h.drive.mute.insert(MessageId::Init);
  ASSERT_GE(h.run_until([&] { return h.count_messages(MessageId::Init) == 1; }), 0);
  h.drive.send_frame(ChannelMode::Expanded, bytes("I0ZA0102010215"
                                                  "9DE"));
  h.run(80);
  EXPECT_FALSE(h.link.travel_allowed());
  EXPECT_EQ(h.link.handshake_problem(),
            "the drive's I0 reply names no known DCP type (DCP 5.12.2.2)");
}

TEST(DcpMasterLink, UnknownDcpTypeIsReportedNotRetriedSilently) {
  Harness h;
  h.drive.mute.insert(MessageId::Init);
  h.run(400);  // 6 s: one attempt per request timeout (2 s by default), so three
  EXPECT_FALSE(h.link.travel_allowed());
  EXPECT_EQ(h.link.handshake_problem(), "no reply to I0");
  EXPECT_GE(h.link.counters().handshake_attempts, 3U);
  const auto problems = std::count_if(h.events.begin(), h.events.end(), [](const LinkEvent& e) {
    return e.kind == LinkEventKind::HandshakeProblem;
  });
  EXPECT_EQ(problems, 1) << "said once, not every second";
}

}  // namespace
}  // namespace liftd::dcp
