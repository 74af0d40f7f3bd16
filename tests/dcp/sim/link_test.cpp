// Chapter 6/7.3 slave behaviour, the communication channel (chapter 5) and fault injection.
#include <gtest/gtest.h>

#include <cmath>

#include "sim_harness.hpp"

namespace liftd::dcp::sim {
namespace {

using namespace testing;
namespace sb = dcp::status_bit;

constexpr std::uint16_t kV4 = 0x0080;
constexpr std::uint16_t kVI = 0x0010;

bool has(std::uint8_t status, std::uint8_t bit) {
  return (status & bit) != 0;
}

dcp::FrameBytes master(std::uint8_t command, std::uint16_t data = 0, std::uint8_t c1 = 0,
                       std::uint8_t c2 = 0) {
  dcp::MasterFrame f;
  f.command = command;
  f.set_data_word(data);
  f.comm1 = c1;
  f.comm2 = c2;
  return dcp::encode(f);
}

// ------------------------------------------------------------------ chapter 6 and 7.3

TEST(SimLink, BadChecksumIsIgnoredAndAnsweredWithS7AndIdleChannel) {
  Harness m;
  m.init();
  m.send_channel(0x1C, "I3");  // make sure the drive would have channel bytes to send
  dcp::FrameBytes bad = master(cmd::kSpeed, kV4, 0x02, 0x1C);
  bad[5] ^= 0x01;
  const Cycle c = m.raw(bad);
  ASSERT_EQ(c.reply.size, 6);
  EXPECT_TRUE(has(c.status, sb::kMessageChecksumError));
  EXPECT_EQ(c.reply.bytes[3], 0x00);  // DCP 6.2 a: communication bytes 00
  EXPECT_EQ(c.reply.bytes[4], 0x00);
  EXPECT_EQ(m.sim.counters().bad_frames, 1U);
  // The next good frame clears S7.
  EXPECT_FALSE(has(m.cycle(cmd::kIdle).status, sb::kMessageChecksumError));
}

TEST(SimLink, B7RepeatsTheLastReplyChannelBytes) {
  Harness m;
  m.init();
  m.send_channel(0x1C, "I8050");
  Cycle first;
  for (int i = 0; i < 20; ++i) {
    first = m.cycle(cmd::kIdle);
    if (first.reply.bytes[3] != 0) break;
  }
  ASSERT_NE(first.reply.bytes[3], 0);
  const Cycle again = m.raw(master(cmd::kIdle | cmd::kB7));
  EXPECT_EQ(again.reply.bytes[3], first.reply.bytes[3]);
  EXPECT_EQ(again.reply.bytes[4], first.reply.bytes[4]);
  EXPECT_EQ(m.sim.counters().repeats, 1U);
}

TEST(SimLink, ChecksumBadFrameWithB7DoesNotRepeat) {
  Harness m;
  m.init();
  dcp::FrameBytes bad = master(cmd::kIdle | cmd::kB7);
  bad[5] ^= 0x10;
  m.raw(bad);
  EXPECT_EQ(m.sim.counters().repeats, 0U);
}

TEST(SimLink, TenMissingFramesDuringTravelFaultAndTenGoodRecover) {
  Harness m;
  m.init();
  m.cycle(cmd::kSpeed, kVI);
  m.repeat(cmd::kTravel, 100);
  ASSERT_GT(m.sim.velocity_mps(), 0.0);
  // DCP 7.3: 10 frames (150 ms) missing during travel; the 10th slot passed by half a cycle.
  m.now += 158ms;
  m.sim.advance(m.now);
  EXPECT_TRUE(has(m.sim.status_byte(), sb::kGeneralFault));
  EXPECT_FALSE(has(m.sim.status_byte(), sb::kTravelActive));
  // Recovers after 10 good frames while stationary.
  m.repeat(cmd::kIdle, 60);
  EXPECT_FALSE(has(m.cycle(cmd::kIdle).status, sb::kGeneralFault));
}

TEST(SimLink, NineBadFramesAreTolerated) {
  Harness m;
  m.init();
  m.cycle(cmd::kSpeed, kVI);
  m.repeat(cmd::kTravel, 100);
  dcp::FrameBytes bad = master(cmd::kTravel);
  bad[5] ^= 0xFF;
  for (int i = 0; i < 9; ++i) m.raw(bad);
  EXPECT_FALSE(has(m.cycle(cmd::kTravel).status, sb::kGeneralFault));
  for (int i = 0; i < 10; ++i) m.raw(bad);
  EXPECT_TRUE(has(m.sim.status_byte(), sb::kGeneralFault));
  // The drive reports it on the channel (DCP 5.11).
  std::string msg;
  m.repeat(cmd::kIdle, 20);
  EXPECT_TRUE(m.take_message(0x1E, msg));
  EXPECT_EQ(msg, "DCP TIMEOUT");
}

TEST(SimLink, LinkLossWhileStationaryIsNoFault) {
  Harness m;
  m.init();
  m.repeat(cmd::kIdle, 5);
  m.now += 500ms;
  m.sim.advance(m.now);
  EXPECT_FALSE(has(m.sim.status_byte(), sb::kGeneralFault));
}

// ------------------------------------------------------------------ channel

TEST(SimChannel, I0ReplyCarriesMakerVersionDateTypeAndLanguage) {
  Harness m;
  // DCP 5.12.2.2: I0 HK1 HK2 V10 V1 V0.1 V0.01 DDMMYY DCP LK1 LK2.
  EXPECT_EQ(m.init(),
            "I0KW0100221126"
            "4"
            "DE");
  EXPECT_TRUE(m.sim.initialised());
  EXPECT_TRUE(has(m.cycle(cmd::kIdle).status, sb::kReady));
}

TEST(SimChannel, I0UnknownLanguageFallsBackToEnglishAndDcp3Type) {
  DriveConfig cfg;
  cfg.protocol = dcp::Protocol::Dcp3;
  Harness m(cfg);
  m.send_channel(0x1C, "I0LI0100010126FR");
  EXPECT_EQ(m.await_channel(0x1C),
            "I0KW0100221126"
            "3"
            "EN");
}

TEST(SimChannel, InvalidI0IsRejected) {
  Harness m;
  m.send_channel(0x1C, "I0LI01x0010126DE");
  EXPECT_EQ(m.await_channel(0x1E), "INIT MESSAGE INVALID");
  EXPECT_FALSE(m.sim.initialised());
}

TEST(SimChannel, I1SetsDataInfoTypeAndExtendedReply) {
  Harness m;
  m.init();
  m.send_channel(0x1C, "I112");
  EXPECT_EQ(m.await_channel(0x1C), "I11");  // extended protocol supported
  EXPECT_EQ(m.sim.data_info_type(), dcp::DataInfoType::Extended);
  // Type '2': every data word is extended status (bit 15 set).
  for (int i = 0; i < 4; ++i) EXPECT_NE(m.cycle(cmd::kIdle).data & 0x8000, 0);
  m.send_channel(0x1C, "I100");
  EXPECT_EQ(m.await_channel(0x1C), "I1");  // base protocol
}

TEST(SimChannel, DataInfoTypeZeroAlternates) {
  Harness m;
  m.init();
  const Cycle a = m.cycle(cmd::kIdle);
  const Cycle b = m.cycle(cmd::kIdle);
  EXPECT_NE((a.data ^ b.data) & 0x8000, 0);  // one distance, one extended status
  const std::uint16_t dist = (a.data & 0x8000) != 0 ? b.data : a.data;
  EXPECT_EQ(dist, 0x7FFF);  // stationary: saturated
}

TEST(SimChannel, I2ResetClearsResettableFaultsAfterDelay) {
  DriveConfig cfg;
  cfg.fast_start_limit_ms = 500;
  Harness m(cfg);
  m.init();
  m.repeat(cmd::kSpeed, 60, 0x0004);  // fast start held past its limit
  m.repeat(cmd::kIdle, 5);
  ASSERT_TRUE(has(m.sim.status_byte(), sb::kGeneralFault));
  EXPECT_EQ(m.await_channel(0x1E), "FAST START TIMEOUT");
  m.send_channel(0x1C, "I2 R");
  EXPECT_EQ(m.await_channel(0x1C), "I2 R");
  const MonoTime answered = m.now;
  while (has(m.cycle(cmd::kIdle).status, sb::kGeneralFault) && m.now - answered < 2s) {
  }
  // DCP 5.12.4: not before 200 ms after the reply, within 1000 ms.
  EXPECT_GE(m.now - answered, 200ms);
  EXPECT_LE(m.now - answered, 1000ms);
}

TEST(SimChannel, I2ResetCanBeCancelledAndInjectedFaultIsNotResettable) {
  Harness m;
  m.init();
  m.send_channel(0x1C, "I2 R");
  EXPECT_EQ(m.await_channel(0x1C), "I2 R");
  m.send_channel(0x1C, "I2 0");
  EXPECT_EQ(m.await_channel(0x1C), "I2 0");
  m.repeat(cmd::kIdle, 80);
  SimEvent e;
  bool reset = false;
  while (m.sim.pop_event(e)) reset |= e.kind == SimEvent::Kind::DriveReset;
  EXPECT_FALSE(reset);
  m.sim.set_general_fault(true, m.now);
  m.send_channel(0x1C, "I2 R");
  EXPECT_EQ(m.await_channel(0x1C), "I2 0");
}

TEST(SimChannel, I3I6I8Replies) {
  Harness m;
  m.init();
  m.send_channel(0x1C, "I322112026123456");
  EXPECT_EQ(m.await_channel(0x1C), "I3");
  m.send_channel(0x1C, "I6U1");
  EXPECT_EQ(m.await_channel(0x1C), "I6U1");
  m.send_channel(0x1C, "I8050");
  EXPECT_EQ(m.await_channel(0x1C), "I8");
  EXPECT_EQ(m.sim.load_percent(), 50U);
  EXPECT_EQ(m.sim.power_supply(), dcp::PowerSupply::Emergency);
  EXPECT_EQ(m.sim.date_time().hour, 12);
  m.send_channel(0x1C, "I201");
  EXPECT_EQ(m.await_channel(0x1C), "I201");  // maximum torque for the next travel
  EXPECT_TRUE(m.sim.max_torque_armed());
}

TEST(SimChannel, I7RepliesWithTheSpecExamples) {
  Harness m;
  m.init();
  m.send_channel(0x1C, "I7200300");
  EXPECT_EQ(m.await_channel(0x1C), "I7s0030000143");
  m.send_channel(0x1C, "I7201000");
  EXPECT_EQ(m.await_channel(0x1C), "I7l0052000250");
}

TEST(SimChannel, I9ExtendedReportsMeasuredTravel) {
  Harness m;
  m.init('1');
  m.send_channel(0x1C, "I110");
  m.await_channel(0x1C);
  m.send_channel(0x1C, "I9+000000");
  EXPECT_EQ(m.await_channel(0x1C), "I9E000000");  // nothing measured yet
  m.cycle(cmd::kSpeed, kV4);
  for (int i = 0; i < 800; ++i) m.distance_cycle(cmd::kDecel, 3000.0);
  m.repeat(cmd::kStop, 10);
  m.repeat(cmd::kIdle, 2);
  m.send_channel(0x1C, "I9+003000");
  EXPECT_EQ(m.await_channel(0x1C), "I9+003000");
}

TEST(SimChannel, OneSecondWithoutFramesResetsChannelAndNeedsNewInit) {
  Harness m;
  m.init();
  m.now += 1100ms;
  m.sim.advance(m.now);
  EXPECT_FALSE(m.sim.initialised());
  EXPECT_FALSE(has(m.cycle(cmd::kIdle).status, sb::kReady));
}

TEST(SimChannel, StxEtxResetsAndPartialMessageExpires) {
  Harness m;
  m.init();
  m.tx.push_back(0x02);
  m.tx.push_back(0x03);
  m.repeat(cmd::kIdle, 2);
  SimEvent e;
  bool reset = false;
  while (m.sim.pop_event(e)) reset |= e.kind == SimEvent::Kind::ChannelReset;
  EXPECT_TRUE(reset);
  // STX 1C "I8" and no ETX for more than 1 s: dropped; a later ETX completes nothing.
  for (char c : std::string("\x02\x1CI8050")) m.tx.push_back(static_cast<std::uint8_t>(c));
  m.repeat(cmd::kIdle, 80);
  m.tx.push_back(0x03);
  EXPECT_EQ(m.await_channel(0x1C, 0, 20), "<none>");
}

TEST(SimChannel, KeypadShowsMenuPagesOnRemoteDisplay) {
  Harness m;
  m.init();
  // DCP 5.8: STX 1F button ETX; 0x00 = no button: the drive shows its first page.
  m.send_channel(0x1F, std::string(1, '\0'));
  std::string line;
  for (int i = 0; i < 200 && !m.take_message(0x1F, line); ++i) m.cycle(cmd::kIdle);
  ASSERT_EQ(line.size(), 22U);
  EXPECT_EQ(line[0], 0x04);  // DCP 5.6.2: line 1
  EXPECT_EQ(line[1], 0x08);  // cursor position 0
  EXPECT_EQ(line.substr(2, 8), "DCP4 SIM");
  m.repeat(cmd::kIdle, 60);  // the other three lines
  m.rx.clear();
  // Button "2": next page. The master announced German in I0 (DCP 5.12.2).
  m.send_channel(0x1F, "\x08");
  line.clear();
  for (int i = 0; i < 200 && !m.take_message(0x1F, line); ++i) m.cycle(cmd::kIdle);
  ASSERT_EQ(line.size(), 22U);
  EXPECT_EQ(line.substr(2, 7), "FAHRTEN");
  EXPECT_EQ(std::string(m.sim.display()[0].data(), 7), "FAHRTEN");
}

// ------------------------------------------------------------------ fault injection

TEST(SimFaults, GeneralFaultStopsTravelAndBlocksStart) {
  Harness m;
  m.init();
  m.cycle(cmd::kSpeed, kVI);
  m.repeat(cmd::kTravel, 100);
  m.sim.set_general_fault(true, m.now);
  const Cycle c = m.cycle(cmd::kTravel);
  EXPECT_TRUE(has(c.status, sb::kGeneralFault));
  EXPECT_FALSE(has(c.status, sb::kReady));
  EXPECT_FALSE(has(c.status, sb::kTravelActive));
  m.repeat(cmd::kIdle, 20);
  m.cycle(cmd::kSpeed, kVI);
  EXPECT_FALSE(has(m.repeat(cmd::kTravel, 20).status, sb::kTravelActive));
  m.sim.set_general_fault(false, m.now);
  EXPECT_TRUE(has(m.cycle(cmd::kIdle).status, sb::kReady));
}

TEST(SimFaults, AdvanceWarningBlocksNewTravel) {
  Harness m;
  m.init();
  m.sim.set_advance_warning(true);
  EXPECT_TRUE(has(m.cycle(cmd::kIdle).status, sb::kAdvanceWarning));
  m.cycle(cmd::kSpeed, kVI);
  EXPECT_FALSE(has(m.repeat(cmd::kTravel, 20).status, sb::kTravelActive));
}

TEST(SimFaults, NotReadyClearsS0) {
  Harness m;
  m.init();
  m.sim.set_not_ready(true);
  EXPECT_FALSE(has(m.cycle(cmd::kIdle).status, sb::kReady));
  m.sim.set_not_ready(false);
  EXPECT_TRUE(has(m.cycle(cmd::kIdle).status, sb::kReady));
}

TEST(SimFaults, ReplyFaultsForNFrames) {
  Harness m;
  m.init();
  m.sim.inject(ReplyFault::BadChecksum, 2);
  for (int i = 0; i < 2; ++i) {
    const Cycle c = m.cycle(cmd::kIdle);
    std::array<std::uint8_t, 6> b{};
    std::copy(c.reply.bytes.begin(), c.reply.bytes.begin() + 6, b.begin());
    EXPECT_FALSE(dcp::decode_slave(b).has_value());
  }
  EXPECT_TRUE(has(m.cycle(cmd::kIdle).status, sb::kReady));

  m.sim.inject(ReplyFault::MessageError, 1);
  EXPECT_TRUE(has(m.cycle(cmd::kIdle).status, sb::kMessageChecksumError));

  m.sim.inject(ReplyFault::Late, 1);
  // DCP 7.2: the master frame ends at 1.5625 ms (6 bytes at 38400 baud); a late reply must start
  // after 11.5625 ms and end after 13.625 ms: 11 ms after the frame starts it at 12.5625 ms and
  // ends it at 14.125 ms.
  const auto late = m.cycle(cmd::kIdle).reply.delay;
  EXPECT_EQ(late, 11000us);
  const auto frame_us = 1562us;
  EXPECT_GT(frame_us + late, 11563us);
  EXPECT_GT(frame_us + late + frame_us, 13625us);
  EXPECT_LT(frame_us + late + frame_us, 15000us);
  EXPECT_EQ(m.cycle(cmd::kIdle).reply.delay, 1000us);

  m.sim.inject(ReplyFault::NoReply, 1);
  EXPECT_EQ(m.cycle(cmd::kIdle).reply.size, 0);

  m.sim.inject(ReplyFault::Garbage, 1);
  EXPECT_EQ(m.cycle(cmd::kIdle).reply.size, 3);
  EXPECT_EQ(m.cycle(cmd::kIdle).reply.size, 6);
}

TEST(SimFaults, ReplyFaultRateIsRoughlyHonoured) {
  Harness m;
  m.sim.set_fault_rate(ReplyFault::NoReply, 0.25);
  int silent = 0;
  for (int i = 0; i < 4000; ++i) silent += m.cycle(cmd::kIdle).reply.size == 0 ? 1 : 0;
  EXPECT_GT(silent, 800);
  EXPECT_LT(silent, 1200);
  m.sim.clear_reply_faults();
  EXPECT_EQ(m.cycle(cmd::kIdle).reply.size, 6);
}

}  // namespace
}  // namespace liftd::dcp::sim
