// The simulated USS slave's drive profile (C 5.2.1) and its car model.
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

// ------------------------------------------------------------------------ drive profile C 5.2.1

struct Step {
  std::uint16_t stw;
  UssDriveState state;
  std::uint16_t zsw_low;  // ZSW bits 0..7
};

TEST(UssSlaveSim, DriveProfileAllowedTransitions) {
  const std::vector<Step> steps = {
      {0x0000, UssDriveState::SwitchOnInhibit, 0x40},   // bit 10 = 0: ignored
      {0x0406, UssDriveState::ReadyToSwitchOn, 0x31},   // OFF1 with OFF2/OFF3 lifted
      {0x0407, UssDriveState::Ready, 0x33},             // ON
      {0x040F, UssDriveState::OperationEnabled, 0x37},  // enable operation
      {0x0407, UssDriveState::Ready, 0x33},             // inhibit operation
      {0x0406, UssDriveState::ReadyToSwitchOn, 0x31},   // OFF1 from ready
      {0x040F, UssDriveState::OperationEnabled, 0x37},  // ON + enable at once
      {0x040E, UssDriveState::ReadyToSwitchOn, 0x31},   // OFF1 at standstill: at once
      {0x040F, UssDriveState::OperationEnabled, 0x37},
      {0x040D, UssDriveState::SwitchOnInhibit, 0x60},  // OFF2: coast
      {0x040E, UssDriveState::ReadyToSwitchOn, 0x31},  // OFF1 first (bit 1 back)
      {0x040F, UssDriveState::OperationEnabled, 0x37},
      {0x040B, UssDriveState::SwitchOnInhibit, 0x50},  // OFF3 at standstill
      {0x0406, UssDriveState::ReadyToSwitchOn, 0x31},
      {0x0403, UssDriveState::SwitchOnInhibit, 0x50},  // OFF3 from ready to switch on
      {0x0406, UssDriveState::ReadyToSwitchOn, 0x31},
      {0x0405, UssDriveState::SwitchOnInhibit, 0x60},  // OFF2 from ready to switch on
      {0x0000, UssDriveState::SwitchOnInhibit, 0x60},  // no control: old data stay
  };
  Harness h(config(PkwLength::None, 2));
  for (std::size_t i = 0; i < steps.size(); ++i) {
    SCOPED_TRACE("step " + std::to_string(i));
    const auto w = h.words(5, {steps[i].stw, 0});
    ASSERT_EQ(w.size(), 2U);
    EXPECT_EQ(h.sim.state(), steps[i].state) << to_string(h.sim.state());
    EXPECT_EQ(w[0] & 0xFF, steps[i].zsw_low);
  }
  EXPECT_TRUE(h.violations().empty());
}

TEST(UssSlaveSim, SwitchOnFromInhibitWithoutOff1IsRefusedAndRecorded) {
  Harness h(config(PkwLength::None, 2));
  h.words(5, {0x047F, 0});
  h.words(5, {0x047F, 0});  // the same word again: recorded once
  EXPECT_EQ(h.sim.state(), UssDriveState::SwitchOnInhibit);
  const auto v = h.violations();
  ASSERT_EQ(v.size(), 1U);
  EXPECT_EQ(v[0].substr(0, 7), "C 5.2.1");
  h.words(5, {0x047E, 0});
  EXPECT_EQ(h.sim.state(), UssDriveState::ReadyToSwitchOn);
  h.words(5, {0x047F, 0});
  EXPECT_EQ(h.sim.state(), UssDriveState::OperationEnabled);
}

TEST(UssSlaveSim, FaultLeftOnlyOnARisingEdgeOfBit7) {
  Harness h(config(PkwLength::None, 2));
  h.words(5, {0x047E, 0});
  h.words(5, {0x047F, 0});
  ASSERT_EQ(h.sim.state(), UssDriveState::OperationEnabled);
  h.sim.set_drive_fault(true);
  auto w = h.words(5, {0x047F, 0});
  EXPECT_EQ(w[0] & 0x0F, 0x08);  // fault, bits 0..2 off
  h.words(5, {0x04FF, 0});       // rising edge while the cause is still there
  EXPECT_EQ(h.sim.state(), UssDriveState::Fault);
  h.sim.set_drive_fault(false);
  h.words(5, {0x04FF, 0});  // bit 7 held: no edge
  EXPECT_EQ(h.sim.state(), UssDriveState::Fault);
  h.words(5, {0x047F, 0});
  w = h.words(5, {0x04FF, 0});  // the edge
  EXPECT_EQ(h.sim.state(), UssDriveState::SwitchOnInhibit);
  EXPECT_EQ(w[0] & 0x4F, 0x40);
  EXPECT_EQ(h.sim.parameter(60), 0U);
}

