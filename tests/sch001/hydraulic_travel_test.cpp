// The hydraulic travel sequencing with a fake clock and a scripted car: the signals of every
// phase as bytes of our 0x68 answer (card document 3c: SP3 SP2 SP1 SFY MSP HSP DW UP), the
// faults that end a travel at once and are reported once, and what may start.
#include <gtest/gtest.h>

#include <chrono>
#include <functional>
#include <vector>

#include "sch001/hydraulic_travel.hpp"

namespace liftd::sch001 {
namespace {

using std::chrono::milliseconds;

// Command bytes (3c).
constexpr std::uint8_t kUp = 0x01, kDw = 0x02, kHsp = 0x04, kMsp = 0x08, kSfy = 0x10, kSp1 = 0x20,
                       kSp2 = 0x40, kSp3 = 0x80;

class HydraulicTest : public ::testing::Test {
 protected:
  HydraulicTest() {
    const std::vector<std::int64_t> levels = {0, 3000, 6000, 9000};
    floors_.assign(levels);
    in_.inputs.valid = in_.inputs.safety_chain_closed = true;
    in_.inputs.doors_closed = in_.inputs.doors_locked = true;
    in_.card_allows_travel = true;
    in_.position_mm = 0;
  }
  /// One tick at `t_ms` with the car at `position_mm`; returns the command byte and checks the
  /// rules that hold in every state.
  std::uint8_t tick(int t_ms, std::optional<std::int64_t> position_mm) {
    in_.now = milliseconds(t_ms);
    in_.position_mm = position_mm;
    const TickOutput out = travel_.tick(floors_, in_);
    const std::uint8_t byte = out.bits.to_byte();
    // 1.4: SFY only while the motor runs; the motor runs for the pump, i.e. going up.
    if (out.bits.sfy) {
      EXPECT_TRUE(out.motor_on && out.bits.up) << "t=" << t_ms;
    }
    EXPECT_FALSE(out.bits.up && out.bits.dw) << "t=" << t_ms;
    if (out.bits.sp1 || out.bits.sp2) {
      EXPECT_TRUE(out.bits.hsp) << "t=" << t_ms;  // 1.4
    }
    return byte;
  }
  std::vector<TravelEvent> events() {
    std::vector<TravelEvent> out;
    TravelEvent e;
    while (travel_.poll_event(e)) out.push_back(e);
    return out;
  }

