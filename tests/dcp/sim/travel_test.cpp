// Travel sequences of the simulated drive (DCP 9 to 13) with a fake clock: S-bit order and
// timing, landing, extensions, crawl limit, DCP3, inspection, relevelling, fast start/stop.
#include <gtest/gtest.h>

#include <cmath>
#include <optional>

#include "sim_harness.hpp"

namespace liftd::dcp::sim {
namespace {

using namespace testing;
namespace sb = dcp::status_bit;

constexpr std::uint16_t kV4 = 0x0080;  // G7
constexpr std::uint16_t kV3 = 0x0040;  // G6
constexpr std::uint16_t kVN = 0x0002;  // G1
constexpr std::uint16_t kVF = 0x0004;  // G2
constexpr std::uint16_t kVI = 0x0010;  // G4
constexpr std::uint16_t kV0 = 0x0001;  // G0

bool has(std::uint8_t status, std::uint8_t bit) {
  return (status & bit) != 0;
}

// First cycle index (from `from`) where `pred` holds on the status, or nullopt.
template <class Pred>
std::optional<std::size_t> first(const std::vector<Cycle>& h, std::size_t from, Pred pred) {
  for (std::size_t i = from; i < h.size(); ++i) {
    if (pred(h[i].status)) return i;
  }
  return std::nullopt;
}

// Runs a DCP4 remaining-distance travel to `target_mm` like a master would: speed message,
// then B2+B0 with target - position every cycle until S6 drops, then B0 until S1 drops.
void dcp4_travel(Harness& m, double target_mm, std::uint16_t speed = kV4, int limit = 4000) {
  const bool down = target_mm < m.sim.position_mm();
  const std::uint8_t dir = down ? cmd::kDown : 0;
  m.cycle(cmd::kSpeed | dir, speed);
  bool moved = false;
  for (int i = 0; i < limit; ++i) {
    const Cycle c = m.distance_cycle(cmd::kDecel | dir, target_mm);
    if (has(c.status, sb::kBrakeOpen)) moved = true;
    if (moved && !has(c.status, sb::kBrakeOpen)) break;
  }
  for (int i = 0; i < limit && has(m.cycle(cmd::kStop | dir).status, sb::kTravelActive); ++i) {
  }
  m.cycle(cmd::kIdle);
}

TEST(SimTravel, NoTravelWithoutInit) {
  // DCP 5.12.2: without a valid I0 the drive is not ready and does not travel.
  Harness m;
  EXPECT_FALSE(has(m.cycle(cmd::kIdle).status, sb::kReady));
  m.cycle(cmd::kSpeed, kV4);
  const Cycle c = m.repeat(cmd::kDecel, 40, 3000);
  EXPECT_FALSE(has(c.status, sb::kTravelActive));
  EXPECT_EQ(m.sim.position_mm(), 0.0);
}

TEST(SimTravel, Dcp4TravelStatusSequenceAndLanding) {
  Harness m;
  m.init();
  ASSERT_TRUE(has(m.cycle(cmd::kIdle).status, sb::kReady));
  const std::size_t start = m.history.size();
  dcp4_travel(m, 3000.0);
  const auto& h = m.history;
  const auto s1_on = first(h, start, [](std::uint8_t s) { return has(s, sb::kTravelActive); });
  const auto s6_on = first(h, start, [](std::uint8_t s) { return has(s, sb::kBrakeOpen); });
  ASSERT_TRUE(s1_on && s6_on);
  const auto s6_off = first(h, *s6_on, [](std::uint8_t s) { return !has(s, sb::kBrakeOpen); });
  ASSERT_TRUE(s6_off);
  const auto s1_off = first(h, *s6_off, [](std::uint8_t s) { return !has(s, sb::kTravelActive); });
  ASSERT_TRUE(s1_off);
  // S1 comes with the start command, S6 after the 300 ms magnetising time.
  EXPECT_EQ(*s1_on, start + 1);
  const auto magnetising = h[*s6_on].at - h[*s1_on].at;
  EXPECT_GE(magnetising, 300ms);
  EXPECT_LE(magnetising, 315ms);
  // S6 drops at standstill, S1 follows after ~100 ms holding torque.
  const auto hold = h[*s1_off].at - h[*s6_off].at;
  EXPECT_GE(hold, 100ms);
  EXPECT_LE(hold, 115ms);
  EXPECT_EQ(h[*s6_off].velocity_mps, 0.0);
  // S5 accepted during the travel; S4 when slow.
  EXPECT_TRUE(has(h[*s6_on].status, sb::kAccepted));
  EXPECT_TRUE(has(h[*s6_off].status, sb::kBelowLevelling));
  // Landing well under 1 mm.
  EXPECT_NEAR(m.sim.position_mm(), 3000.0, 1.0);
  EXPECT_EQ(m.sim.last_travel_mm(), 3000);
  // Peak speed of a 3 m travel stays below V4 (short travel).
  double vmax = 0;
  for (const auto& c : h) vmax = std::max(vmax, std::fabs(c.velocity_mps));
  EXPECT_GT(vmax, 1.0);
  EXPECT_LT(vmax, 1.6);
}

TEST(SimTravel, Dcp4DownTravelAndDecelerationDistanceWord) {
  DriveConfig cfg;
  cfg.start_position_mm = 20000;
  Harness m(cfg);
  m.init('1');  // data-information-type '1': 15-bit deceleration distance only
  const std::size_t start = m.history.size();
  dcp4_travel(m, 10000.0);
  EXPECT_NEAR(m.sim.position_mm(), 10000.0, 1.0);
  EXPECT_EQ(m.sim.last_travel_mm(), -10000);
  // DCP 4.2.1.2: 0x7FFF while stationary/starting, counts up while accelerating, then
  // constant: the largest value is the deceleration distance from V4 (2.50 m).
  std::uint16_t prev = 0;
  bool counting = false;
  std::uint16_t max = 0;
  for (std::size_t i = start; i < m.history.size(); ++i) {
    const auto& c = m.history[i];
    if (!has(c.status, sb::kBrakeOpen)) {
      EXPECT_EQ(c.data, 0x7FFF) << i;
      continue;
    }
    if (c.data == 0x7FFF) continue;  // brake lifting, not moving yet
    if (counting) {
      EXPECT_GE(c.data, prev) << "never counts down";
    }
    counting = true;
    prev = c.data;
    max = std::max(max, c.data);
  }
  EXPECT_NEAR(max, 2499, 2);
}

TEST(SimTravel, Dcp4SaturatedFifteenBitDistanceIsFollowedToTheFarLevel) {
  // DCP 3.5.3.4: 40 m is sent as 0x7FFF until the car is within 32.767 m; the drive keeps
  // extending its target and lands exactly.
  Harness m;
  m.init();
  m.cycle(cmd::kSpeed, kV4);
  bool moved = false;
  for (int i = 0; i < 4000; ++i) {
    const Cycle c = m.distance_cycle(cmd::kDecel, 40000.0);
    moved |= has(c.status, sb::kBrakeOpen);
    if (moved && !has(c.status, sb::kBrakeOpen)) break;
  }
  EXPECT_NEAR(m.sim.position_mm(), 40000.0, 1.0);
}

TEST(SimTravel, Dcp4SixteenBitDistanceWithDataInfoTypeThree) {
  Harness m;
  m.init('3');  // 16-bit remaining distance and 16-bit deceleration distance
  EXPECT_EQ(m.cycle(cmd::kIdle).data, 0xFFFF);  // stationary: 16-bit saturation
  m.cycle(cmd::kSpeed, kV4);
  bool moved = false;
  for (int i = 0; i < 4000; ++i) {
    const Cycle c = m.distance_cycle(cmd::kDecel, 50000.0, 65535.0);
    moved |= has(c.status, sb::kBrakeOpen);
    if (moved && !has(c.status, sb::kBrakeOpen)) break;
  }
  EXPECT_NEAR(m.sim.position_mm(), 50000.0, 1.0);
  EXPECT_EQ(m.sim.counters().extensions, 0U);  // one target from the start
}

TEST(SimTravel, Dcp4LateExtensionIsImplausibleClearsS5AndStops) {
  Harness m;
  m.init();
  m.cycle(cmd::kSpeed, kV4);
  double target = 5000.0;
  bool extended_late = false;
  for (int i = 0; i < 3000; ++i) {
    const Cycle c = m.distance_cycle(cmd::kDecel, target);
    // Extend once early (while accelerating) to 10 m.
    if (i == 40) target = 10000.0;
    // Try once late, while decelerating, to 12 m: must be refused.
    if (!extended_late && c.velocity_mps > 0 && target - m.sim.position_mm() < 1500.0) {
      target = 12000.0;
      extended_late = true;
    }
    if (extended_late && c.velocity_mps == 0.0 && !has(c.status, sb::kBrakeOpen)) break;
  }
  EXPECT_EQ(m.sim.counters().extensions, 1U);
  // DCP 4.1 note: "If a plausibility error is found in the remaining distance transmitted, the
  // drive controller should carry out an emergency stop": the car stops short of even the old
  // target on the emergency ramp, S5 cleared until it stands.
  EXPECT_EQ(m.sim.counters().refused_extensions, 1U);
  EXPECT_EQ(m.sim.counters().implausible, 1U);
  EXPECT_LT(m.sim.position_mm(), 10000.0 - 100.0);
}

TEST(SimTravel, Dcp4NearerLevelTheCarCanStillReachIsTakenOver) {
  // DCP 3.5.3.4 "the drive unit must process always the remaining distance during the total
  // travel": a nearer target beyond the stopping distance is plausible.
  Harness m;
  m.init();
  m.cycle(cmd::kSpeed, kV4);
  double target = 15000.0;
  bool shortened = false;
  for (int i = 0; i < 4000; ++i) {
    const Cycle c = m.distance_cycle(cmd::kDecel, target);
    if (!shortened && c.velocity_mps > 1.5) {
      target = 9000.0;  // well beyond the ~2.5 m the car needs from 1.6 m/s
      shortened = true;
    }
    if (shortened && c.velocity_mps == 0.0 && !has(c.status, sb::kBrakeOpen)) break;
  }
  EXPECT_EQ(m.sim.counters().shortened, 1U);
  EXPECT_EQ(m.sim.counters().implausible, 0U);
  EXPECT_NEAR(m.sim.position_mm(), 9000.0, 1.0);
}

// Runs a DCP4 travel towards 12 m until the car is at V4, then sends one remaining distance
// that is `error_mm` short of the truth as measured `held_up` before the frame is read (the
// frame arriving that much after its 15 ms slot), then travels on to the 12 m target.
struct HeldUpFrame {
  std::chrono::milliseconds held_up;
  double error_mm;
};
Harness travel_with_one_odd_frame(HeldUpFrame odd) {
  Harness m;
  m.init();
  m.cycle(cmd::kSpeed, kV4);
  constexpr double kTarget = 12000.0;
  for (int i = 0; i < 4000 && m.sim.velocity_mps() < 1.6 - 1e-9; ++i) {
    m.distance_cycle(cmd::kDecel, kTarget);
  }
  m.sim.advance(m.now + 15ms);
  const double measured_at = m.sim.position_mm();
  m.now += odd.held_up;
  m.cycle(cmd::kDecel,
          static_cast<std::uint16_t>(std::lround(kTarget - measured_at - odd.error_mm)));
  for (int i = 0; i < 4000; ++i) {
    const Cycle c = m.distance_cycle(cmd::kDecel, kTarget);
    if (c.velocity_mps == 0.0 && !has(c.status, sb::kBrakeOpen)) break;
  }
  return m;
}

TEST(SimTravel, Dcp4FrameHeldUpOnItsWayIsNotATargetChange) {
  // A remaining distance measured 60 ms before the drive reads it is 96 mm too long at 1.6 m/s:
  // the frame's age, not a new target. Read on time, the same frame moves the target.
  const Harness late = travel_with_one_odd_frame({60ms, 0.0});
  EXPECT_EQ(late.sim.counters().extensions, 0U);
  EXPECT_EQ(late.sim.counters().shortened, 0U);
  EXPECT_EQ(late.sim.counters().implausible, 0U);
  EXPECT_NEAR(late.sim.position_mm(), 12000.0, 1.0);

  const Harness on_time = travel_with_one_odd_frame({0ms, 96.0});
  EXPECT_EQ(on_time.sim.counters().shortened, 1U) << "96 mm nearer, read on time, is a change";
}

TEST(SimTravel, Dcp4NearerLevelReadLateIsRefinedAsTheCarSlowsAndLandsOnTheLevel) {
  // DCP 3.5.3.4: "the drive unit must process always the remaining distance during the total
  // travel". The first frame with a nearer level (9 m instead of 15 m) was measured 20 ms
  // before the drive reads it: 32 mm long at 1.6 m/s, within the frame-age tolerance, so the
  // drive takes the level 32 mm too far. The frames that follow are on time; as the car slows
  // their error shrinks, and the drive must follow them onto the level the master means.
  Harness m;
  m.init();
  m.cycle(cmd::kSpeed, kV4);
  for (int i = 0; i < 4000 && m.sim.velocity_mps() < 1.6 - 1e-9; ++i) {
    m.distance_cycle(cmd::kDecel, 15000.0);
  }
  m.sim.advance(m.now + 15ms);
  const double measured_at = m.sim.position_mm();
  m.now += 20ms;
  m.cycle(cmd::kDecel, static_cast<std::uint16_t>(std::lround(9000.0 - measured_at)));
  EXPECT_EQ(m.sim.counters().shortened, 1U);
  for (int i = 0; i < 4000; ++i) {
    const Cycle c = m.distance_cycle(cmd::kDecel, 9000.0);
    if (c.velocity_mps == 0.0 && !has(c.status, sb::kBrakeOpen)) break;
  }
  EXPECT_EQ(m.sim.counters().shortened, 1U) << "refinements are not new targets";
  EXPECT_EQ(m.sim.counters().extensions, 0U);
  EXPECT_EQ(m.sim.counters().implausible, 0U);
  EXPECT_NEAR(m.sim.position_mm(), 9000.0, 1.0);
}

// A service stop as liftd makes it: a DCP4 travel to 15 m is cut short to the next possible level
// (6 m) while the car still speeds up, and every frame reaches the drive `lag` after the master
// measured the car (the thread hand-offs of a loaded machine).
Harness service_stop_with_lag(std::chrono::milliseconds lag, DriveConfig config = {}) {
  Harness m(config);
  m.init();
  m.cycle(cmd::kSpeed, kV4);
  double target = 15000.0;
  bool shortened = false;
  for (int i = 0; i < 4000; ++i) {
    m.sim.advance(m.now + 15ms - lag);
    const double rd = std::clamp(target - m.sim.position_mm(), 0.0, 32767.0);
    const Cycle c = m.cycle(cmd::kDecel, static_cast<std::uint16_t>(std::lround(rd)));
    if (!shortened && m.sim.position_mm() > 1570.0) {
      target = 6000.0;
      shortened = true;
    }
    if (shortened && c.velocity_mps == 0.0 && !has(c.status, sb::kBrakeOpen)) break;
  }
  return m;
}

class NearerLevelWithMeasuringLag : public ::testing::TestWithParam<int> {};

TEST_P(NearerLevelWithMeasuringLag, EveryFrameLateByTheLagStillLandsOnTheLevel) {
  // DCP 3.5.3.4: the drive follows the remaining distance onto the level; the readings' lag
  // shrinks with the speed, and a reading of 0 near the level must not make it stop behind the
  // car.
  const Harness m = service_stop_with_lag(std::chrono::milliseconds(GetParam()));
  EXPECT_EQ(m.sim.counters().shortened, 1U);
  EXPECT_EQ(m.sim.counters().implausible, 0U);
  EXPECT_NEAR(m.sim.position_mm(), 6000.0, 2.0);
}

TEST(SimTravel, Dcp4ZeroWhileTheCarIsPastItsTargetIsNotImplausible) {
  // DCP 3.5.3.4: 0 says the car is at its target. The late readings of the service stop above
  // make the drive brake on its hardest ramp and run a little past its target before it comes
  // back; the master, seeing the car past the level, sends 0. That agrees with the drive however
  // small its tolerance for jitter (here 1 mm), and is no plausibility error.
  DriveConfig strict;
  strict.distance_tolerance_mm = 1;
  const Harness m = service_stop_with_lag(20ms, strict);
  EXPECT_EQ(m.sim.counters().implausible, 0U);
  EXPECT_NEAR(m.sim.position_mm(), 6000.0, 2.0);
}

INSTANTIATE_TEST_SUITE_P(LagMs, NearerLevelWithMeasuringLag, ::testing::Values(0, 5, 10, 20, 30));

TEST(SimTravel, StopMessageAtSpeedIsAViolationAndAnEmergencyStop) {
  // DCP 3.5.3.2: stop mode 0001 "During deceleration" only; DCP 11.1.1 d: B2 "remains
  // activated until the lift car comes to the level".
  Harness m;
  m.init();
  m.cycle(cmd::kSpeed, kV4);
  for (int i = 0; i < 4000; ++i) {
    const Cycle c = m.distance_cycle(cmd::kDecel, 15000.0);
    if (c.velocity_mps > 1.5) break;
  }
  for (int i = 0; i < 400 && m.sim.velocity_mps() != 0.0; ++i) m.cycle(cmd::kStop, 0);
  EXPECT_EQ(m.sim.violations(dcp::sim::Violation::StopAtSpeed), 1U);
  EXPECT_EQ(m.sim.counters().violations, 1U);
}

TEST(SimTravel, Dcp4StartBelow20cmLimitsToCrawl) {
  Harness m;
  m.init();
  dcp4_travel(m, 150.0);
  double vmax = 0;
  for (const auto& c : m.history) vmax = std::max(vmax, std::fabs(c.velocity_mps));
  EXPECT_LE(vmax, 0.05 + 1e-9);  // V0
  EXPECT_NEAR(m.sim.position_mm(), 150.0, 1.0);
}

TEST(SimTravel, Dcp4RelevellingOnRemainingDistance) {
  // DCP 11.1.4: VN' travel positions to the millimetre at relevelling speed.
  DriveConfig cfg;
  cfg.start_position_mm = 2980;
  Harness m(cfg);
  m.init();
  dcp4_travel(m, 3000.0, kVN);
  EXPECT_NEAR(m.sim.position_mm(), 3000.0, 1.0);
  for (const auto& c : m.history) EXPECT_LE(std::fabs(c.velocity_mps), 0.03 + 1e-9);
}

TEST(SimTravel, Dcp4ImplausibleDistanceClearsS5AndStops) {
  Harness m;
  m.init();
  m.cycle(cmd::kSpeed, kV4);
  Cycle c;
  for (int i = 0; i < 200; ++i) {
    c = m.distance_cycle(cmd::kDecel, 8000.0);
  }
  ASSERT_GT(c.velocity_mps, 1.0);
  c = m.cycle(cmd::kDecel, 100);  // target jumps back by metres
  EXPECT_FALSE(has(c.status, sb::kAccepted));
  for (int i = 0; i < 200 && m.sim.velocity_mps() > 0; ++i) m.cycle(cmd::kDecel, 0);
  EXPECT_EQ(m.sim.velocity_mps(), 0.0);
  std::string msg;
  m.cycle(cmd::kStop);
  for (int i = 0; i < 20; ++i) m.cycle(cmd::kStop);
  EXPECT_TRUE(m.take_message(0x1E, msg));
  EXPECT_EQ(msg, "DISTANCE IMPLAUSIBLE");
}

TEST(SimTravel, Dcp3V4TravelFixedDecelerationToCrawl) {
  DriveConfig cfg;
  cfg.protocol = dcp::Protocol::Dcp3;
  cfg.dcp3_decel_mm[7] = 2600;  // SV4 (index = speed bit G7)
  Harness m(cfg);
  m.init();
  m.cycle(cmd::kSpeed, kV4);
  m.repeat(cmd::kTravel, 600);  // B1+B2: 9 s, reaches V4
  ASSERT_NEAR(m.sim.velocity_mps(), 1.6, 1e-9);
  const double off_at = m.sim.position_mm();
  // B1 off: decelerate to crawl within SV4, B2 still on.
  Cycle c = m.cycle(cmd::kDecel);
  for (int i = 0; i < 400 && m.sim.velocity_mps() > 0.05 + 1e-9; ++i) c = m.cycle(cmd::kDecel);
  EXPECT_NEAR(m.sim.velocity_mps(), 0.05, 1e-9);
  EXPECT_NEAR(m.sim.position_mm() - off_at, 2600.0, 1.6 * 15.0 + 1.0);
  m.repeat(cmd::kDecel, 20);  // crawl
  EXPECT_NEAR(m.sim.velocity_mps(), 0.05, 1e-9);
  // B2 off at the level: stop.
  for (int i = 0; i < 100 && has(c.status, sb::kBrakeOpen); ++i) c = m.cycle(cmd::kStop);
  EXPECT_EQ(m.sim.velocity_mps(), 0.0);
  for (int i = 0; i < 20 && has(c.status, sb::kTravelActive); ++i) c = m.cycle(cmd::kStop);
  EXPECT_FALSE(has(c.status, sb::kTravelActive));
}

TEST(SimTravel, InspectionCrawlsAfterB1AndStopsOnB2) {
  Harness m;
  m.init();
  m.cycle(cmd::kSpeed, kVI);
  m.repeat(cmd::kTravel, 200);
  EXPECT_NEAR(m.sim.velocity_mps(), 0.5, 1e-9);
  m.repeat(cmd::kDecel, 200);  // B1 off, B2 on: crawl
  EXPECT_NEAR(m.sim.velocity_mps(), 0.05, 1e-9);
  const Cycle c = m.repeat(cmd::kStop, 40);
  EXPECT_EQ(m.sim.velocity_mps(), 0.0);
  EXPECT_FALSE(has(c.status, sb::kTravelActive));
}

TEST(SimTravel, InspectionFromEndZoneWithB2OnlyCrawls) {
  Harness m;
  m.init();
  m.cycle(cmd::kSpeed, kVI);
  m.repeat(cmd::kDecel, 200);  // B2 only (deceleration meaning after a travel message is unset)
  EXPECT_NEAR(m.sim.velocity_mps(), 0.05, 1e-9);
  EXPECT_EQ(m.sim.travel_kind(), TravelKind::Crawl);
}

TEST(SimTravel, InspectionButtonReleasedDropsEverythingAtOnce) {
  Harness m;
  m.init();
  m.cycle(cmd::kSpeed, kVI);
  m.repeat(cmd::kTravel, 200);
  const Cycle c = m.cycle(cmd::kIdle);  // B0 off
  EXPECT_FALSE(has(c.status, sb::kTravelActive));
  EXPECT_FALSE(has(c.status, sb::kBrakeOpen));
  m.repeat(cmd::kIdle, 40);
  EXPECT_EQ(m.sim.velocity_mps(), 0.0);
}

TEST(SimTravel, RelevellingWithElectricStop) {
  // DCP 9.2.3.2: VN, B1 without B2; B1 off with B0 kept: decelerate, S6 off, then S1 off.
  Harness m;
  m.init();
  m.cycle(cmd::kSpeed, kVN);
  m.repeat(cmd::kRelevel, 60);
  EXPECT_NEAR(m.sim.velocity_mps(), 0.03, 1e-9);
  const std::size_t off = m.history.size();
  m.repeat(cmd::kStop, 30);
  const auto s6_off = first(m.history, off, [](std::uint8_t s) { return !has(s, sb::kBrakeOpen); });
  const auto s1_off =
      first(m.history, off, [](std::uint8_t s) { return !has(s, sb::kTravelActive); });
  ASSERT_TRUE(s6_off && s1_off);
  EXPECT_LT(*s6_off, *s1_off);
  EXPECT_GE(m.history[*s1_off].at - m.history[*s6_off].at, 100ms);
}

TEST(SimTravel, RelevellingWithoutElectricStopDropsS1AndS6Together) {
  // DCP 9.2.3.1: B1 and B0 off at the same time.
  Harness m;
  m.init();
  m.cycle(cmd::kSpeed, kVN);
  m.repeat(cmd::kRelevel, 60);
  const Cycle c = m.cycle(cmd::kIdle);
  EXPECT_FALSE(has(c.status, sb::kBrakeOpen));
  EXPECT_FALSE(has(c.status, sb::kTravelActive));
}

TEST(SimTravel, Dcp3CrawlTravelWithV0) {
  DriveConfig cfg;
  cfg.protocol = dcp::Protocol::Dcp3;
  Harness m(cfg);
  m.init();
  m.cycle(cmd::kSpeed, kV0);
  m.repeat(cmd::kTravel, 60);
  EXPECT_NEAR(m.sim.velocity_mps(), 0.05, 1e-9);
  m.repeat(cmd::kStop, 30);
  EXPECT_EQ(m.sim.velocity_mps(), 0.0);
}

TEST(SimTravel, Dcp4FastStartHoldsThenTravels) {
  Harness m;
  m.init();
  // DCP 12.1.1: speed message VF with B3=1 B2=0 B1=0 B0=1 while the doors close.
  Cycle c = m.repeat(cmd::kSpeed, 30, kVF);
  EXPECT_TRUE(has(c.status, sb::kBrakeOpen));  // after 300 ms magnetising: held, brake open
  EXPECT_TRUE(has(c.status, sb::kTravelActive));
  c = m.repeat(cmd::kDecel, 20, 0);  // DCP4: remaining distance 0x0000 while held
  EXPECT_EQ(m.sim.phase(), Phase::FastStartHold);
  EXPECT_EQ(m.sim.velocity_mps(), 0.0);
  // DCP 12.1.3: go (DCP4 1101) with V4, then the remaining distance.
  const std::size_t go = m.history.size();
  m.cycle(cmd::kGo4, kV4);
  for (int i = 0; i < 1000; ++i) {
    c = m.distance_cycle(cmd::kDecel, 4000.0);
    if (m.history.size() > go + 10 && !has(c.status, sb::kBrakeOpen)) break;
  }
  EXPECT_NEAR(m.sim.position_mm(), 4000.0, 1.0);
  // No magnetising after the go: the car moves in the first cycles.
  EXPECT_GT(m.history[go + 3].velocity_mps, 0.0);
}

TEST(SimTravel, Dcp3FastStartGoWith1111) {
  DriveConfig cfg;
  cfg.protocol = dcp::Protocol::Dcp3;
  Harness m(cfg);
  m.init();
  m.repeat(cmd::kSpeed, 30, kVF);
  ASSERT_EQ(m.sim.phase(), Phase::FastStartHold);
  m.cycle(cmd::kGo3, kV3);
  m.repeat(cmd::kTravel, 200);
  EXPECT_NEAR(m.sim.velocity_mps(), 1.0, 1e-9);
}

TEST(SimTravel, FastStartControlledAbort) {
  Harness m;
  m.init();
  m.repeat(cmd::kSpeed, 30, kVF);
  ASSERT_EQ(m.sim.phase(), Phase::FastStartHold);
  const std::size_t abort = m.history.size();
  m.repeat(cmd::kStop, 20);  // DCP 12.2.2: B2=0 B1=0 B0=1
  const auto s6_off =
      first(m.history, abort, [](std::uint8_t s) { return !has(s, sb::kBrakeOpen); });
  const auto s1_off =
      first(m.history, abort, [](std::uint8_t s) { return !has(s, sb::kTravelActive); });
  ASSERT_TRUE(s6_off && s1_off);
  EXPECT_EQ(*s6_off, abort);  // brake closes at once
  EXPECT_GE(m.history[*s1_off].at - m.history[*s6_off].at, 100ms);
}

TEST(SimTravel, FastStartImmediateAbort) {
  Harness m;
  m.init();
  m.repeat(cmd::kSpeed, 30, kVF);
  const Cycle c = m.cycle(cmd::kIdle);  // DCP 12.2.1: command byte cleared
  EXPECT_FALSE(has(c.status, sb::kBrakeOpen));
  EXPECT_FALSE(has(c.status, sb::kTravelActive));
}

TEST(SimTravel, FastStartIsTimeLimitedOnTheDriveSide) {
  DriveConfig cfg;
  cfg.fast_start_limit_ms = 2000;
  Harness m(cfg);
  m.init();
  Cycle c = m.repeat(cmd::kSpeed, 30, kVF);
  ASSERT_EQ(m.sim.phase(), Phase::FastStartHold);
  c = m.repeat(cmd::kSpeed, 140, kVF);  // 2.1 s
  EXPECT_TRUE(has(c.status, sb::kGeneralFault));
  EXPECT_FALSE(has(c.status, sb::kBrakeOpen));
}

TEST(SimTravel, FastStopUsesFastRampAndLocksOutTravel) {
  Harness m;
  m.init();
  m.cycle(cmd::kSpeed, kV4);
  for (int i = 0; i < 400; ++i) {
    m.distance_cycle(cmd::kDecel, 20000.0);
  }
  ASSERT_NEAR(m.sim.velocity_mps(), 1.6, 1e-9);
  const double at = m.sim.position_mm();
  m.cycle(cmd::kGo4, kVF);  // DCP 13.1: speed after fast start with VF during travel
  for (int i = 0; i < 200 && m.sim.velocity_mps() > 0; ++i) m.cycle(cmd::kDecel, 10000);
  const double stop_mm = m.sim.position_mm() - at;
  // Faster than the normal ramp's 2.5 m.
  EXPECT_LT(stop_mm, 2000.0);
  // Further travel commands are ignored until idle.
  m.repeat(cmd::kDecel, 40, 10000);
  EXPECT_EQ(m.sim.velocity_mps(), 0.0);
  m.repeat(cmd::kStop, 20);
  m.repeat(cmd::kIdle, 2);
  const double here = m.sim.position_mm();
  dcp4_travel(m, here + 1000.0);
  EXPECT_NEAR(m.sim.position_mm(), here + 1000.0, 1.0);
}

TEST(SimTravel, DirectionChangeDeceleratesWithoutFault) {
  Harness m;
  m.init();
  m.cycle(cmd::kSpeed, kVI);
  m.repeat(cmd::kTravel, 100);
  const Cycle c = m.repeat(cmd::kTravel | cmd::kDown, 100);
  EXPECT_EQ(m.sim.velocity_mps(), 0.0);
  EXPECT_FALSE(has(c.status, sb::kGeneralFault));
}

// The simulated absolute encoder reads the drive's trajectory from another thread, at the time
// the master asks, however long ago the drive last ran. Taken at any moment of a travel (the
// jerk-limited start, cruise, the rounded-off stop) and up to 100 ms before the next frame
// (fewer than DCP 7.3's 10 missing frames, so the drive keeps its plan), the trajectory puts
// the car exactly where the drive's own model then has it, up and down.
TEST(SimTravel, TrajectoryPredictsTheCarUntilTheDriveChangesItsPlan) {
  struct Case {
    const char* what;
    double from_mm, to_mm;
  };
  const Case cases[] = {{"up", 0.0, 3000.0}, {"down", 9000.0, 5500.0}};
  for (const Case& c : cases) {
    Harness m;
    m.sim.set_position_mm(c.from_mm);
    m.init();
    const std::uint8_t dir = c.to_mm < c.from_mm ? cmd::kDown : 0;
    m.cycle(cmd::kSpeed | dir, kV4);
    int checked = 0;
    bool moved = false;
    for (int i = 0; i < 4000; ++i) {
      const Cycle cy = m.distance_cycle(cmd::kDecel | dir, c.to_mm);
      if (has(cy.status, sb::kBrakeOpen)) moved = true;
      if (moved && !has(cy.status, sb::kBrakeOpen)) break;
      if (i % 7 != 0) continue;
      const Trajectory seen = m.sim.trajectory();
      for (auto later = 1ms; later <= 100ms; later += 3ms) {
        DriveSim probe = m.sim;
        probe.advance(m.now + later);
        ASSERT_NEAR(seen.position_mm(m.now + later), probe.position_mm(), 1e-9)
            << c.what << " cycle " << i << " +" << later.count() << " ms";
        ASSERT_NEAR(seen.velocity_mps(m.now + later), probe.velocity_mps(), 1e-12) << c.what;
        ++checked;
      }
    }
    EXPECT_TRUE(moved) << c.what;
    EXPECT_GT(checked, 1000) << c.what;
    EXPECT_NEAR(m.sim.position_mm(), c.to_mm, 1.0) << c.what;
  }
}

}  // namespace
}  // namespace liftd::dcp::sim