TEST(UssSlaveSim, TelegramTimeoutTripsAfterTheFirstGoodTelegram) {
  auto c = config(PkwLength::None, 2);
  c.telegram_timeout = 100ms;
  Harness h(c);
  h.now += 1s;  // no monitoring before the first telegram (C 3.1)
  h.sim.on_time(h.now);
  EXPECT_NE(h.sim.state(), UssDriveState::Fault);
  h.words(5, {0x047E, 0});
  h.now += 101ms;
  h.sim.on_time(h.now);
  EXPECT_EQ(h.sim.state(), UssDriveState::Fault);
  EXPECT_EQ(h.sim.parameter(60), 2U);
  EXPECT_EQ(h.sim.rx_counters().error_word & 0x80, 0x80);
  h.words(5, {0x047E, 0});
  h.words(5, {0x04FE, 0});
  EXPECT_EQ(h.sim.state(), UssDriveState::SwitchOnInhibit);
}

// -------------------------------------------------------------------------------- car model

TEST(UssSlaveSim, CarFollowsTheRampOnlyWithOperationEnabled) {
  auto c = config(PkwLength::None, 2);
  c.car.nominal_mps = 1.0;
  c.car.accel_mps2 = 0.5;
  c.car.floors_mm = {0.0, 3000.0};
  Harness h(c);
  h.words(5, {0x0476, 0x4000});  // ready to switch on, setpoint 100 %
  h.words(5, {0x0477, 0x4000});  // ready: no pulses, brake closed
  h.now += 1s;
  h.sim.on_time(h.now);
  EXPECT_EQ(h.sim.position_mm(), 0.0);
  EXPECT_EQ(h.sim.floor_at(), 0);
  h.words(5, {0x047F, 0x4000});          // operation enabled
  const MonoTime start = h.request_end;  // the telegram took effect at its last character
  h.now = start + 1s;
  h.sim.on_time(h.now);
  EXPECT_NEAR(h.sim.velocity_mps(), 0.5, 1e-9);
  EXPECT_NEAR(h.sim.position_mm(), 250.0, 2.0);  // 1/2 a t^2
  h.now = start + 3s;
  h.sim.on_time(h.now);
  EXPECT_NEAR(h.sim.velocity_mps(), 1.0, 1e-9);
  const auto w = h.words(5, {0x047F, 0x4000});
  EXPECT_NEAR(static_cast<std::int16_t>(w[1]), 0x4000, 2);  // HIW
  EXPECT_EQ(w[0] & 0x0500, 0x0500);                         // setpoint and speed reached
  // OFF1: down the ramp, then ready to switch on; the car stands.
  h.words(5, {0x047E, 0x4000});
  EXPECT_EQ(h.sim.state(), UssDriveState::RampStop);
  h.now += 2100ms;
  h.sim.on_time(h.now);
  EXPECT_EQ(h.sim.velocity_mps(), 0.0);
  EXPECT_EQ(h.sim.state(), UssDriveState::ReadyToSwitchOn);
  const double stopped = h.sim.position_mm();
  h.now += 1s;
  h.sim.on_time(h.now);
  EXPECT_EQ(h.sim.position_mm(), stopped);
}

TEST(UssSlaveSim, CoastStopsTheCarAtOnceAndQuickStopRampsFaster) {
  auto c = config(PkwLength::None, 2);
  c.car.accel_mps2 = 0.5;
  c.car.quick_stop_mps2 = 2.0;
  Harness h(c);
  h.words(5, {0x047E, 0x4000});
  h.words(5, {0x047F, 0x4000});
  h.now += 2s;
  h.sim.on_time(h.now);
  h.words(5, {0x047D, 0x4000});  // OFF2
  EXPECT_EQ(h.sim.state(), UssDriveState::SwitchOnInhibit);
  h.now += 1ms;
  h.sim.on_time(h.now);
  EXPECT_EQ(h.sim.velocity_mps(), 0.0);
  h.words(5, {0x047E, 0x4000});
  h.words(5, {0x047F, 0x4000});
  h.now += 2s;
  h.sim.on_time(h.now);
  h.words(5, {0x047B, 0x4000});  // OFF3
  EXPECT_EQ(h.sim.state(), UssDriveState::QuickStop);
  h.now += 520ms;
  h.sim.on_time(h.now);
  EXPECT_EQ(h.sim.velocity_mps(), 0.0);
  EXPECT_EQ(h.sim.state(), UssDriveState::SwitchOnInhibit);
}

TEST(UssSlaveSim, DownwardSetpointAndRampFreeze) {
  auto c = config(PkwLength::None, 2);
  c.car.bottom_mm = -5000.0;
  Harness h(c);
  h.words(5, {0x047E, 0xC000});  // -100 %
  h.words(5, {0x047F, 0xC000});
  h.now += 1s;
  h.sim.on_time(h.now);
  EXPECT_NEAR(h.sim.velocity_mps(), -0.5, 0.01);
  h.words(5, {0x045F, 0xC000});  // bit 5 = 0: ramp frozen
  h.now += 1s;
  h.sim.on_time(h.now);
  EXPECT_NEAR(h.sim.velocity_mps(), -0.5, 0.01);
  EXPECT_LT(h.sim.position_mm(), -500.0);
}

}  // namespace
