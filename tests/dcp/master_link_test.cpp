// The master link engine against a scripted fake drive, with a fake clock: handshake, DCP 6
// error handling, DCP 7.3 supervision, channel timeouts, I3 at day change, requests and timeouts,
// the I2 reset window.
#include "dcp/master_link.hpp"

#include <gtest/gtest.h>

#include <vector>

#include "master_link_harness.hpp"

namespace liftd::dcp {
namespace {

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

}  // namespace
}  // namespace liftd::dcp
