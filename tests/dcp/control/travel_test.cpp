// Travels end to end in process: the real DcpController against the drive simulator, one 15 ms
// cycle per step on a fake clock. Floor to floor in both dialects, speed choice, target
// extension, stops, relevelling, inspection, fast start and the calls queue.
#include <gtest/gtest.h>

#include <map>

#include <cmath>

#include "controller_rig.hpp"

namespace liftd::control {
namespace {

using testing::enable_of;
using testing::nibble_of;
using testing::Rig;
using testing::word_of;
using namespace std::chrono_literals;
namespace cb = dcp::command_bit;

// DCP 11.1.2: a distance travel ends at the level without crawl; our acceptance is 2 mm.
constexpr double kDcp4LandingMm = 2.0;
// DCP3 by position (rig config): B2 is withdrawn 8 mm (the stop lead) before the level, and
// the simulator stops from crawl V0 = 0.05 m/s on its jerk-limited
// ramp in about 7.7 mm (2 * sqrt(0.05 / 2.1) = 0.31 s at half the crawl speed). The decision is
// taken once per cycle, and a cycle at crawl is 0.75 mm, so the car stops within about 1 mm of
// the level; 2 mm bounds it. Without the lead it overshoots by 4 to 5 mm.
constexpr double kDcp3LandingMm = 2.0;

/// Runs one travel to `floor` and waits until it is over and the drive is idle.
::testing::AssertionResult travel_to(Rig& rig, std::size_t floor) {
  const std::size_t finished = rig.travel_events(travel::Event::Type::Finished).size();
  const CommandReply r = rig.command(TravelCommand{floor, std::nullopt, std::nullopt, false});
  if (r.code != ReplyCode::Ok) return ::testing::AssertionFailure() << "refused: " << r.detail;
  if (!rig.run_until(
          [&] {
            return rig.travel_events(travel::Event::Type::Finished).size() > finished && rig.idle();
          },
          90s)) {
    return ::testing::AssertionFailure() << "travel to floor " << floor << " did not finish";
  }
  return ::testing::AssertionSuccess();
}

/// Index of the first frame from `from` on whose nibble is `nibble`.
std::optional<std::size_t> find_nibble(const Rig& rig, std::uint8_t nibble, std::size_t from = 0) {
  for (std::size_t i = from; i < rig.frames.size(); ++i) {
    if (nibble_of(rig.frames[i]) == nibble) return i;
  }
  return std::nullopt;
}

// ---- floor to floor ----

struct FloorCase {
  dcp::Protocol protocol;
  double tolerance_mm;
};

class EveryFloorPair : public ::testing::TestWithParam<FloorCase> {};

TEST_P(EveryFloorPair, LandsOnTheLevel) {
  const FloorCase c = GetParam();
  Rig rig(c.protocol);
  ASSERT_TRUE(rig.warm_up());
  const auto floors = testing::six_floors();
  for (std::size_t from = 0; from < floors.size(); ++from) {
    for (std::size_t to = 0; to < floors.size(); ++to) {
      if (from == to) continue;
      rig.place_at(floors[from]);
      ASSERT_TRUE(travel_to(rig, to)) << from << " -> " << to;
      EXPECT_NEAR(rig.sim.position_mm(), static_cast<double>(floors[to]), c.tolerance_mm)
          << from << " -> " << to;
      EXPECT_EQ(rig.controller.snapshot().floor, to) << from << " -> " << to;
      // DCP 9.1.1: B0 off while stationary.
      EXPECT_FALSE(enable_of(rig.frames.back())) << from << " -> " << to;
    }
  }
  EXPECT_TRUE(rig.travel_events(travel::Event::Type::Aborted).empty());
}

INSTANTIATE_TEST_SUITE_P(Dialects, EveryFloorPair,
                         ::testing::Values(FloorCase{dcp::Protocol::Dcp4, kDcp4LandingMm},
                                           FloorCase{dcp::Protocol::Dcp3, kDcp3LandingMm}),
                         [](const auto& p) {
                           return p.param.protocol == dcp::Protocol::Dcp4 ? "Dcp4" : "Dcp3";
                         });

// ---- DCP3 speed choice ----

// Levels chosen so the hops need every DCP3 speed of a two-speed installation: SV4 = 2654 mm,
// SV3 = 1181 mm (rig config: the simulator's SVx plus 100 mm of crawl).
std::vector<std::int64_t> uneven_floors() {
  return {0, 400, 2000, 8000};
}

struct SpeedCase {
  const char* legend;
  std::size_t from;
  std::size_t to;
  dcp::Speed speed;
};

class Dcp3SpeedChoice : public ::testing::TestWithParam<SpeedCase> {};

TEST_P(Dcp3SpeedChoice, SendsTheSpeedThatFitsAndLands) {
  const SpeedCase c = GetParam();
  ControllerConfig config = testing::default_config(dcp::Protocol::Dcp3);
  config.floors_mm = uneven_floors();
  Rig rig(config, testing::sim_config(dcp::Protocol::Dcp3));
  ASSERT_TRUE(rig.warm_up());
  rig.place_at(uneven_floors()[c.from]);
  const std::size_t first = rig.frames.size();
  ASSERT_TRUE(travel_to(rig, c.to)) << c.legend;
  const auto speed_at = find_nibble(rig, 0x9, first);  // DCP 3.5: speed message 1001
  ASSERT_TRUE(speed_at) << c.legend;
  EXPECT_EQ(word_of(rig.frames[*speed_at]), dcp::speed_word(c.speed)) << c.legend;
  EXPECT_NEAR(rig.sim.position_mm(), static_cast<double>(uneven_floors()[c.to]), kDcp3LandingMm)
      << c.legend;
  if (c.speed == dcp::Speed::V0) {
    // DCP 10.3 step 2: crawl starts with B1 and B2 together (travel message 0111).
    EXPECT_EQ(nibble_of(rig.frames[*speed_at + 2]), 0x7) << c.legend;
  }
}

INSTANTIATE_TEST_SUITE_P(
    Table, Dcp3SpeedChoice,
    ::testing::Values(SpeedCase{"400 mm hop: shorter than SV3, crawl V0", 0, 1, dcp::Speed::V0},
                      SpeedCase{"1600 mm hop: SV3 fits, SV4 does not: V3", 1, 2, dcp::Speed::V3},
                      SpeedCase{"6000 mm hop: SV4 fits: V4", 2, 3, dcp::Speed::V4},
                      SpeedCase{"8000 mm down: V4", 3, 0, dcp::Speed::V4},
                      SpeedCase{"400 mm down: crawl V0", 1, 0, dcp::Speed::V0}),
    [](const auto& p) { return "Case" + std::to_string(p.index); });

// DCP 10.1.2 / 10.2.2: when B1 drops before Vx is reached, the drive still covers the same
// fixed SVx down to crawl, so the by-position stop lands on the level just as after a long
// travel (these hops once overshot by 160 to 360 mm in the simulator).
TEST(Dcp3ShortTravel, SimulatorCoversSvxWhenB1DropsWhileAccelerating) {
  ControllerConfig config = testing::default_config(dcp::Protocol::Dcp3);
  config.floors_mm = {0, 2000, 5000};
  Rig rig(config, testing::sim_config(dcp::Protocol::Dcp3));
  ASSERT_TRUE(rig.warm_up());
  ASSERT_TRUE(travel_to(rig, 2));  // 5000 mm at V4: B1 drops at 2654 mm, still accelerating
  EXPECT_NEAR(rig.sim.position_mm(), 5000.0, kDcp3LandingMm);
  rig.place_at(400);
  ASSERT_TRUE(travel_to(rig, 2));  // 4600 mm at V4: B1 drops at 1946 mm, full acceleration
  EXPECT_NEAR(rig.sim.position_mm(), 5000.0, kDcp3LandingMm);
  rig.place_at(0);
  ASSERT_TRUE(travel_to(rig, 1));  // 2000 mm at V3
  EXPECT_NEAR(rig.sim.position_mm(), 2000.0, kDcp3LandingMm);
}

// ---- wire order ----

TEST(Dcp4Wire, SpeedMessageThenRemainingDistanceUntilS6ThenStopUntilS1) {
  Rig rig;
  ASSERT_TRUE(rig.warm_up());
  const std::size_t first = rig.frames.size();
  const std::size_t log_first = rig.log.size();
  ASSERT_TRUE(travel_to(rig, 2));
  // DCP 11.1.2 step 1: speed message 1001 with V4 first, B4 = 0 (up).
  const auto speed_at = find_nibble(rig, 0x9, first);
  ASSERT_TRUE(speed_at);
  EXPECT_EQ(rig.frames[*speed_at][0], 0x09);
  EXPECT_EQ(word_of(rig.frames[*speed_at]), dcp::speed_word(dcp::Speed::V4));
  // Nothing with B0/B1/B2 before it.
  for (std::size_t i = first; i < *speed_at; ++i) EXPECT_EQ(rig.frames[i][0] & 0x07, 0) << i;
  // Step 2: then B2 + B0 (0101) with the remaining distance, B1 never.
  const auto dist_at = find_nibble(rig, 0x5, *speed_at);
  ASSERT_TRUE(dist_at);
  EXPECT_EQ(word_of(rig.frames[*dist_at]), 6000);  // 6 m to floor 2 from floor 0
  for (std::size_t i = first; i < rig.frames.size(); ++i) {
    EXPECT_EQ(rig.frames[i][0] & cb::kTravel, 0) << i;
  }
  // Step 4: B2 held until S6 fell; then the stop message 0001 until S1 = 0; then idle.
  const auto stop_at = find_nibble(rig, 0x1, *dist_at);
  ASSERT_TRUE(stop_at);
  const std::size_t stop_log = log_first + (*stop_at - first);
  ASSERT_TRUE(rig.log[stop_log].seen);
  EXPECT_EQ(*rig.log[stop_log].seen & dcp::status_bit::kBrakeOpen, 0);
  EXPECT_EQ(*rig.log[stop_log - 1].seen & dcp::status_bit::kBrakeOpen, dcp::status_bit::kBrakeOpen);
  for (std::size_t i = *dist_at; i < *stop_at; ++i) EXPECT_EQ(nibble_of(rig.frames[i]), 0x5) << i;
  const auto idle_at = find_nibble(rig, 0x0, *stop_at);
  ASSERT_TRUE(idle_at);
  const std::size_t idle_log = log_first + (*idle_at - first);
  EXPECT_EQ(*rig.log[idle_log].seen & dcp::status_bit::kTravelActive, 0);
  EXPECT_NE(*rig.log[idle_log - 1].seen & dcp::status_bit::kTravelActive, 0);
}

TEST(Dcp3Wire, SpeedThenB1ThenB2BeforeDecelPointThenStop) {
  Rig rig(dcp::Protocol::Dcp3);
  ASSERT_TRUE(rig.warm_up());
  rig.place_at(6000);
  const std::size_t first = rig.frames.size();
  const std::size_t log_first = rig.log.size();
  ASSERT_TRUE(travel_to(rig, 0));  // down 6 m at V4
  // DCP 10.1.1 step 1: speed message V4, B4 = 1 (down): 0x19.
  const auto speed_at = find_nibble(rig, 0x9, first);
  ASSERT_TRUE(speed_at);
  EXPECT_EQ(rig.frames[*speed_at][0], 0x19);
  EXPECT_EQ(word_of(rig.frames[*speed_at]), dcp::speed_word(dcp::Speed::V4));
  // Step 2: travel command B1 (with B2 and B0: 0111), direction kept.
  const auto travel_at = find_nibble(rig, 0x7, *speed_at);
  ASSERT_TRUE(travel_at);
  EXPECT_EQ(rig.frames[*travel_at][0], 0x17);
  // Step 3: B1 off at SV4 before the level, B2 kept (0101), data word 0. The decision uses the
  // position read for that frame, so it lies within one cycle (24 mm at 1.6 m/s) below SV4.
  const double sv4 = testing::default_config(dcp::Protocol::Dcp3)
                         .travel.dcp3_decel_distance_mm[travel::speed_index(dcp::Speed::V4)];
  const auto creep_at = find_nibble(rig, 0x5, *travel_at);
  ASSERT_TRUE(creep_at);
  EXPECT_EQ(word_of(rig.frames[*creep_at]), 0);
  const double at_decel = rig.log[log_first + (*creep_at - first)].position_mm;
  EXPECT_LE(at_decel, sv4);
  EXPECT_GT(at_decel, sv4 - 25.0);
  EXPECT_EQ(nibble_of(rig.frames[*creep_at - 1]), 0x7);
  // Step 4/5: B2 off (stop 0001 keeps B0) 3 + 5 mm before the level, within one crawl cycle.
  const auto stop_at = find_nibble(rig, 0x1, *creep_at);
  ASSERT_TRUE(stop_at);
  const double at_stop = rig.log[log_first + (*stop_at - first)].position_mm;
  EXPECT_LE(at_stop, 8.5);
  EXPECT_GT(at_stop, 6.5);
  // B0 kept until S1 = 0, then idle.
  const auto idle_at = find_nibble(rig, 0x0, *stop_at);
  ASSERT_TRUE(idle_at);
  EXPECT_EQ(*rig.log[log_first + (*idle_at - first)].seen & dcp::status_bit::kTravelActive, 0);
  for (std::size_t i = *travel_at; i < rig.frames.size(); ++i) {
    if (rig.frames[i][0] == 0) break;
    EXPECT_NE(rig.frames[i][0] & cb::kDirectionDown, 0) << "B4 constant, DCP 9.1.2";
  }
}

// ---- DCP4 target extension ----

TEST(Dcp4Extension, ExtendsEarlyRefusesLateWithReason) {
  Rig rig;
  ASSERT_TRUE(rig.warm_up());
  ASSERT_EQ(rig.command(TravelCommand{2, std::nullopt, std::nullopt, false}).code, ReplyCode::Ok);
  // Early: the car is still accelerating, far from the deceleration point of a 6 m travel.
  ASSERT_TRUE(rig.run_until([&] { return rig.sim.position_mm() > 300.0; }, 20s));
  const CommandReply early = rig.command(TravelCommand{4, std::nullopt, std::nullopt, false});
  EXPECT_EQ(early.code, ReplyCode::Ok) << early.detail;
  EXPECT_TRUE(early.extended);
  // The drive sees the new remaining distance on the wire.
  ASSERT_TRUE(rig.run_until([&] { return word_of(rig.frames.back()) > 9000; }, 1s));
  // Late: inside the deceleration distance of floor 4 (12 m).
  ASSERT_TRUE(rig.run_until([&] { return rig.sim.position_mm() > 11500.0; }, 30s));
  const CommandReply late = rig.command(TravelCommand{5, std::nullopt, std::nullopt, false});
  EXPECT_EQ(late.code, ReplyCode::Busy);
  EXPECT_EQ(late.detail, travel::to_string(travel::ExtendResult::TooLate));
  EXPECT_FALSE(late.extended);
  ASSERT_TRUE(rig.run_until([&] { return rig.finished_travels(1) && rig.idle(); }, 60s));
  EXPECT_NEAR(rig.sim.position_mm(), 12000.0, kDcp4LandingMm);
  EXPECT_EQ(rig.controller.snapshot().floor, 4U);
  // Exactly one extension event, for the accepted one, naming the new level.
  const auto extended = rig.travel_events(travel::Event::Type::TargetExtended);
  ASSERT_EQ(extended.size(), 1U);
  EXPECT_EQ(extended[0].target_mm, 12000);
}

TEST(Dcp4Extension, RefusedWhileAdvanceWarning) {
  Rig rig;
  ASSERT_TRUE(rig.warm_up());
  ASSERT_EQ(rig.command(TravelCommand{2, std::nullopt, std::nullopt, false}).code, ReplyCode::Ok);
  ASSERT_TRUE(rig.run_until([&] { return rig.sim.position_mm() > 300.0; }, 20s));
  rig.sim.set_advance_warning(true);
  rig.run(45ms);
  const CommandReply r = rig.command(TravelCommand{4, std::nullopt, std::nullopt, false});
  EXPECT_EQ(r.code, ReplyCode::NotReady);  // DCP 9.1.5: no extension with S2 set
  EXPECT_EQ(r.detail, travel::to_string(travel::ExtendResult::AdvanceWarning));
  ASSERT_TRUE(rig.run_until([&] { return rig.finished_travels(1) && rig.idle(); }, 60s));
  EXPECT_NEAR(rig.sim.position_mm(), 6000.0, kDcp4LandingMm);
  // DCP 9.1.5: no new travel while S2 is set.
  EXPECT_EQ(rig.command(TravelCommand{0, std::nullopt, std::nullopt, false}).code,
            ReplyCode::NotReady);
}

// ---- stop and fast stop ----

/// Wire-level rule (DCP 11.1.1 d, 11.1.2 step 4): no frame with B2 clear while the last reply
/// the controller had seen showed S6 set. Returns the first offending record index, or -1.
long b2_dropped_while_brake_open(const Rig& rig, std::size_t from) {
  for (std::size_t i = from + 1; i < rig.log.size(); ++i) {
    const bool b2_before = (rig.log[i - 1].frame[0] & dcp::command_bit::kStopSwitch) != 0;
    const bool b2_now = (rig.log[i].frame[0] & dcp::command_bit::kStopSwitch) != 0;
    const bool s6 = rig.log[i].seen && (*rig.log[i].seen & dcp::status_bit::kBrakeOpen) != 0;
    if (b2_before && !b2_now && s6) return static_cast<long>(i);
  }
  return -1;
}

struct StopCase {
  const char* legend;
  dcp::Protocol protocol;
  std::uint8_t nibble;  // what must be on the wire right after the request
};

class StopDuringTravel : public ::testing::TestWithParam<StopCase> {};

TEST_P(StopDuringTravel, LandsAtTheNextPossibleFloor) {
  // Issue: `stop` means the next possible floor. DCP4: the remaining distance now ends there,
  // B2 until S6 = 0 (DCP 11.1.1 d). DCP3: crawl from that floor's deceleration point SVx
  // (DCP 10.1.1 step 3). Never the stop message at speed (DCP 3.5.3.2).
  const StopCase c = GetParam();
  Rig rig(c.protocol);
  ASSERT_TRUE(rig.warm_up());
  ASSERT_EQ(rig.command(TravelCommand{5, std::nullopt, std::nullopt, false}).code, ReplyCode::Ok);
  ASSERT_TRUE(rig.run_until([&] { return rig.sim.velocity_mps() > 1.2; }, 20s)) << c.legend;
  const double at_mm = rig.sim.position_mm();
  const std::size_t at = rig.frames.size();
  const std::size_t log_at = rig.log.size();
  const CommandReply r = rig.command(StopCommand{});
  ASSERT_EQ(r.code, ReplyCode::Ok) << c.legend;
  ASSERT_TRUE(r.floor.has_value()) << c.legend;
  EXPECT_LT(*r.floor, 5U) << c.legend << ": a floor before the target";
  EXPECT_GT(static_cast<double>(testing::six_floors()[*r.floor]), at_mm) << c.legend;
  EXPECT_EQ(nibble_of(rig.frames[at]), c.nibble) << c.legend;
  ASSERT_TRUE(rig.run_until([&] { return rig.idle(); }, 30s)) << c.legend;
  EXPECT_TRUE(rig.travel_events(travel::Event::Type::Aborted).empty()) << c.legend;
  EXPECT_EQ(rig.travel_events(travel::Event::Type::Finished).size(), 1U) << c.legend;
  EXPECT_NEAR(rig.sim.position_mm(), static_cast<double>(testing::six_floors()[*r.floor]), 10.0)
      << c.legend;
  // DCP4 holds B2 until S6 falls (11.1.1 d); DCP3 positions with B2 at crawl (10.1.1 step 4),
  // which the simulator checks: a stop message at speed would count as a violation.
  if (c.protocol == dcp::Protocol::Dcp4) {
    EXPECT_EQ(b2_dropped_while_brake_open(rig, log_at), -1) << c.legend;
  }
  EXPECT_EQ(rig.sim.counters().violations, 0U) << c.legend;
  EXPECT_FALSE(enable_of(rig.frames.back())) << c.legend;
}

INSTANTIATE_TEST_SUITE_P(
    Table, StopDuringTravel,
    ::testing::Values(StopCase{"DCP4 stop: remaining distance retargeted, B2 held (0101)",
                               dcp::Protocol::Dcp4, 0x5},
                      StopCase{"DCP3 stop: travel message until the deceleration point (0111)",
                               dcp::Protocol::Dcp3, 0x7}),
    [](const auto& p) { return "Case" + std::to_string(p.index); });

struct FastStopCase {
  const char* legend;
  dcp::Protocol protocol;
  std::uint8_t nibble;
};

class FastStopDuringTravel : public ::testing::TestWithParam<FastStopCase> {};

TEST_P(FastStopDuringTravel, StopsOnTheFastStopRamp) {
  const FastStopCase c = GetParam();
  Rig rig(c.protocol);
  ASSERT_TRUE(rig.warm_up());
  ASSERT_EQ(rig.command(TravelCommand{5, std::nullopt, std::nullopt, false}).code, ReplyCode::Ok);
  ASSERT_TRUE(rig.run_until([&] { return rig.sim.velocity_mps() > 1.2; }, 20s)) << c.legend;
  const std::size_t at = rig.frames.size();
  ASSERT_EQ(rig.command(FastStopCommand{}).code, ReplyCode::Ok) << c.legend;
  // The request is handled before the next frame: that frame already carries it.
  EXPECT_EQ(nibble_of(rig.frames[at]), c.nibble) << c.legend;
  // DCP 13.1: speed-after-fast-start message with VF in the data bytes.
  EXPECT_EQ(word_of(rig.frames[at]), dcp::speed_word(dcp::Speed::VF)) << c.legend;
  ASSERT_TRUE(rig.run_until([&] { return rig.idle(); }, 30s)) << c.legend;
  const auto aborted = rig.travel_events(travel::Event::Type::Aborted);
  ASSERT_EQ(aborted.size(), 1U) << c.legend;
  EXPECT_EQ(aborted[0].cause, lift::Cause::StopRequested) << c.legend;
  EXPECT_LT(rig.sim.position_mm(), 15000.0 - 1000.0) << c.legend;
  EXPECT_FALSE(enable_of(rig.frames.back())) << c.legend;
}

INSTANTIATE_TEST_SUITE_P(Table, FastStopDuringTravel,
                         ::testing::Values(FastStopCase{"DCP4 fast stop: 1101 with VF (DCP 3.5.2)",
                                                        dcp::Protocol::Dcp4, 0xD},
                                           FastStopCase{"DCP3 fast stop: 1111 with VF (DCP 3.5.1)",
                                                        dcp::Protocol::Dcp3, 0xF}),
                         [](const auto& p) { return "Case" + std::to_string(p.index); });

TEST(FastStop, FasterThanAControlledStop) {
  double stop_mm[2] = {};
  for (int fast = 0; fast < 2; ++fast) {
    Rig rig;
    ASSERT_TRUE(rig.warm_up());
    ASSERT_EQ(rig.command(TravelCommand{5, std::nullopt, std::nullopt, false}).code, ReplyCode::Ok);
    ASSERT_TRUE(rig.run_until([&] { return rig.sim.velocity_mps() > 1.55; }, 20s));
    const double from = rig.sim.position_mm();
    if (fast != 0) {
      rig.post(FastStopCommand{});
    } else {
      rig.post(StopCommand{});
    }
    ASSERT_TRUE(rig.run_until([&] { return rig.sim.stationary(); }, 20s));
    stop_mm[fast] = rig.sim.position_mm() - from;
  }
  EXPECT_LT(stop_mm[1], stop_mm[0]);  // DCP 13.2: the fast-stop ramp is steeper
}

// ---- relevelling ----

TEST(Relevel, Dcp4AutoRelevelsAfterDrift) {
  Rig rig;
  ASSERT_TRUE(rig.warm_up());
  ASSERT_TRUE(travel_to(rig, 2));
  rig.run(500ms);
  const std::size_t first = rig.frames.size();
  rig.place_at(6000 - 25);  // the car sank 25 mm (rope stretch under load)
  ASSERT_TRUE(rig.run_until([&] { return rig.finished_travels(2) && rig.idle(); }, 30s));
  // DCP 11.1.4: VN' = speed message VN, then B2 + B0 with the remaining distance.
  const auto speed_at = find_nibble(rig, 0x9, first);
  ASSERT_TRUE(speed_at);
  EXPECT_EQ(rig.frames[*speed_at][0], 0x09);  // up
  EXPECT_EQ(word_of(rig.frames[*speed_at]), dcp::speed_word(dcp::Speed::VN));
  const auto dist_at = find_nibble(rig, 0x5, *speed_at);
  ASSERT_TRUE(dist_at);
  EXPECT_NEAR(word_of(rig.frames[*dist_at]), 25, 1);
  const auto finished = rig.travel_events(travel::Event::Type::Finished);
  EXPECT_EQ(finished.back().kind, travel::TravelKind::Dcp4Relevel);
  EXPECT_NEAR(rig.sim.position_mm(), 6000.0, kDcp4LandingMm);
}

TEST(Relevel, Dcp3RelevelCommand) {
  ControllerConfig config = testing::default_config(dcp::Protocol::Dcp3);
  config.travel.relevel_electric_stop = true;  // DCP 9.2.3.2, checked below
  Rig rig(config, testing::sim_config(dcp::Protocol::Dcp3));
  ASSERT_TRUE(rig.warm_up());
  ASSERT_TRUE(travel_to(rig, 1));
  rig.run(500ms);
  const std::size_t first = rig.frames.size();
  rig.place_at(3000 - 25);
  rig.run(1s);
  EXPECT_EQ(find_nibble(rig, 0x9, first), std::nullopt) << "no automatic relevelling in DCP3";
  const CommandReply r = rig.command(RelevelCommand{});
  ASSERT_EQ(r.code, ReplyCode::Ok) << r.detail;
  ASSERT_TRUE(rig.run_until([&] { return rig.finished_travels(2) && rig.idle(); }, 30s));
  // DCP 9.2.3: speed VN, then B1 without B2 (relevelling 0011).
  const auto speed_at = find_nibble(rig, 0x9, first);
  ASSERT_TRUE(speed_at);
  EXPECT_EQ(word_of(rig.frames[*speed_at]), dcp::speed_word(dcp::Speed::VN));
  const auto relevel_at = find_nibble(rig, 0x3, *speed_at);
  ASSERT_TRUE(relevel_at);
  EXPECT_EQ(rig.frames[*relevel_at][0], 0x03);
  // 9.2.3.2 with electric stop: B1 off, B0 kept (0001) until S6 and S1 are 0.
  EXPECT_TRUE(find_nibble(rig, 0x1, *relevel_at));
  EXPECT_EQ(rig.travel_events(travel::Event::Type::Finished).back().kind,
            travel::TravelKind::Relevel);
  // The relevelling ends once the car is level (travel.level_tolerance_mm); VN = 0.03 m/s then
  // stops within a fraction of a mm on the deceleration ramp.
  EXPECT_NEAR(rig.sim.position_mm(), 3000.0, config.travel.level_tolerance_mm + 1.0);
}

// ---- inspection ----

TEST(Inspection, ButtonReleasedMidTravelDropsB0AtOnce) {
  Rig rig;
  ASSERT_TRUE(rig.warm_up());
  rig.inputs.inspection = true;
  rig.run(100ms);
  rig.post(InspectionCommand{true, lift::Direction::Up});
  const std::size_t first = rig.frames.size();
  // Hold the direction by repeating the command every 300 ms, inside the 500 ms hold.
  for (int i = 0; i < 10; ++i) {
    rig.run(300ms);
    rig.post(InspectionCommand{true, lift::Direction::Up});
  }
  const auto speed_at = find_nibble(rig, 0x9, first);
  ASSERT_TRUE(speed_at);
  EXPECT_EQ(word_of(rig.frames[*speed_at]), dcp::speed_word(dcp::Speed::VI));
  EXPECT_EQ(nibble_of(rig.frames.back()), 0x7);  // DCP 9.2.1.1: B1 + B2 with VI
  EXPECT_GT(rig.sim.velocity_mps(), 0.3);
  // Released: the very next frame has B0 off (DCP 9.1.1).
  rig.post(InspectionCommand{true, lift::Direction::None});
  rig.cycle();
  EXPECT_EQ(rig.frames.back()[0] & 0x07, 0);
  ASSERT_TRUE(rig.run_until([&] { return rig.idle(); }, 10s));
  EXPECT_FALSE(enable_of(rig.frames.back()));
}

TEST(Inspection, DirectionNotRepeatedStopsAfterTheHoldTime) {
  Rig rig;
  ASSERT_TRUE(rig.warm_up());
  rig.inputs.inspection = true;
  rig.run(100ms);
  const MonoTime sent = rig.now + 15ms;  // handled in the next cycle
  rig.post(InspectionCommand{true, lift::Direction::Down});
  rig.run(300ms);
  ASSERT_TRUE(enable_of(rig.frames.back()));
  ASSERT_TRUE(rig.run_until([&] { return !enable_of(rig.frames.back()); }, 2s));
  // ControllerConfig::inspection_hold = 500 ms: B0 drops in the first cycle after it.
  EXPECT_GT(rig.now - sent, 500ms);
  EXPECT_LE(rig.now - sent, 515ms);
}

// ---- fast start ----

struct FastStartCase {
  const char* legend;
  dcp::Protocol protocol;
  std::uint8_t go_nibble;
};

class FastStart : public ::testing::TestWithParam<FastStartCase> {};

TEST_P(FastStart, ArmedThenGoesWhenDoorsLock) {
  const FastStartCase c = GetParam();
  Rig rig(c.protocol);
  ASSERT_TRUE(rig.warm_up());
  rig.inputs.doors_locked = false;
  rig.inputs.doors_closed = false;
  rig.run(100ms);
  const std::size_t first = rig.frames.size();
  ASSERT_EQ(rig.command(TravelCommand{2, std::nullopt, std::nullopt, true}).code, ReplyCode::Ok);
  ASSERT_TRUE(rig.run_until([&] { return rig.controller.snapshot().fast_start_armed; }, 3s));
  rig.run(300ms);
  // DCP 12.1.1: speed message with VF (B3 + B0), doors still open.
  const auto vf_at = find_nibble(rig, 0x9, first);
  ASSERT_TRUE(vf_at) << c.legend;
  EXPECT_EQ(word_of(rig.frames[*vf_at]), dcp::speed_word(dcp::Speed::VF)) << c.legend;
  EXPECT_NEAR(rig.sim.position_mm(), 0.0, 1.0) << "held at the level";
  if (c.protocol == dcp::Protocol::Dcp4) {
    // DCP 12.1.2: remaining distance 0x0000 while held.
    EXPECT_EQ(nibble_of(rig.frames.back()), 0x5);
    EXPECT_EQ(word_of(rig.frames.back()), 0x0000);
  }
  const CommandReply early = rig.command(FastStartCommand{FastStartCommand::Action::Go});
  EXPECT_EQ(early.code, ReplyCode::NotReady) << c.legend;
  const std::size_t before_go = rig.frames.size();
  rig.inputs.doors_closed = rig.inputs.doors_locked = true;
  rig.cycle();
  rig.cycle();
  // DCP 12.1.3: the speed-after-fast-start message with the real speed.
  const auto go_at = find_nibble(rig, c.go_nibble, before_go);
  ASSERT_TRUE(go_at) << c.legend;
  EXPECT_EQ(word_of(rig.frames[*go_at]), dcp::speed_word(dcp::Speed::V4)) << c.legend;
  ASSERT_TRUE(rig.run_until([&] { return rig.finished_travels(1) && rig.idle(); }, 60s));
  EXPECT_NEAR(rig.sim.position_mm(), 6000.0,
              c.protocol == dcp::Protocol::Dcp4 ? kDcp4LandingMm : kDcp3LandingMm);
}

TEST_P(FastStart, DoorReversalAbortsControlled) {
  const FastStartCase c = GetParam();
  Rig rig(c.protocol);
  ASSERT_TRUE(rig.warm_up());
  rig.inputs.doors_locked = false;
  rig.inputs.doors_closed = false;
  rig.run(100ms);
  ASSERT_EQ(rig.command(TravelCommand{2, std::nullopt, std::nullopt, true}).code, ReplyCode::Ok);
  ASSERT_TRUE(rig.run_until([&] { return rig.controller.snapshot().fast_start_armed; }, 3s));
  rig.run(300ms);
  ASSERT_NE(rig.sim.status_byte() & dcp::status_bit::kBrakeOpen, 0) << "held with open brake";
  const std::size_t at = rig.frames.size();
  const std::size_t log_at = rig.log.size();
  rig.inputs.door_reversal = true;
  rig.cycle();
  // DCP 12.2.2: stop message B2 = 0 B1 = 0 B0 = 1 ...
  EXPECT_EQ(rig.frames[at][0] & 0x0F, 0x01) << c.legend;
  ASSERT_TRUE(rig.run_until([&] { return rig.idle(); }, 5s)) << c.legend;
  // ... held until S6 = 0; only then B0 off.
  std::size_t off = at;
  while (off < rig.frames.size() && enable_of(rig.frames[off])) ++off;
  ASSERT_LT(off, rig.frames.size());
  EXPECT_EQ(*rig.log[log_at + (off - at)].seen & dcp::status_bit::kBrakeOpen, 0) << c.legend;
  const auto aborted = rig.travel_events(travel::Event::Type::Aborted);
  ASSERT_EQ(aborted.size(), 1U);
  EXPECT_EQ(aborted[0].cause, lift::Cause::DoorReversal);
  EXPECT_NEAR(rig.sim.position_mm(), 0.0, 1.0) << "the car never moved";
}

TEST_P(FastStart, HoldEndsAfterItsTimeLimit) {
  const FastStartCase c = GetParam();
  Rig rig(c.protocol);
  ASSERT_TRUE(rig.warm_up());
  rig.inputs.doors_locked = false;
  rig.inputs.doors_closed = false;
  rig.run(100ms);
  ASSERT_EQ(rig.command(TravelCommand{2, std::nullopt, std::nullopt, true}).code, ReplyCode::Ok);
  ASSERT_TRUE(rig.run_until([&] { return rig.controller.snapshot().fast_start_armed; }, 3s));
  const MonoTime armed = rig.now;
  // DCP 12.1.2: time limited on our side too (travel.fast_start_timeout_ms, 3000 by default:
  // shorter than the simulated drive's 10 s, so ours is the one that acts).
  const auto limit = std::chrono::milliseconds(travel::TravelConfig{}.fast_start_timeout_ms);
  ASSERT_TRUE(rig.run_until([&] { return !rig.controller.snapshot().fast_start_armed; }, 12s));
  EXPECT_GE(rig.now - armed, limit - 100ms) << c.legend;
  EXPECT_LE(rig.now - armed, limit + 500ms) << c.legend;
  ASSERT_TRUE(rig.run_until([&] { return rig.idle(); }, 5s));
  const auto aborted = rig.travel_events(travel::Event::Type::Aborted);
  ASSERT_EQ(aborted.size(), 1U);
  EXPECT_EQ(aborted[0].cause, lift::Cause::FastStartTimeout);
  EXPECT_EQ(rig.raised(FaultCode::DriveFault), 0U) << "the drive's own limit never tripped";
  EXPECT_FALSE(enable_of(rig.frames.back()));
}

INSTANTIATE_TEST_SUITE_P(
    Dialects, FastStart,
    ::testing::Values(FastStartCase{"DCP4: go is 1101", dcp::Protocol::Dcp4, 0xD},
                      FastStartCase{"DCP3: go is 1111", dcp::Protocol::Dcp3, 0xF}),
    [](const auto& p) { return p.param.protocol == dcp::Protocol::Dcp4 ? "Dcp4" : "Dcp3"; });

// ---- calls ----

TEST(Calls, AnsweredAsOnEveryLiftAndRefusedWhileTheServiceStops) {
  // The DCP lift answers `calls` with the shared lift rules (lift/rules.hpp), as the SCH001 and
  // USS lifts do: docs/api.md's texts, and no new call once the service is stopping.
  Rig rig;
  ASSERT_TRUE(rig.warm_up());
  CommandReply r = rig.command(CallCommand::adding(99));
  EXPECT_EQ(r.code, ReplyCode::BadRequest);
  EXPECT_EQ(r.detail, "no such floor");
  r = rig.command(CallCommand::cancelling(2));
  EXPECT_EQ(r.code, ReplyCode::BadRequest);
  EXPECT_EQ(r.detail, "floor is not queued");
  ASSERT_EQ(rig.command(ShutdownCommand{false}).code, ReplyCode::Ok);
  r = rig.command(CallCommand::adding(2));
  EXPECT_EQ(r.code, ReplyCode::NotReady);
  EXPECT_EQ(r.detail, "the service is stopping");
  EXPECT_EQ(rig.controller.snapshot().call_count, 0U);
}

TEST(Calls, ATravelRefusedWhileTheServiceStopsAsOnEveryLift) {
  // The first gates of a travel command are the shared ones (lift::ControllerCore): the service
  // stop before the floor, with the same text on every drive kind.
  Rig rig;
  ASSERT_TRUE(rig.warm_up());
  ASSERT_EQ(rig.command(ShutdownCommand{false}).code, ReplyCode::Ok);
  for (std::size_t floor : {2U, 99U}) {
    TravelCommand travel;
    travel.floor = floor;
    const CommandReply r = rig.command(travel);
    EXPECT_EQ(r.code, ReplyCode::NotReady) << floor;
    EXPECT_EQ(r.detail, "the service is stopping") << floor;
  }
}

TEST(Calls, NoReplyIsLostWhenCommandsComeFasterThanRepliesAreRead) {
  // Clients pipeline calls while the io thread does not read replies: every command the cycle
  // took gets exactly one reply; the rest are refused before they are queued (post() false, the
  // daemon answers busy), so no client waits for an answer that never comes.
  Rig rig;
  ASSERT_TRUE(rig.warm_up());
  rig.read_replies = false;
  int accepted = 0;
  int refused = 0;
  std::map<std::uint32_t, int> answered;
  auto read = [&] {
    CommandReply r;
    while (rig.controller.poll_reply(r)) ++answered[r.tag];
  };
  for (int round = 0; round < 40; ++round) {
    for (int i = 0; i < 20; ++i) {
      const bool add = (i % 2) == 0;
      const Command c{++rig.next_tag, (add ? CallCommand::adding : CallCommand::cancelling)(
                                          static_cast<std::size_t>(1 + i % 3))};
      if (rig.controller.post(c)) {
        ++accepted;
      } else {
        ++refused;
      }
    }
    rig.cycle();
    if (round % 8 == 7) read();
  }
  rig.cycle();
  read();
  EXPECT_GT(refused, 0) << "the test never filled the queues";
  EXPECT_EQ(static_cast<int>(answered.size()), accepted);
  for (const auto& [tag, n] : answered) EXPECT_EQ(n, 1) << "tag " << tag;
  EXPECT_EQ(rig.controller.lost_replies(), 0U);
  EXPECT_EQ(rig.controller.replies_owed(), 0U);
}

TEST(Calls, ServedInOrder) {
  Rig rig;
  ASSERT_TRUE(rig.warm_up());
  for (std::size_t floor : {3U, 1U, 4U}) {
    ASSERT_EQ(rig.command(CallCommand::adding(floor)).code, ReplyCode::Ok);
  }
  ASSERT_TRUE(rig.run_until(
      [&] { return rig.events_of(ControllerEvent::Kind::CallServed).size() == 3; }, 120s));
  const auto served = rig.events_of(ControllerEvent::Kind::CallServed);
  EXPECT_EQ(served[0].floor, 3U);
  EXPECT_EQ(served[1].floor, 1U);
  EXPECT_EQ(served[2].floor, 4U);
  ASSERT_TRUE(rig.run_until([&] { return rig.idle(); }, 10s));
  EXPECT_NEAR(rig.sim.position_mm(), 12000.0, kDcp4LandingMm);
  EXPECT_EQ(rig.controller.snapshot().call_count, 0U);
  // Each finished travel ended where its call asked.
  const auto finished = rig.travel_events(travel::Event::Type::Finished);
  ASSERT_GE(finished.size(), 3U);
  EXPECT_EQ(finished[0].target_mm, 9000);
  EXPECT_EQ(finished[1].target_mm, 3000);
  EXPECT_EQ(finished[2].target_mm, 12000);
}

}  // namespace
}  // namespace liftd::control