  HydraulicConfig config_;
  HydraulicTravel travel_{config_};
  lift::FloorTable floors_;
  TickInput in_;
};

TEST_F(HydraulicTest, UpTravelStartsTheMotorThenFastThenSlowThenStopsAtTheLevel) {
  ASSERT_EQ(travel_.start_travel(floors_, 2, Speed::Fast, in_), lift::Cause::None);
  EXPECT_EQ(tick(0, 0), 0) << "star-delta start: no signal before the motor runs";
  EXPECT_EQ(tick(1499, 0), 0);
  EXPECT_EQ(tick(1500, 0), kUp | kHsp | kSfy);
  EXPECT_EQ(tick(3000, 5499), kUp | kHsp | kSfy);
  EXPECT_EQ(tick(3100, 5500), kUp | kSfy) << "slowdown 500 mm before the level";
  EXPECT_EQ(tick(4000, 5996), kUp | kSfy);
  EXPECT_EQ(tick(4100, 5997), 0) << "within the 3 mm stop tolerance";
  EXPECT_EQ(travel_.kind(), TravelKind::None);
  EXPECT_EQ(travel_.current_floor(), 2U);
  const auto ev = events();
  ASSERT_EQ(ev.size(), 2U);
  EXPECT_EQ(ev[0].type, TravelEvent::Type::Started);
  EXPECT_EQ(ev[1].type, TravelEvent::Type::Finished);
  EXPECT_EQ(ev[1].floor, 2U);
  EXPECT_EQ(tick(5000, 5998), 0);
}

TEST_F(HydraulicTest, DownTravelByTheValveAloneWithTheConfiguredFastSignal) {
  struct Case {
    FastDown fast_down;
    std::uint8_t fast;
  };
  for (const Case& c : {Case{FastDown::Hsp, kDw | kHsp}, Case{FastDown::Sp3, kDw | kSp3}}) {
    config_.fast_down = c.fast_down;
    travel_ = HydraulicTravel(config_);
    travel_.set_current_floor(3);
    in_.now = MonoTime{};
    in_.position_mm = 9000;
    ASSERT_EQ(travel_.start_travel(floors_, 0, Speed::Fast, in_), lift::Cause::None);
    EXPECT_EQ(tick(0, 9000), c.fast) << "no motor start going down";
    EXPECT_EQ(tick(5000, 701), c.fast);
    EXPECT_EQ(tick(5100, 700), kDw) << "slowdown 700 mm above the level";
    EXPECT_EQ(tick(6000, 3), 0);
    EXPECT_EQ(travel_.current_floor(), 0U);
  }
}

TEST_F(HydraulicTest, FasterSpeedsWhereTheUnitHasThem) {
  struct Case {
    bool v3, v4;
    Speed asked;
    std::uint8_t fast;
    std::int64_t slow_at;  // the position where the slowdown starts (target 9000)
  };
  for (const Case& c : {Case{true, true, Speed::V4, kUp | kHsp | kSfy | kSp2, 7500},
                        Case{true, true, Speed::V3, kUp | kHsp | kSfy | kSp1, 8000},
                        Case{true, false, Speed::V4, kUp | kHsp | kSfy | kSp1, 8000},
                        Case{false, false, Speed::V4, kUp | kHsp | kSfy, 8500},
                        Case{false, false, Speed::V3, kUp | kHsp | kSfy, 8500}}) {
    config_.has_v3 = c.v3;
    config_.has_v4 = c.v4;
    travel_ = HydraulicTravel(config_);
    in_.now = MonoTime{};
    in_.position_mm = 0;
    ASSERT_EQ(travel_.start_travel(floors_, 3, c.asked, in_), lift::Cause::None);
    tick(0, 0);
    EXPECT_EQ(tick(2000, c.slow_at - 1), c.fast);
    EXPECT_EQ(tick(2100, c.slow_at), kUp | kSfy);
    travel_.abort(lift::Cause::StopRequested, milliseconds(2200));
  }
}

// 3b/3c: the card takes our signals only in the answer to its status frame, every 100 ms; at
// 0.5 m/s the car covers 50 mm between two. The slowdown comes at the frame nearest the point
// (8500 for floor 3 at 9000), never more than half a period's travel (25 mm) before or after it,
// whatever the frames' phase: the slow approach, at a tenth of the speed, would otherwise last
// up to a second longer or shorter from travel to travel.
TEST_F(HydraulicTest, TheSpeedSignalsDropAtTheStatusFrameNearestTheSlowdownPoint) {
  struct Case {
    std::int64_t phase_mm;      // where the car is at a frame, modulo 50 mm, below 8500
    std::int64_t slow_from_mm;  // the first frame's position that gets the slow signals
  };
  for (const Case& c : {Case{0, 8500}, Case{1, 8501}, Case{24, 8524}, Case{25, 8475},
                        Case{26, 8476}, Case{49, 8499}}) {
    travel_ = HydraulicTravel(config_);
    in_.now = MonoTime{};
    in_.position_mm = 0;
    ASSERT_EQ(travel_.start_travel(floors_, 3, Speed::Fast, in_), lift::Cause::None);
    tick(0, 0);
    int t = 1500;
    for (std::int64_t p = 8000 + c.phase_mm; p <= 8600; p += 50, t += 100) {
      const std::uint8_t expected = p >= c.slow_from_mm ? kUp | kSfy : kUp | kHsp | kSfy;
      EXPECT_EQ(tick(t, p), expected) << "phase " << c.phase_mm << " at " << p << " mm";
    }
    travel_.abort(lift::Cause::StopRequested, milliseconds(t));
  }
}

// The speed is measured over one status period: a position from longer ago (a car that stood,
// a tick that came late) gives no lead, the slowdown point is then taken as it is.
TEST_F(HydraulicTest, APositionFromLongAgoGivesNoLeadOnTheSlowdownPoint) {
  ASSERT_EQ(travel_.start_travel(floors_, 3, Speed::Fast, in_), lift::Cause::None);
  tick(0, 0);
  EXPECT_EQ(tick(1500, 8400), kUp | kHsp | kSfy);
  EXPECT_EQ(tick(1801, 8499), kUp | kHsp | kSfy) << "301 ms since the last tick: no speed known";
  EXPECT_EQ(tick(1901, 8500), kUp | kSfy);
}

// The controller may step twice on one status frame (faults, then calls), microseconds apart,
// with the position a millimetre on: that is no speed of metres per second, and the slowdown
// stays where the last frames' speed puts it.
TEST_F(HydraulicTest, TwoStepsOnOneFrameMeasureNoSpeed) {
  ASSERT_EQ(travel_.start_travel(floors_, 3, Speed::Fast, in_), lift::Cause::None);
  tick(0, 0);
  EXPECT_EQ(tick(1500, 7000), kUp | kHsp | kSfy);
  EXPECT_EQ(tick(1600, 7050), kUp | kHsp | kSfy);
  in_.now = milliseconds(1700);
  in_.position_mm = 7100;
  travel_.tick(floors_, in_);
  in_.now += std::chrono::microseconds(20);
  in_.position_mm = 7101;
  EXPECT_EQ(travel_.tick(floors_, in_).bits.to_byte(), kUp | kHsp | kSfy)
      << "1 mm in 20 us is no speed: 1399 mm from the level is far from the slowdown";
  EXPECT_EQ(tick(1800, 7150), kUp | kHsp | kSfy);
  EXPECT_EQ(tick(2900, 8420), kUp | kHsp | kSfy) << "1100 ms: no speed known, no lead";
  EXPECT_EQ(tick(3000, 8476), kUp | kSfy)
      << "524 mm from the level, 56 mm in the last 100 ms: this frame is the nearest";
}

TEST_F(HydraulicTest, EveryFaultEndsTheTravelAtOnceReportedOnce) {
  struct Case {
    const char* name;
    void (*inject)(TickInput&);
    lift::Cause cause;
  };
  const std::vector<Case> cases = {
      {"RDY drops", [](TickInput& i) { i.card_allows_travel = false; }, lift::Cause::DriveNotReady},
      {"ERR",
       [](TickInput& i) {
         i.card_error = true;
         i.card_allows_travel = false;
       },
       lift::Cause::DriveFault},
      {"card silent",
       [](TickInput& i) {
         i.card_silent = true;
         i.card_allows_travel = false;
       },
       lift::Cause::CardSilent},
      {"bus-off", [](TickInput& i) { i.bus_ok = false; }, lift::Cause::BusFault},
      {"safety chain", [](TickInput& i) { i.inputs.safety_chain_closed = false; },
       lift::Cause::SafetyChainOpen},
      {"doors", [](TickInput& i) { i.inputs.doors_locked = false; }, lift::Cause::DoorsNotLocked},
      {"inputs lost", [](TickInput& i) { i.inputs.valid = false; }, lift::Cause::InputsLost},
  };
  for (const Case& c : cases) {
    travel_ = HydraulicTravel(config_);
    in_ = TickInput{};
    in_.inputs.valid = in_.inputs.safety_chain_closed = true;
    in_.inputs.doors_closed = in_.inputs.doors_locked = true;
    in_.card_allows_travel = true;
    in_.position_mm = 0;
    ASSERT_EQ(travel_.start_travel(floors_, 3, Speed::Fast, in_), lift::Cause::None) << c.name;
    tick(0, 0);
    ASSERT_EQ(tick(2000, 1000), kUp | kHsp | kSfy) << c.name;
    c.inject(in_);
    EXPECT_EQ(tick(2015, 1010), 0) << c.name << ": a travel bit after the fault";
    const TickInput healthy = [&] {
      TickInput i;
      i.inputs.valid = i.inputs.safety_chain_closed = i.inputs.doors_locked = true;
      i.card_allows_travel = true;
      return i;
    }();
    in_ = healthy;
    EXPECT_EQ(tick(2030, 1020), 0) << c.name << ": the travel resumed by itself";
    const auto ev = events();
    ASSERT_EQ(ev.size(), 2U) << c.name;
    EXPECT_EQ(ev[1].type, TravelEvent::Type::Aborted) << c.name;
    EXPECT_EQ(ev[1].cause, c.cause) << c.name << ": " << to_string(ev[1].cause);
  }
}

TEST_F(HydraulicTest, PositionLostAndTheRunTimeLimiterEndTravels) {
  ASSERT_EQ(travel_.start_travel(floors_, 3, Speed::Fast, in_), lift::Cause::None);
  tick(0, 0);
  EXPECT_EQ(tick(2000, std::nullopt), 0);
  EXPECT_EQ(events().back().cause, lift::Cause::PositionLost);
  config_.max_travel_ms = 10000;
  travel_ = HydraulicTravel(config_);
  in_.now = MonoTime{};
  in_.position_mm = 0;
  ASSERT_EQ(travel_.start_travel(floors_, 3, Speed::Fast, in_), lift::Cause::None);
  EXPECT_EQ(tick(10000, 100), kUp | kHsp | kSfy);
  EXPECT_EQ(tick(10001, 100), 0) << "the car hardly moved in 10 s: pump or valve fault";
  EXPECT_EQ(events().back().cause, lift::Cause::TravelTimeout);
}

TEST_F(HydraulicTest, NothingStartsWhileAConditionForbidsIt) {
  in_.card_allows_travel = false;
  EXPECT_EQ(travel_.start_travel(floors_, 1, Speed::Fast, in_), lift::Cause::DriveNotReady);
  in_.card_allows_travel = true;
  in_.inputs.doors_locked = false;
  EXPECT_EQ(travel_.start_travel(floors_, 1, Speed::Fast, in_), lift::Cause::DoorsNotLocked);
  in_.position_mm.reset();
  in_.inputs.doors_locked = true;
  EXPECT_EQ(travel_.start_travel(floors_, 1, Speed::Fast, in_), lift::Cause::PositionLost);
  EXPECT_TRUE(events().empty());
  EXPECT_EQ(tick(0, std::nullopt), 0);
}

TEST_F(HydraulicTest, RelevellingAtTheSlowSpeedWithDoorsOpenWhereAllowed) {
  travel_.set_current_floor(1);
  in_.inputs.doors_locked = in_.inputs.doors_closed = false;
  in_.inputs.door_zone_bridge = true;
  in_.position_mm = 2985;  // sank 15 mm
  ASSERT_EQ(travel_.start_relevel(floors_, 1, in_), lift::Cause::None);
  EXPECT_EQ(tick(0, 2985), 0);
  EXPECT_EQ(tick(1500, 2985), kUp | kSfy) << "up by the pump at the slow speed only";
  EXPECT_EQ(tick(3000, 2998), 0);
  EXPECT_EQ(travel_.current_floor(), 1U);
  // Above the level: down by the valve at the slow speed.
  in_.position_mm = 3020;
  ASSERT_EQ(travel_.start_relevel(floors_, 1, in_), lift::Cause::None);
  EXPECT_EQ(tick(4000, 3020), kDw);
  // Without the bridge, or with relevelling at open doors not allowed: refused.
  travel_.abort(lift::Cause::StopRequested, milliseconds(4100));
  in_.inputs.door_zone_bridge = false;
  EXPECT_EQ(travel_.start_relevel(floors_, 1, in_), lift::Cause::DoorsNotLocked);
  config_.relevel_doors_open = false;
  travel_ = HydraulicTravel(config_);
  in_.inputs.door_zone_bridge = true;
  EXPECT_EQ(travel_.start_relevel(floors_, 1, in_), lift::Cause::DoorsNotLocked);
}

TEST_F(HydraulicTest, InspectionRunsWhileHeldAndStopsAtTheTerminalLevels) {
  ASSERT_EQ(travel_.inspect(lift::Direction::Up, in_), lift::Cause::None);
  EXPECT_EQ(tick(0, 0), 0);
  EXPECT_EQ(tick(1500, 10), kUp | kSfy | kMsp);
  EXPECT_EQ(tick(9000, 8999), kUp | kSfy | kMsp);
  EXPECT_EQ(tick(9100, 9000), 0) << "the top level ends an inspection run up";
  ASSERT_EQ(travel_.inspect(lift::Direction::Down, in_), lift::Cause::None);
  EXPECT_EQ(tick(9200, 9000), kDw | kMsp);
  ASSERT_EQ(travel_.inspect(lift::Direction::None, in_), lift::Cause::None);
  EXPECT_EQ(tick(9300, 8990), 0) << "released";
}

TEST_F(HydraulicTest, StopLandsAtTheNextReachableFloor) {
  ASSERT_EQ(travel_.start_travel(floors_, 3, Speed::Fast, in_), lift::Cause::None);
  tick(0, 0);
  tick(1500, 0);
  ASSERT_EQ(tick(2000, 2000), kUp | kHsp | kSfy);
  // Floor 1 (3000) is 1000 mm ahead, beyond the 500 mm slowdown: the car stops there.
  EXPECT_EQ(travel_.stop(floors_, in_), std::optional<std::size_t>(1));
  EXPECT_EQ(tick(2100, 2600), kUp | kSfy);
  EXPECT_EQ(tick(2200, 2998), 0);
  EXPECT_EQ(travel_.current_floor(), 1U);
  // Before the motor runs there is nothing to land: everything drops.
  ASSERT_EQ(travel_.start_travel(floors_, 3, Speed::Fast, in_), lift::Cause::None);
  EXPECT_EQ(travel_.stop(floors_, in_), std::nullopt);
  EXPECT_EQ(events().back().cause, lift::Cause::StopRequested);
}

TEST_F(HydraulicTest, ShaftSignalsSlowAndStopWhereTheyAreMet) {
  ASSERT_EQ(travel_.start_travel(floors_, 1, Speed::Fast, in_), lift::Cause::None);
  tick(0, 0);
  EXPECT_EQ(tick(1500, 100), kUp | kHsp | kSfy);
  in_.inputs.decel_up[0] = true;  // V1 (fast) up
  EXPECT_EQ(tick(1600, 1000), kUp | kSfy);
  in_.inputs.decel_up[0] = false;
  in_.inputs.level_zone = true;
  EXPECT_EQ(tick(1700, 2900), 0);
  EXPECT_EQ(travel_.current_floor(), 1U);
}

// ---- the learning travel's legs (lift/learning_travel.hpp) ----

TEST_F(HydraulicTest, LearningLegUpRunsAtTheSlowSpeedThroughTheZonesAndEndsByPosition) {
  // The issue: "the slow speed on a hydraulic unit"; 1.4: the direction signal alone (no HSP,
  // SP1, SP2), SFY once the motor runs after its star-delta start.
  ASSERT_EQ(travel_.start_learning(9300, lift::Direction::Up, in_), lift::Cause::None);
  EXPECT_EQ(travel_.kind(), TravelKind::Learn);
  EXPECT_EQ(travel_.target(), std::nullopt) << "a leg goes to no floor";
  struct Step {
    int t_ms;
    std::int64_t position_mm;
    bool level_zone;
    std::uint8_t byte;
    const char* legend;
  };
  const Step steps[] = {
      {0, 0, true, 0, "star-delta start: nothing before the motor runs"},
      {1499, 0, true, 0, "still starting"},
      {1500, 0, true, kUp | kSfy, "slow up: UP and SFY alone"},
      {30000, 2950, true, kUp | kSfy, "a level zone stops no learning leg"},
      {60000, 6000, false, kUp | kSfy, "past the slowdown point of floor 2: still slow"},
      {90000, 9299, false, kUp | kSfy, "1 mm short of the leg's end"},
      {90100, 9300, false, 0, "at the leg's end: every signal drops"},
  };
  for (const Step& s : steps) {
    in_.inputs.level_zone = s.level_zone;
    EXPECT_EQ(tick(s.t_ms, s.position_mm), s.byte) << s.legend;
  }
  const auto ev = events();
  ASSERT_EQ(ev.size(), 2U);
  EXPECT_EQ(ev[0].kind, TravelKind::Learn);
  EXPECT_EQ(ev[1].type, TravelEvent::Type::Finished);
  EXPECT_EQ(travel_.current_floor(), 3U) << "3c: the floor nearest where the leg ended";
}

TEST_F(HydraulicTest, LearningLegDownByTheValveFastThenSlowToItsEnd) {
  struct Case {
    FastDown fast_down;
    std::uint8_t fast;
  };
  for (const Case& c : {Case{FastDown::Hsp, kDw | kHsp}, Case{FastDown::Sp3, kDw | kSp3}}) {
    config_.fast_down = c.fast_down;
    travel_ = HydraulicTravel(config_);
    in_.now = MonoTime{};
    in_.position_mm = 6000;
    ASSERT_EQ(travel_.start_learning(-300, lift::Direction::Down, in_), lift::Cause::None);
    EXPECT_EQ(tick(0, 6000), c.fast) << "no motor start going down";
    EXPECT_EQ(tick(5000, 401), c.fast);
    EXPECT_EQ(tick(5100, 400), kDw) << "slowdown 700 mm above the leg's end";
    in_.inputs.level_zone = true;
    EXPECT_EQ(tick(6000, 0), kDw) << "the bottom floor's zone stops no learning leg";
    in_.inputs.level_zone = false;
    EXPECT_EQ(tick(9000, -299), kDw);
    EXPECT_EQ(tick(9100, -300), 0);
    EXPECT_EQ(travel_.kind(), TravelKind::None);
  }
}

TEST_F(HydraulicTest, LearningLegUpEndsWhereTheRunOutSaysAndOnlyThere) {
  ASSERT_EQ(travel_.start_learning(9300, lift::Direction::Up, in_), lift::Cause::None);
  tick(0, 0);
  ASSERT_EQ(tick(1500, 0), kUp | kSfy);
  EXPECT_TRUE(travel_.end_learning_at(9070));
  EXPECT_EQ(tick(60000, 9069), kUp | kSfy);
  EXPECT_EQ(tick(60100, 9070), 0);
  EXPECT_FALSE(travel_.end_learning_at(9100)) << "no leg runs";
  // A leg down has no run-out, nor has a travel.
  in_.position_mm = 9070;
  ASSERT_EQ(travel_.start_learning(-300, lift::Direction::Down, in_), lift::Cause::None);
  EXPECT_FALSE(travel_.end_learning_at(100));
  travel_.abort(lift::Cause::StopRequested, milliseconds(60200));
  ASSERT_EQ(travel_.start_travel(floors_, 0, Speed::Fast, in_), lift::Cause::None);
  EXPECT_FALSE(travel_.end_learning_at(100));
}

TEST_F(HydraulicTest, AFaultMidLegEndsItAtOnceWithEverySignalDropped) {
  struct Case {
    const char* legend;
    std::function<void(TickInput&)> fault;
    lift::Cause cause;
  };
  const Case cases[] = {
      {"card ERR (3d)", [](TickInput& in) { in.card_error = true; }, lift::Cause::DriveFault},
      {"RDY = 0 (3e)", [](TickInput& in) { in.card_allows_travel = false; },
       lift::Cause::DriveNotReady},
      {"card silent (3f)", [](TickInput& in) { in.card_silent = true; }, lift::Cause::CardSilent},
      {"bus fault", [](TickInput& in) { in.bus_ok = false; }, lift::Cause::BusFault},
      {"safety chain", [](TickInput& in) { in.inputs.safety_chain_closed = false; },
       lift::Cause::SafetyChainOpen},
      {"doors", [](TickInput& in) { in.inputs.doors_locked = false; }, lift::Cause::DoorsNotLocked},
      {"inputs stale", [](TickInput& in) { in.inputs.valid = false; }, lift::Cause::InputsLost},
  };
  for (const Case& c : cases) {
    travel_ = HydraulicTravel(config_);
    (void)events();
    TickInput healthy = in_;
    in_.now = MonoTime{};
    in_.position_mm = -300;
    ASSERT_EQ(travel_.start_learning(1100, lift::Direction::Up, in_), lift::Cause::None)
        << c.legend;
    tick(0, -300);
    ASSERT_EQ(tick(1500, -300), kUp | kSfy) << c.legend;
    c.fault(in_);
    EXPECT_EQ(tick(1600, -295), 0) << c.legend;
    EXPECT_EQ(travel_.kind(), TravelKind::None) << c.legend;
    const auto ev = events();
    ASSERT_EQ(ev.size(), 2U) << c.legend;
    EXPECT_EQ(ev[1].type, TravelEvent::Type::Aborted) << c.legend;
    EXPECT_EQ(ev[1].cause, c.cause) << c.legend;
    // The same condition refuses a new leg.
    EXPECT_EQ(travel_.start_learning(1100, lift::Direction::Up, in_), c.cause) << c.legend;
    in_ = healthy;
  }
  in_.position_mm = std::nullopt;
  EXPECT_EQ(travel_.start_learning(1100, lift::Direction::Up, in_), lift::Cause::PositionLost);
}

TEST_F(HydraulicTest, StopEndsALearningLegAtOnce) {
  ASSERT_EQ(travel_.start_learning(9300, lift::Direction::Up, in_), lift::Cause::None);
  tick(0, 0);
  ASSERT_EQ(tick(1500, 0), kUp | kSfy);
  in_.position_mm = 100;
  EXPECT_EQ(travel_.stop(floors_, in_), std::nullopt) << "no floor to land at";
  EXPECT_EQ(tick(1600, 100), 0);
  const auto ev = events();
  ASSERT_EQ(ev.size(), 2U);
  EXPECT_EQ(ev[1].type, TravelEvent::Type::Aborted);
  EXPECT_EQ(ev[1].cause, lift::Cause::StopRequested);
}

TEST_F(HydraulicTest, TheRunTimeLimiterAllowsASlowRunThroughTheLeg) {
  // 9300 mm at 40 ms/mm on top of the 45 s limiter (lift::learn_leg_limit_ms): 417 s.
  ASSERT_EQ(travel_.start_learning(9300, lift::Direction::Up, in_), lift::Cause::None);
  tick(0, 0);
  EXPECT_EQ(tick(45001, 2000), kUp | kSfy) << "past the limit of a travel: a leg goes on";
  EXPECT_EQ(tick(417000, 9000), kUp | kSfy);
  EXPECT_EQ(tick(417001, 9000), 0);
  EXPECT_EQ(events().back().cause, lift::Cause::TravelTimeout);
}

}  // namespace
}  // namespace liftd::sch001
