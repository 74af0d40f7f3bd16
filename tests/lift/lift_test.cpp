// Floors, next possible stop and the calls queue (DCP 11.1.2.1: which floors can still be served),
// and the lift rules every controller shares (inputs, inspection, start grace, calls answers).
#include <gtest/gtest.h>

#include <initializer_list>
#include <optional>
#include <string>
#include <vector>

#include "lift/faults.hpp"
#include "lift/floors.hpp"
#include "lift/lift_model.hpp"
#include "lift/rules.hpp"

namespace liftd::lift {
namespace {

// Five floors, 3 m apart, the lowest at 0.
const std::vector<std::int64_t> kLevels = {0, 3000, 6000, 9000, 12000};

FloorTable table() {
  FloorTable floors;
  EXPECT_TRUE(floors.assign(kLevels));
  return floors;
}

TEST(FloorTable, RejectsEmptyOrNotStrictlyIncreasing) {
  FloorTable floors;
  EXPECT_FALSE(floors.assign({}));
  const std::vector<std::int64_t> equal = {0, 3000, 3000};
  EXPECT_FALSE(floors.assign(equal));
  const std::vector<std::int64_t> falling = {0, 3000, 2000};
  EXPECT_FALSE(floors.assign(falling));
  const std::vector<std::int64_t> too_many(kMaxFloors + 1, 0);
  EXPECT_FALSE(floors.assign(too_many));
  EXPECT_EQ(floors.size(), 0U);
  EXPECT_TRUE(floors.assign(kLevels));
  EXPECT_FALSE(floors.assign(falling));
  EXPECT_EQ(floors.size(), 5U);  // a rejected table leaves the old one
}

TEST(FloorTable, FloorAtUsesTheLevelTolerance) {
  const FloorTable floors = table();
  // Legend: position, tolerance -> floor (nullopt: between floors).
  struct Case {
    std::int64_t position_mm;
    std::uint32_t tolerance_mm;
    std::optional<std::size_t> floor;
  };
  const std::vector<Case> cases = {
      {0, 5, 0},
      {5, 5, 0},
      {6, 5, std::nullopt},
      {-5, 5, 0},
      {2996, 5, 1},
      {3004, 5, 1},
      {4500, 5, std::nullopt},
      {12000, 0, 4},
      {12001, 0, std::nullopt},
  };
  for (const auto& c : cases) {
    EXPECT_EQ(floors.floor_at(c.position_mm, c.tolerance_mm), c.floor) << c.position_mm;
  }
}

TEST(Relevelling, ACarAtRestIsRelevelledToItsNearestFloorBeyondTheThresholdWithinTheZone) {
  const FloorTable floors = table();  // 3 m apart from 0
  struct Case {
    std::int64_t position_mm;
    std::optional<std::size_t> floor;
  };
  // threshold 15 mm, zone lift::kRelevelZoneMm (150 mm), on both sides of a level.
  const Case cases[] = {
      {3000, std::nullopt},
      {3015, std::nullopt},
      {2985, std::nullopt},  // within the threshold
      {3016, 1},
      {2984, 1},
      {3150, 1},  // relevelled
      {2850, 1},
      {3151, std::nullopt},
      {2849, std::nullopt},  // between floors
      {-20, 0},
      {6020, 2},
      {1500, std::nullopt},
  };
  for (const Case& c : cases) {
    EXPECT_EQ(floor_to_relevel(floors, c.position_mm, 15, kRelevelZoneMm), c.floor)
        << c.position_mm;
  }
  EXPECT_TRUE(drift_needs_relevel(-16, 15, 150));
  EXPECT_FALSE(drift_needs_relevel(-151, 15, 150));
  EXPECT_FALSE(floor_to_relevel(FloorTable{}, 10, 2, 150).has_value()) << "no floors";
}

TEST(NextPossibleStop, TableOfPositionsDirectionsAndDecelerationDistances) {
  const FloorTable floors = table();
  // Legend: position, direction, deceleration distance, margin -> next possible stop.
  // A floor counts when its level is at least decel + margin ahead.
  struct Case {
    std::int64_t position_mm;
    Direction direction;
    std::uint32_t decel_mm;
    std::uint32_t margin_mm;
    std::optional<std::size_t> expected;
  };
  const std::vector<Case> cases = {
      {0, Direction::Up, 1430, 100, 1},               // DCP example Sv 143 cm: floor 1 is 3 m away
      {1500, Direction::Up, 1430, 100, 2},            // 1500 mm left < 1530 needed: floor 2
      {1470, Direction::Up, 1430, 100, 1},            // exactly 1530 mm left: still possible
      {1471, Direction::Up, 1430, 100, 2},            // 1529 mm left: too late, next is floor 2
      {4000, Direction::Up, 2500, 0, 3},              // DCP example Sv 250 cm at V4
      {10000, Direction::Up, 2500, 0, std::nullopt},  // nothing ahead far enough
      {10000, Direction::Down, 2500, 100, 2},         // 6000 is 4 m below
      {7000, Direction::Down, 800, 100, 2},           // 1 m to floor 2: fine
      {6500, Direction::Down, 800, 100, 1},           // 500 mm to floor 2: too close
      {100, Direction::Down, 0, 0, 0},
      {-50, Direction::Down, 0, 0, std::nullopt},
      {5000, Direction::None, 0, 0, std::nullopt},  // stationary: nothing "ahead"
  };
  for (const auto& c : cases) {
    EXPECT_EQ(next_possible_stop(floors, c.position_mm, c.direction, c.decel_mm, c.margin_mm),
              c.expected)
        << c.position_mm;
  }
}

TEST(CallQueue, ServesInOrderAndCancels) {
  CallQueue calls;
  EXPECT_EQ(calls.add(3, 5), CallError::None);
  EXPECT_EQ(calls.add(1, 5), CallError::None);
  EXPECT_EQ(calls.add(4, 5), CallError::None);
  EXPECT_EQ(calls.add(1, 5), CallError::AlreadyQueued);
  EXPECT_EQ(calls.add(5, 5), CallError::NoSuchFloor);
  EXPECT_EQ(calls.front(), std::optional<std::size_t>(3));
  EXPECT_TRUE(calls.cancel(1));
  EXPECT_FALSE(calls.cancel(1));
  calls.pop_front();
  EXPECT_EQ(calls.front(), std::optional<std::size_t>(4));
  calls.pop_front();
  EXPECT_FALSE(calls.front().has_value());
  calls.pop_front();  // harmless on empty
  EXPECT_EQ(calls.size(), 0U);
}

TEST(CallQueue, FullQueueRefuses) {
  CallQueue calls;
  for (std::size_t i = 0; i < kMaxFloors; ++i) EXPECT_EQ(calls.add(i, kMaxFloors), CallError::None);
  EXPECT_EQ(calls.size(), kMaxFloors);
  EXPECT_EQ(calls.add(0, kMaxFloors), CallError::AlreadyQueued);
}

TEST(LiftModel, PublishesCurrentFloorAndNextPossibleStop) {
  LiftModel model({.level_tolerance_mm = 5, .stop_margin_mm = 100});
  ASSERT_TRUE(model.set_floors(kLevels));
  // Legend: position, direction, decel -> current floor, next possible stop.
  struct Case {
    std::optional<std::int64_t> position_mm;
    Direction direction;
    std::optional<std::uint32_t> decel_mm;
    std::optional<std::size_t> current;
    std::optional<std::size_t> next;
  };
  const std::vector<Case> cases = {
      {3002, Direction::None, std::nullopt, 1, 1},             // standing at floor 1
      {4400, Direction::None, std::nullopt, std::nullopt, 1},  // stopped between: nearest
      {3500, Direction::Up, 1430, std::nullopt, 2},
      {4600, Direction::Up, 1430, std::nullopt, 3},
      {4600, Direction::Up, std::nullopt, std::nullopt, std::nullopt},  // decel unknown
      {std::nullopt, Direction::Up, 1430, std::nullopt, std::nullopt},  // position invalid
  };
  for (const auto& c : cases) {
    model.update(c.position_mm, c.direction, c.decel_mm);
    EXPECT_EQ(model.current_floor(), c.current) << c.position_mm.value_or(-1);
    EXPECT_EQ(model.next_possible_stop(), c.next) << c.position_mm.value_or(-1);
  }
}

TEST(LiftModel, NewFloorTableClearsCalls) {
  LiftModel model;
  ASSERT_TRUE(model.set_floors(kLevels));
  EXPECT_EQ(model.calls().add(2, model.floors().size()), CallError::None);
  EXPECT_EQ(model.calls().add(9, model.floors().size()), CallError::NoSuchFloor);
  EXPECT_EQ(model.calls().size(), 1U);
  const std::vector<std::int64_t> two = {0, 4000};
  ASSERT_TRUE(model.set_floors(two));
  EXPECT_EQ(model.calls().size(), 0U);
}

// ---- the lift rules (one copy for the DCP, SCH001 and USS lifts) ----

using namespace std::chrono_literals;

LiftModel five_floors() {
  LiftModel lift;
  EXPECT_TRUE(lift.set_floors(kLevels));
  return lift;
}

/// A `calls set` command of `floors`.
CallCommand setting(std::initializer_list<std::uint8_t> floors) {
  CallCommand c;
  c.op = CallCommand::Op::Set;
  for (const std::uint8_t f : floors) c.floors[c.count++] = f;
  return c;
}
/// A `calls insert` command of `floor` at `position` (none: the end).
CallCommand inserting(std::size_t floor, std::optional<std::size_t> position) {
  CallCommand c;
  c.op = CallCommand::Op::Insert;
  c.floor = floor;
  c.position = position;
  return c;
}

TEST(LiftRules, CallsAnswersAreTheApisOnEveryLift) {
  // docs/api.md `calls`: what a dispatcher reads on every drive kind, applied one after another
  // to one queue (five floors); each change applies whole or changes nothing.
  struct Case {
    const char* what;
    CallCommand call;
    bool shutting_down;
    bool heading_for;  // a travel runs to the queue's first floor
    ReplyCode code;
    std::string_view detail;
    std::vector<std::size_t> queue;  // afterwards
  };
  constexpr std::string_view kKept =
      "the car keeps travelling to the first queued floor: the change follows it";
  const Case cases[] = {
      {"add", CallCommand::adding(3), false, false, ReplyCode::Ok, "", {3}},
      {"add again", CallCommand::adding(3), false, false, ReplyCode::Ok, "already queued", {3}},
      {"add a floor that does not exist",
       CallCommand::adding(5),
       false,
       false,
       ReplyCode::BadRequest,
       "no such floor",
       {3}},
      {"add while the service stops",
       CallCommand::adding(1),
       true,
       false,
       ReplyCode::NotReady,
       "the service is stopping",
       {3}},
      {"cancel", CallCommand::cancelling(3), false, false, ReplyCode::Ok, "", {}},
      {"cancel again",
       CallCommand::cancelling(3),
       false,
       false,
       ReplyCode::BadRequest,
       "floor is not queued",
       {}},
      {"cancel while the service stops",
       CallCommand::cancelling(1),
       true,
       false,
       ReplyCode::BadRequest,
       "floor is not queued",
       {}},
      {"set with repeats", setting({0, 1, 0}), false, false, ReplyCode::Ok, "", {0, 1, 0}},
      {"set twice in a row",
       setting({2, 2}),
       false,
       false,
       ReplyCode::BadRequest,
       "the same floor twice in a row",
       {0, 1, 0}},
      {"set a floor that does not exist",
       setting({2, 9}),
       false,
       false,
       ReplyCode::BadRequest,
       "no such floor",
       {0, 1, 0}},
      {"insert first", inserting(4, 0), false, false, ReplyCode::Ok, "", {4, 0, 1, 0}},
      {"insert at the end",
       inserting(2, std::nullopt),
       false,
       false,
       ReplyCode::Ok,
       "",
       {4, 0, 1, 0, 2}},
      {"insert next to itself",
       inserting(1, 2),
       false,
       false,
       ReplyCode::BadRequest,
       "the same floor twice in a row",
       {4, 0, 1, 0, 2}},
      {"insert beyond the end",
       inserting(3, 6),
       false,
       false,
       ReplyCode::BadRequest,
       "position is beyond the end of the queue",
       {4, 0, 1, 0, 2}},
      {"cancel takes the first of repeats",
       CallCommand::cancelling(0),
       false,
       false,
       ReplyCode::Ok,
       "",
       {4, 1, 0, 2}},
      {"insert ahead of the running target goes after it",
       inserting(3, 0),
       false,
       true,
       ReplyCode::Ok,
       kKept,
       {4, 3, 1, 0, 2}},
      {"set while a travel runs keeps its target first",
       setting({1, 2}),
       false,
       true,
       ReplyCode::Ok,
       kKept,
       {4, 1, 2}},
      {"set that names the running target first means that stop",
       setting({4, 0}),
       false,
       true,
       ReplyCode::Ok,
       kKept,
       {4, 0}},
      {"set nothing while a travel runs keeps its target",
       setting({}),
       false,
       true,
       ReplyCode::Ok,
       kKept,
       {4}},
      {"set nothing at rest empties the queue", setting({}), false, false, ReplyCode::Ok, "", {}},
      {"set while the service stops",
       setting({1}),
       true,
       false,
       ReplyCode::NotReady,
       "the service is stopping",
       {}},
  };
  LiftModel lift = five_floors();
  for (const Case& c : cases) {
    const Answer a = LiftRules::answer_call(lift, c.call, c.shutting_down, c.heading_for);
    EXPECT_EQ(a.code, c.code) << c.what;
    EXPECT_EQ(a.detail, c.detail) << c.what;
    std::vector<std::size_t> queue;
    for (std::size_t i = 0; i < lift.calls().size(); ++i) queue.push_back(lift.calls().at(i));
    EXPECT_EQ(queue, c.queue) << c.what;
  }
}

TEST(LiftRules, InputsAreValidWhileFreshAndTheApiInspectionHoldsItsDirection) {
  LiftRules rules(200ms, 300ms);
  const MonoTime t0{10s};
  EXPECT_FALSE(rules.current_inputs(t0).valid) << "nothing from the provider yet";
  Inputs sent;
  sent.safety_chain_closed = true;
  sent.doors_locked = true;
  rules.take_inputs(sent, t0);
  EXPECT_TRUE(rules.current_inputs(t0 + 200ms).valid);
  EXPECT_TRUE(rules.current_inputs(t0 + 200ms).doors_locked);
  EXPECT_FALSE(rules.current_inputs(t0 + 201ms).valid) << "older than inputs_timeout";

  rules.take_inputs(sent, t0 + 1s);
  rules.take_inspection(true, Direction::Up, t0 + 1s);
  Inputs in = rules.current_inputs(t0 + 1s + 300ms);
  EXPECT_TRUE(in.inspection);
  EXPECT_TRUE(in.button_up);
  EXPECT_FALSE(in.button_down);
  in = rules.current_inputs(t0 + 1s + 301ms);
  EXPECT_TRUE(in.inspection) << "inspection stays on";
  EXPECT_FALSE(in.button_up) << "the direction was not repeated within the hold";
  rules.take_inspection(false, Direction::Down, t0 + 1s + 310ms);
  in = rules.current_inputs(t0 + 1s + 320ms);
  EXPECT_FALSE(in.inspection);
  EXPECT_FALSE(in.button_down) << "off carries no direction";
}

TEST(LiftRules, StartGraceIsTwoInputTimeouts) {
  LiftRules rules(200ms, 300ms);
  const MonoTime t0{5s};
  rules.start(t0);
  EXPECT_FALSE(rules.start_grace_over(t0 + 400ms));
  EXPECT_TRUE(rules.start_grace_over(t0 + 401ms));
}

TEST(FaultTable, EachRaiseAndClearIsToldOnceAndInOrderWhateverTheQueueTakes) {
  // The io thread's event queue refuses (full) at some sets: what was not told is owed and told
  // at a later set; a fault that came and went while the queue was full is still told as one
  // raise and one clear; nothing is told twice.
  struct Step {
    bool active;
    bool queue_takes;
    const char* told;  // what reaches the queue at this set: r = raise, c = clear
  };
  struct Case {
    const char* what;
    std::vector<Step> steps;
  };
  const std::vector<Case> cases = {
      {"plain", {{true, true, "r"}, {true, true, ""}, {false, true, "c"}, {false, true, ""}}},
      {"raise waits", {{true, false, ""}, {true, false, ""}, {true, true, "r"}}},
      {"came and went while full", {{true, false, ""}, {false, false, ""}, {false, true, "rc"}}},
      {"ended and came again while full",
       {{true, true, "r"}, {false, false, ""}, {true, false, ""}, {true, true, "cr"}}},
      {"clear waits", {{true, true, "r"}, {false, false, ""}, {false, true, "c"}}},
  };
  for (const Case& c : cases) {
    FaultTable table;
    MonoTime now{1s};
    for (std::size_t i = 0; i < c.steps.size(); ++i) {
      const Step& step = c.steps[i];
      std::string told;
      table.set(FaultCode::DriveFault, step.active, now, [&](FaultCode code, bool raised) {
        EXPECT_EQ(code, FaultCode::DriveFault);
        if (!step.queue_takes) return false;
        told += raised ? 'r' : 'c';
        return true;
      });
      EXPECT_EQ(told, step.told) << c.what << ", step " << i;
      EXPECT_EQ(table.active(FaultCode::DriveFault), step.active) << c.what;
      now += 15ms;
    }
  }
}

TEST(FaultTable, KeepsWhenEachFaultBegan) {
  FaultTable table;
  const auto any = [](FaultCode, bool) { return true; };
  table.set(FaultCode::SafetyChain, true, MonoTime{2s}, any);
  table.set(FaultCode::SafetyChain, true, MonoTime{3s}, any);
  EXPECT_EQ(table.since_all()[static_cast<std::size_t>(FaultCode::SafetyChain)], MonoTime{2s});
  table.set(FaultCode::SafetyChain, false, MonoTime{4s}, any);
  table.set(FaultCode::SafetyChain, true, MonoTime{5s}, any);
  EXPECT_EQ(table.since_all()[static_cast<std::size_t>(FaultCode::SafetyChain)], MonoTime{5s});
  EXPECT_FALSE(table.active(FaultCode::LinkFault));
}

}  // namespace
}  // namespace liftd::lift
