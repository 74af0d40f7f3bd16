// The master side of the drive profile (USS C 5.2.1): ZSW -> state, wish + state -> the exact
// STW bits, the fault acknowledge edge and the timing supervision, with a fake clock.
#include <gtest/gtest.h>

#include <chrono>

#include "uss/drive/drive_profile.hpp"

namespace liftd::uss {
namespace {

using std::chrono::milliseconds;

// ZSW bits (C 5.2.1 table 5.5, 5.6) spelt out, so the tables below read like the spec.
constexpr std::uint16_t kRtso = 1U << 0, kRdy = 1U << 1, kOpEn = 1U << 2, kFlt = 1U << 3,
                        kNo2 = 1U << 4, kNo3 = 1U << 5, kInh = 1U << 6, kWarn = 1U << 7,
                        kPlc = 1U << 9;

TEST(DecodeStatus, EveryStateOfTable55) {
  struct Case {
    std::uint16_t zsw;
    bool off1_sent;
    ProfileState state;
  };
  const Case cases[] = {
      {0x0000, false, ProfileState::Off2Active},  // bits 4, 5 are active low
      {kNo2 | kNo3, false, ProfileState::NotReadyToSwitchOn},
      {kNo2 | kNo3 | kInh, false, ProfileState::SwitchOnInhibit},
      {kNo2 | kNo3 | kInh | kPlc, false, ProfileState::SwitchOnInhibit},
      {kNo2 | kNo3 | kRtso, false, ProfileState::ReadyToSwitchOn},
      {kNo2 | kNo3 | kRtso | kRdy, false, ProfileState::Ready},
      {kNo2 | kNo3 | kRtso | kRdy | kOpEn, false, ProfileState::OperationEnabled},
      {kNo2 | kNo3 | kRtso | kRdy | kOpEn | kWarn, false, ProfileState::OperationEnabled},
      {kNo2 | kNo3 | kRtso | kRdy | kOpEn, true, ProfileState::Off1Active},
      {kNo2 | kNo3 | kRtso | kRdy, true, ProfileState::Ready},
      {kNo3 | kRtso | kRdy | kOpEn, false, ProfileState::Off2Active},
      {kNo2 | kRtso | kRdy | kOpEn, false, ProfileState::Off3Active},
      {kNo2 | kRtso | kRdy | kOpEn, true, ProfileState::Off3Active},
      {kNo3 | kInh, false, ProfileState::SwitchOnInhibit},  // OFF2 done: inhibit
      {kNo2 | kNo3 | kFlt, false, ProfileState::Fault},
      {kNo2 | kNo3 | kFlt | kInh, false, ProfileState::Fault},
      {kFlt | kRtso | kRdy | kOpEn, false, ProfileState::Fault},
  };
  for (const Case& c : cases) {
    EXPECT_EQ(decode_status(c.zsw, c.off1_sent), c.state)
        << std::hex << "zsw=0x" << c.zsw << " off1=" << c.off1_sent;
  }
}

TEST(ControlWord, ExactBitsPerWishAndState) {
  // Bits: 0 ON, 1 no OFF2, 2 no OFF3, 3 enable operation, 4 ramp generator enable, 5 ramp
  // start, 6 setpoint enable, 7 acknowledge, 10 control by PLC (C 5.2.1 tables 5.2 - 5.4).
  EXPECT_EQ(control::kRun, 0x047F);
  EXPECT_EQ(control::kStop, 0x047E);
  EXPECT_EQ(control::kCoast, 0x0404);
  EXPECT_EQ(control::kQuickStop, 0x040A);
  struct Case {
    ProfileWish wish;
    ProfileState state;
    std::uint16_t stw;
  };
  const Case cases[] = {
      // Run: OFF1 first out of inhibit, not ready, fault and a running OFF2 / OFF3.
      {ProfileWish::Run, ProfileState::SwitchOnInhibit, 0x047E},
      {ProfileWish::Run, ProfileState::NotReadyToSwitchOn, 0x047E},
      {ProfileWish::Run, ProfileState::Fault, 0x047E},
      {ProfileWish::Run, ProfileState::Off2Active, 0x047E},
      {ProfileWish::Run, ProfileState::Off3Active, 0x047E},
      {ProfileWish::Run, ProfileState::ReadyToSwitchOn, 0x047F},
      {ProfileWish::Run, ProfileState::Ready, 0x047F},
      {ProfileWish::Run, ProfileState::OperationEnabled, 0x047F},
      {ProfileWish::Run, ProfileState::Off1Active, 0x047F},
      // The stops do not depend on the state.
      {ProfileWish::Stop, ProfileState::OperationEnabled, 0x047E},
      {ProfileWish::Stop, ProfileState::SwitchOnInhibit, 0x047E},
      {ProfileWish::Coast, ProfileState::OperationEnabled, 0x0404},
      {ProfileWish::Coast, ProfileState::Fault, 0x0404},
      {ProfileWish::QuickStop, ProfileState::OperationEnabled, 0x040A},
      {ProfileWish::QuickStop, ProfileState::Ready, 0x040A},
  };
  for (const Case& c : cases) {
    EXPECT_EQ(control_word(c.wish, c.state), c.stw)
        << to_string(c.wish) << " in " << to_string(c.state);
  }
}

class ProfileTest : public ::testing::Test {
 protected:
  std::uint16_t step(ProfileWish wish, int t_ms, std::uint16_t zsw, bool link = true) {
    ProfileInput in;
    in.now = milliseconds(t_ms);
    in.zsw = zsw;
    in.replies = replies_;
    in.link_ok = link;
    return profile_.step(wish, in);
  }
  ProfileConfig config_;
  DriveProfile profile_{config_};
  std::uint64_t replies_ = 100;
};

TEST_F(ProfileTest, RunFromInhibitSendsOff1UntilReadyToSwitchOnThenOn) {
  const std::uint16_t inhibit = kNo2 | kNo3 | kInh | kPlc;
  const std::uint16_t rtso = kNo2 | kNo3 | kRtso | kPlc;
  const std::uint16_t ready = rtso | kRdy;
  const std::uint16_t enabled = ready | kOpEn;
  EXPECT_EQ(step(ProfileWish::Run, 0, inhibit), 0x047E);
  EXPECT_EQ(step(ProfileWish::Run, 10, inhibit), 0x047E);
  EXPECT_EQ(step(ProfileWish::Run, 20, rtso), 0x047F);
  EXPECT_EQ(step(ProfileWish::Run, 30, ready), 0x047F);
  EXPECT_EQ(step(ProfileWish::Run, 40, enabled), 0x047F);
  EXPECT_EQ(profile_.state(), ProfileState::OperationEnabled);
  EXPECT_EQ(step(ProfileWish::Stop, 50, enabled), 0x047E);
  EXPECT_EQ(step(ProfileWish::Stop, 60, enabled), 0x047E);
  EXPECT_EQ(profile_.state(), ProfileState::Off1Active) << "OFF1 sent, pulses still on";
  EXPECT_EQ(step(ProfileWish::Stop, 70, rtso), 0x047E);
  EXPECT_EQ(profile_.state(), ProfileState::ReadyToSwitchOn);
  EXPECT_EQ(profile_.supervision(), Supervision::None);
}

TEST_F(ProfileTest, AcknowledgeIsOneRisingEdgeTheDriveSawTheZeroOf) {
  const std::uint16_t fault = kNo2 | kNo3 | kFlt | kPlc;
  const std::uint16_t inhibit = kNo2 | kNo3 | kInh | kPlc;
  // Before the acknowledgement: the idle word, bit 7 low.
  EXPECT_EQ(step(ProfileWish::Stop, 0, fault), 0x047E);
  profile_.acknowledge();
  EXPECT_TRUE(profile_.acknowledging());
  // The 0 goes out (again) and stays until a reply to a telegram sent after it came.
  EXPECT_EQ(step(ProfileWish::Stop, 10, fault), 0x047E);
  EXPECT_EQ(step(ProfileWish::Stop, 20, fault), 0x047E) << "no reply yet: still 0";
  ++replies_;  // the drive answered the telegram with bit 7 = 0
  EXPECT_EQ(step(ProfileWish::Stop, 30, fault), 0x04FE) << "then the 1: the rising edge";
  EXPECT_EQ(step(ProfileWish::Stop, 40, fault), 0x04FE) << "held until the drive answered it";
  ++replies_;
  EXPECT_EQ(step(ProfileWish::Stop, 50, fault), 0x04FE) << "held while the fault is reported";
  ++replies_;
  EXPECT_EQ(step(ProfileWish::Stop, 60, inhibit), 0x047E) << "fault gone: bit 7 back to 0";
  EXPECT_FALSE(profile_.acknowledging());
  EXPECT_EQ(step(ProfileWish::Stop, 70, inhibit), 0x047E);
}

TEST_F(ProfileTest, AcknowledgeEndsAfterTheHoldTimeWhenTheFaultStays) {
  const std::uint16_t fault = kNo2 | kNo3 | kFlt | kPlc;
  profile_.acknowledge();
  EXPECT_EQ(step(ProfileWish::Coast, 0, fault), 0x0404);
  ++replies_;
  EXPECT_EQ(step(ProfileWish::Coast, 10, fault), 0x0484);
  replies_ += 50;
  EXPECT_EQ(step(ProfileWish::Coast, 1009, fault), 0x0484);
  EXPECT_EQ(step(ProfileWish::Coast, 1010, fault), 0x0404) << "acknowledge_hold_ms = 1000";
  EXPECT_FALSE(profile_.acknowledging());
}

TEST_F(ProfileTest, SupervisionLatchesAStateNotReachedInTime) {
  const std::uint16_t ready = kNo2 | kNo3 | kRtso | kRdy | kPlc;
  const std::uint16_t enabled = ready | kOpEn;
  step(ProfileWish::Run, 0, ready);
  step(ProfileWish::Run, 1999, ready);
  EXPECT_EQ(profile_.supervision(), Supervision::None);
  step(ProfileWish::Run, 2000, ready);
  EXPECT_EQ(profile_.supervision(), Supervision::NotSwitchedOn) << "switch_on_timeout_ms";
  step(ProfileWish::Run, 2010, enabled);
  EXPECT_EQ(profile_.supervision(), Supervision::NotSwitchedOn) << "latched";
  profile_.acknowledge();
  EXPECT_EQ(profile_.supervision(), Supervision::None);

  // A stop whose ZSW bit 2 stays: stop_timeout_ms from the wish.
  step(ProfileWish::Stop, 3000, enabled);
  step(ProfileWish::Stop, 7999, enabled);
  EXPECT_EQ(profile_.supervision(), Supervision::None);
  step(ProfileWish::Stop, 8000, enabled);
  EXPECT_EQ(profile_.supervision(), Supervision::NotStopped);
}

TEST_F(ProfileTest, SupervisionWaitsWhileTheLinkIsDownAndRestartsWhenTheGoalHolds) {
  const std::uint16_t ready = kNo2 | kNo3 | kRtso | kRdy | kPlc;
  const std::uint16_t enabled = ready | kOpEn;
  step(ProfileWish::Run, 0, ready);
  step(ProfileWish::Run, 1500, ready, /*link=*/false);
  step(ProfileWish::Run, 3000, ready, /*link=*/false);
  EXPECT_EQ(profile_.supervision(), Supervision::None) << "no current replies: nothing judged";
  step(ProfileWish::Run, 4999, ready);
  EXPECT_EQ(profile_.supervision(), Supervision::None);
  step(ProfileWish::Run, 5000, enabled);
  step(ProfileWish::Run, 6000, ready);  // dropped out: the clock runs from the last good state
  step(ProfileWish::Run, 6999, ready);
  EXPECT_EQ(profile_.supervision(), Supervision::None);
  step(ProfileWish::Run, 7000, ready);
  EXPECT_EQ(profile_.supervision(), Supervision::NotSwitchedOn);
}

TEST(ProfilePlcControl, ZswBit9) {
  ProfileConfig config;
  DriveProfile profile(config);
  EXPECT_FALSE(profile.plc_control(kNo2 | kNo3 | kRtso));
  EXPECT_TRUE(profile.plc_control(kNo2 | kNo3 | kRtso | kPlc));
  config.require_plc_control = false;
  EXPECT_TRUE(DriveProfile(config).plc_control(kNo2 | kNo3 | kRtso));
}

}  // namespace
}  // namespace liftd::uss
