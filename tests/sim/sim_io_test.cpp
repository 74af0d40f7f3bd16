// sim::SimulatedIo with a fake clock: defaults, the door model's timing, open on arrival,
// reversal and obstruction, safety chain, switches and end zones.
#include "sim/sim_io.hpp"

#include <gtest/gtest.h>

namespace liftd::sim {
namespace {

using namespace std::chrono_literals;

TEST(SimIo, PowersOnReadyToTravel) {
  SimulatedIo io;
  const lift::Inputs in = io.inputs(0ms);
  EXPECT_TRUE(in.valid);
  EXPECT_TRUE(in.safety_chain_closed);
  EXPECT_TRUE(in.doors_closed);
  EXPECT_TRUE(in.doors_locked);
  EXPECT_FALSE(in.door_reversal);
  EXPECT_FALSE(in.inspection);
  EXPECT_FALSE(in.recall);
  EXPECT_FALSE(in.button_up || in.button_down);
  EXPECT_FALSE(in.end_zone_top || in.end_zone_bottom);
  EXPECT_EQ(io.door_state(), DoorState::Locked);
}

TEST(SimIo, DoorsOpenThenCloseAndLockOnTime) {
  // Legend: open takes 2 s, close 2 s, the lock engages 300 ms after closing (defaults).
  SimulatedIo io({}, 0ms);
  io.open_doors(1000ms);
  struct Step {
    MonoTime at;
    DoorState state;
    bool closed;
    bool locked;
  };
  const Step opening[] = {
      {1000ms, DoorState::Opening, false, false},  // unlocked at once
      {2000ms, DoorState::Opening, false, false},  // half open
      {2999ms, DoorState::Opening, false, false},
      {3000ms, DoorState::Open, false, false},  // fully open after 2 s
  };
  for (const auto& s : opening) {
    const lift::Inputs in = io.inputs(s.at);
    EXPECT_EQ(io.door_state(), s.state) << s.at.count();
    EXPECT_EQ(in.doors_closed, s.closed) << s.at.count();
    EXPECT_EQ(in.doors_locked, s.locked) << s.at.count();
  }
  EXPECT_DOUBLE_EQ(io.door_opening(), 1.0);

  io.close_doors(5000ms);
  const Step closing[] = {
      {6000ms, DoorState::Closing, false, false},
      {6999ms, DoorState::Closing, false, false},
      {7000ms, DoorState::Closed, true, false},  // closed after 2 s
      {7299ms, DoorState::Closed, true, false},
      {7300ms, DoorState::Locked, true, true},  // locked 300 ms later
  };
  for (const auto& s : closing) {
    const lift::Inputs in = io.inputs(s.at);
    EXPECT_EQ(io.door_state(), s.state) << s.at.count();
    EXPECT_EQ(in.doors_closed, s.closed) << s.at.count();
    EXPECT_EQ(in.doors_locked, s.locked) << s.at.count();
  }
}

TEST(SimIo, OneLargeStepCrossesSeveralStatesAtTheRightTimes) {
  SimulatedIo io({}, 0ms);
  io.open_doors(0ms);
  io.advance(10s);
  EXPECT_EQ(io.door_state(), DoorState::Open);
  io.close_doors(10s);
  io.advance(12s + 300ms);  // closed at 12 s, locked at 12.3 s, in one call
  EXPECT_EQ(io.door_state(), DoorState::Locked);
  EXPECT_TRUE(io.inputs().doors_locked);
}

TEST(SimIo, TimingsAreConfigurable) {
  SimIoConfig c;
  c.close_ms = 500;
  c.lock_ms = 0;
  c.doors_open_at_start = true;
  SimulatedIo io(c, 0ms);
  EXPECT_EQ(io.door_state(), DoorState::Open);
  EXPECT_FALSE(io.inputs().doors_closed);
  io.close_doors(100ms);
  io.advance(599ms);
  EXPECT_EQ(io.door_state(), DoorState::Closing);
  io.advance(600ms);
  EXPECT_EQ(io.door_state(), DoorState::Locked) << "lock_ms 0 locks as soon as closed";
}

TEST(SimIo, PartlyOpenDoorsCloseInProportion) {
  SimulatedIo io({}, 0ms);
  io.open_doors(0ms);
  io.close_doors(500ms);  // a quarter open
  EXPECT_NEAR(io.door_opening(), 0.25, 1e-9);
  io.advance(999ms);
  EXPECT_EQ(io.door_state(), DoorState::Closing);
  io.advance(1000ms);
  EXPECT_EQ(io.door_state(), DoorState::Closed);
}

TEST(SimIo, OpenRequestWhileMovingWaitsForArrival) {
  SimulatedIo io({}, 0ms);
  io.set_car(true, 1000.0, 0ms);
  io.open_doors(100ms);
  EXPECT_TRUE(io.open_pending());
  io.advance(3s);
  EXPECT_EQ(io.door_state(), DoorState::Locked) << "doors stay shut while the car moves";
  io.set_car(false, 3000.0, 4s);  // arrival
  EXPECT_FALSE(io.open_pending());
  EXPECT_EQ(io.door_state(), DoorState::Opening);
  io.advance(6s);
  EXPECT_EQ(io.door_state(), DoorState::Open);
}

TEST(SimIo, OpenOnArrivalOpensAfterEveryTravel) {
  SimIoConfig c;
  c.open_on_arrival = true;
  SimulatedIo io(c, 0ms);
  io.set_car(false, 0.0, 0ms);
  EXPECT_EQ(io.door_state(), DoorState::Locked) << "no travel yet";
  io.set_car(true, 10.0, 1s);
  io.set_car(true, 2000.0, 4s);
  io.set_car(false, 3000.0, 5s);
  EXPECT_EQ(io.door_state(), DoorState::Opening);
}

TEST(SimIo, CloseCancelsAPendingOpen) {
  SimulatedIo io({}, 0ms);
  io.set_car(true, 0.0, 0ms);
  io.open_doors(0ms);
  io.close_doors(10ms);
  io.set_car(false, 0.0, 1s);
  EXPECT_EQ(io.door_state(), DoorState::Locked);
}

TEST(SimIo, InjectedReversalReopensClosingDoorsAndPulsesTheInput) {
  SimulatedIo io({}, 0ms);
  io.open_doors(0ms);
  io.close_doors(2s);           // from fully open
  io.inject_door_reversal(3s);  // half closed
  EXPECT_EQ(io.door_state(), DoorState::Opening);
  EXPECT_TRUE(io.inputs(3s).door_reversal);
  EXPECT_TRUE(io.inputs(3499ms).door_reversal);
  EXPECT_FALSE(io.inputs(3500ms).door_reversal) << "500 ms pulse";
  io.advance(3999ms);
  EXPECT_EQ(io.door_state(), DoorState::Opening);
  io.advance(4s);  // half way back takes 1 s
  EXPECT_EQ(io.door_state(), DoorState::Open);
}

TEST(SimIo, ObstructionRefusesClosingUntilReleased) {
  SimulatedIo io({}, 0ms);
  io.open_doors(0ms);
  io.advance(2s);
  io.set_door_obstructed(true, 2s);
  EXPECT_TRUE(io.inputs().door_reversal);
  io.close_doors(3s);
  EXPECT_EQ(io.door_state(), DoorState::Open);
  io.set_door_obstructed(false, 4s);
  EXPECT_FALSE(io.inputs().door_reversal);
  io.close_doors(4s);
  EXPECT_EQ(io.door_state(), DoorState::Closing);
}

TEST(SimIo, ReversalDoesNotOpenLockedDoors) {
  SimulatedIo io({}, 0ms);
  io.inject_door_reversal(1s);
  EXPECT_EQ(io.door_state(), DoorState::Locked);
  EXPECT_TRUE(io.inputs().door_reversal);
}

TEST(SimIo, SafetyChainSwitchesAndProviderFailure) {
  SimulatedIo io;
  io.set_safety_chain_open(true);
  io.set_inspection(true);
  io.set_recall(true);
  io.set_buttons(true, false);
  io.set_door_zone_bridge(true);
  lift::Inputs in = io.inputs(1s);
  EXPECT_FALSE(in.safety_chain_closed);
  EXPECT_TRUE(in.inspection);
  EXPECT_TRUE(in.recall);
  EXPECT_TRUE(in.button_up);
  EXPECT_FALSE(in.button_down);
  EXPECT_TRUE(in.door_zone_bridge);
  EXPECT_FALSE(in.level_zone) << "the simulated machine has no shaft signals (the API adds them)";
  io.set_safety_chain_open(false);
  io.set_valid(false);
  in = io.inputs(2s);
  EXPECT_TRUE(in.safety_chain_closed);
  EXPECT_FALSE(in.valid);
}

TEST(SimIo, EndZonesFollowTheCarPosition) {
  // Legend: shaft from 0 to 10000 mm, 300 mm end zones.
  SimIoConfig c;
  c.shaft_bottom_mm = 0.0;
  c.shaft_top_mm = 10000.0;
  SimulatedIo io(c, 0ms);
  struct Case {
    double position_mm;
    bool bottom;
    bool top;
  };
  const Case cases[] = {
      {0.0, true, false},     {299.0, true, false},  {300.0, false, false},  {5000.0, false, false},
      {9700.0, false, false}, {9701.0, false, true}, {10000.0, false, true},
  };
  for (const auto& k : cases) {
    io.set_car(false, k.position_mm, 0ms);
    const lift::Inputs in = io.inputs();
    EXPECT_EQ(in.end_zone_bottom, k.bottom) << k.position_mm;
    EXPECT_EQ(in.end_zone_top, k.top) << k.position_mm;
  }
}

}  // namespace
}  // namespace liftd::sim
