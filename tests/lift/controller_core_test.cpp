// The shared command plumbing of every lift controller (lift/controller_core.hpp) and
// the travel sequencers' shared helpers (lift/gate.hpp, lift/floors.hpp, lift/travel_event.hpp),
// on a stub travel: the order of a travel command's gates, calls, inputs and inspection, faults.
#include <gtest/gtest.h>

#include <chrono>
#include <optional>
#include <type_traits>
#include <variant>
#include <vector>

#include "lift/car_snapshot.hpp"
#include "lift/controller_core.hpp"
#include "lift/gate.hpp"
#include "lift/travel_event.hpp"

namespace liftd::lift {
namespace {

using std::chrono::milliseconds;

enum class StubKind : std::uint8_t { None, Travel, Relevel, Inspection };
enum class StubPhase : std::uint8_t { Idle, Run };
enum class StubSpeed : std::uint8_t { V1, V4 };
using StubEvent = BasicTravelEvent<StubKind>;

struct StubInput {
  MonoTime now{};
  std::optional<std::int64_t> position_mm;
  Inputs inputs{};
};

/// A travel that starts when asked (or refuses with `refuse`), and lands when told.
class StubTravel {
 public:
  explicit StubTravel(Cause refuse) noexcept : refuse_(refuse) {}
  StubKind kind() const noexcept { return kind_; }
  StubPhase phase() const noexcept {
    return kind_ == StubKind::None ? StubPhase::Idle : StubPhase::Run;
  }
  Direction direction() const noexcept { return Direction::None; }
  std::optional<std::size_t> target() const noexcept {
    return kind_ == StubKind::Travel ? std::optional<std::size_t>(target_) : std::nullopt;
  }
  bool busy() const noexcept { return kind_ != StubKind::None; }
  void set_current_floor(std::size_t floor) noexcept { current_floor_ = floor; }
  std::size_t current_floor() const noexcept { return current_floor_; }
  /// The drive's side of a start, as the real travels check it first.
  Cause drive_forbidding(const StubInput&) const noexcept { return drive_refuse_; }
  Cause start_travel(std::size_t floor, MonoTime now) noexcept {
    if (drive_refuse_ != Cause::None) return drive_refuse_;
    if (refuse_ != Cause::None) return refuse_;
    kind_ = StubKind::Travel;
    target_ = floor;
    events_.push({StubEvent::Type::Started, kind_, Direction::Up, floor, Cause::None, now});
    return Cause::None;
  }
  void land(MonoTime now) noexcept { land_at(target_, now); }
  /// Ends the travel at `floor`'s level, not necessarily its target (a stop at the next floor).
  void land_at(std::size_t floor, MonoTime now) noexcept {
    current_floor_ = floor;
    events_.push({StubEvent::Type::Finished, kind_, Direction::Up, floor, Cause::None, now});
    kind_ = StubKind::None;
  }
  std::optional<std::size_t> landing_floor(const FloorTable&, const StubInput&) const noexcept {
    return target();
  }
  std::optional<std::size_t> stop(const FloorTable&, const StubInput&) noexcept {
    return busy() ? std::optional<std::size_t>(target_) : std::nullopt;
  }
  void abort(Cause cause, MonoTime now) noexcept {
    if (kind_ == StubKind::None) return;
    events_.push({StubEvent::Type::Aborted, kind_, Direction::None, current_floor_, cause, now});
    kind_ = StubKind::None;
  }
  bool poll_event(StubEvent& out) noexcept { return events_.poll(out); }
  std::uint64_t dropped_events() const noexcept { return events_.dropped(); }

  Cause refuse_ = Cause::None;
  Cause drive_refuse_ = Cause::None;  ///< the drive's own refusal (drive_forbidding)

 private:
  StubKind kind_ = StubKind::None;
  std::size_t target_ = 0;
  std::size_t current_floor_ = 0;
  TravelEventQueue<StubEvent> events_;
};

struct StubControllerEvent {
  enum class Kind : std::uint8_t { Travel, FaultRaised, FaultCleared, CallServed, CallsDropped };
  Kind kind = Kind::Travel;
  MonoTime at{};
  StubEvent travel{};
  FaultCode fault = FaultCode::LinkFault;
  std::size_t floor = 0;
  DroppedCalls dropped{};
  Cause cause = Cause::None;
};

/// What every lift's snapshot has (CarSnapshot), and the stub travel's kind and phase.
struct StubSnapshot : CarSnapshot {
  std::uint64_t steps = 0;
  StubKind travel_kind = StubKind::None;
  StubPhase phase = StubPhase::Idle;
};

using StubTravelCommand = BasicTravelCommand<StubSpeed>;
using StubBody = std::variant<StubTravelCommand, StopCommand, InspectionCommand, CallCommand,
                              InputsCommand, ShutdownCommand>;

using StubTypes =
    CoreTypes<TaggedCommand<StubBody>, CommandReply, StubControllerEvent, StubSnapshot, StubTravel,
              StubEvent, StubKind, StubTravelCommand, StubInput>;

const std::vector<std::int64_t> kLevels = {0, 3000, 6000, 9000};
constexpr MonoTime kInputsTimeout = milliseconds(500);
constexpr MonoTime kHold = milliseconds(300);

ControllerCoreConfig core_config() {
  ControllerCoreConfig c;
  c.floors_mm = kLevels;
  c.inputs_timeout = kInputsTimeout;
  c.inspection_hold = kHold;
  return c;
}

/// A controller of the stub travel: V1 has no setpoint (the drive's own gate).
class StubController : public ControllerCore<StubTypes> {
 public:
  StubController() : ControllerCore(core_config(), Cause::None) {}

  void step(MonoTime now) {
    ++steps_;
    StubInput in = input(now);
    StubTypes::Command command;
    while (next_command(command)) {
      std::visit(
          [&](const auto& body) {
            using T = std::decay_t<decltype(body)>;
            if constexpr (std::is_same_v<T, StubTravelCommand>) {
              (void)handle_travel(
                  command.tag, body, in,
                  [&]() -> std::optional<Refusal> {
                    if (body.speed == StubSpeed::V1) {
                      return Refusal{ReplyCode::BadRequest, "no V1"};
                    }
                    return std::nullopt;
                  },
                  [&] { return travel_.start_travel(body.floor, now); },
                  [](Cause cause) { return refusal_for({}, cause); });
            } else {
              handle_shared(command.tag, body, in);
            }
          },
          command.body);
      in = input(now);
    }
    locate_car(in);
    drain_travel(now);
    if (!shutting_down_) {
      if (const auto floor = next_call(in)) (void)travel_.start_travel(*floor, now);
    }
    drain_travel(now);
    set_fault(FaultCode::InputsLost, !in.inputs.valid, now);
    lift_.update(in.position_mm, Direction::None, std::nullopt);
    StubSnapshot s;
    fill_lift_snapshot(s, now, in);
    publish_snapshot(s);
  }
  void land(MonoTime now) { travel_.land(now); }
  void land_at(std::size_t floor, MonoTime now) { travel_.land_at(floor, now); }
  void abort(Cause cause, MonoTime now) { travel_.abort(cause, now); }
  void refuse_starts(Cause cause) { travel_.refuse_ = cause; }
  void drive_refuses(Cause cause) { travel_.drive_refuse_ = cause; }

  std::optional<std::int64_t> position_mm = 0;

 private:
  StubInput input(MonoTime now) const { return StubInput{now, position_mm, current_inputs(now)}; }
};

class ControllerCoreTest : public ::testing::Test {
 protected:
  CommandReply command(std::uint32_t tag, StubBody body) {
    EXPECT_TRUE(controller.post({tag, body}));
    controller.step(now);
    CommandReply r;
    EXPECT_TRUE(controller.poll_reply(r));
    EXPECT_EQ(r.tag, tag);
    return r;
  }
  std::vector<StubControllerEvent> events() {
    std::vector<StubControllerEvent> out;
    StubControllerEvent e;
    while (controller.poll_event(e)) out.push_back(e);
    return out;
  }
  void good_inputs() {
    Inputs in;
    in.safety_chain_closed = true;
    in.doors_locked = true;
    (void)command(100, InputsCommand{in});
  }

  StubController controller;
  MonoTime now = milliseconds(1000);
};

TEST_F(ControllerCoreTest, TravelCommandGatesInOrder) {
  good_inputs();
  // Floor before the drive's gate before inspection before a running travel.
  EXPECT_EQ(command(1, StubTravelCommand{9, StubSpeed::V1}).code, ReplyCode::BadRequest);
  const CommandReply speed = command(2, StubTravelCommand{2, StubSpeed::V1});
  EXPECT_EQ(speed.code, ReplyCode::BadRequest);
  EXPECT_EQ(speed.detail, "no V1");
  const CommandReply here = command(3, StubTravelCommand{0, StubSpeed::V4});
  EXPECT_EQ(here.code, ReplyCode::BadRequest);  // docs/api.md `travel`, as DCP answers it
  EXPECT_EQ(here.detail, "the car is already at that level");
  controller.refuse_starts(Cause::SafetyChainOpen);
  const CommandReply refused = command(4, StubTravelCommand{2, StubSpeed::V4});
  EXPECT_EQ(refused.code, ReplyCode::Fault);
  EXPECT_EQ(refused.detail, "safety chain open");
  controller.refuse_starts(Cause::None);
  EXPECT_EQ(command(5, StubTravelCommand{2, StubSpeed::V4}).code, ReplyCode::Ok);
  EXPECT_EQ(command(6, StubTravelCommand{3, StubSpeed::V4}).code, ReplyCode::Busy);
  EXPECT_EQ(command(7, InspectionCommand{true, Direction::Up}).code, ReplyCode::Ok);
  EXPECT_EQ(command(8, StubTravelCommand{3, StubSpeed::V4}).detail,
            "inspection or recall is switched on");
  EXPECT_EQ(command(9, ShutdownCommand{false}).code, ReplyCode::Ok);
  const CommandReply stopping = command(10, StubTravelCommand{9, StubSpeed::V1});
  EXPECT_EQ(stopping.code, ReplyCode::NotReady);
  EXPECT_EQ(stopping.detail, "the service is stopping");
  EXPECT_TRUE(controller.snapshot().shutting_down);
}

TEST_F(ControllerCoreTest, TheSnapshotSaysTheDriveAllowsATravelExactlyWhenItsStartCheckPasses) {
  // status drive.state reads drive_allows_travel: it is the travel's own drive check, so a travel
  // is refused for the drive exactly while the snapshot says the drive does not allow one.
  good_inputs();
  EXPECT_TRUE(controller.snapshot().drive_allows_travel);
  controller.drive_refuses(Cause::DriveNotReady);
  controller.step(now);
  EXPECT_FALSE(controller.snapshot().drive_allows_travel);
  const CommandReply refused = command(1, StubTravelCommand{2, StubSpeed::V4});
  EXPECT_EQ(refused.code, ReplyCode::NotReady);
  EXPECT_FALSE(controller.snapshot().drive_allows_travel);
  controller.drive_refuses(Cause::None);
  controller.step(now);
  EXPECT_TRUE(controller.snapshot().drive_allows_travel);
  EXPECT_EQ(command(2, StubTravelCommand{2, StubSpeed::V4}).code, ReplyCode::Ok);
}

TEST_F(ControllerCoreTest, CallsAreServedByTravelOrAtOnceWhenThere) {
  good_inputs();
  EXPECT_EQ(command(1, CallCommand::adding(0)).code, ReplyCode::Ok);  // the car is at floor 0
  EXPECT_EQ(command(2, CallCommand::adding(2)).code, ReplyCode::Ok);
  EXPECT_EQ(command(3, CallCommand::adding(7)).code, ReplyCode::BadRequest);
  EXPECT_EQ(command(4, CallCommand::cancelling(3)).code, ReplyCode::BadRequest);
  std::vector<StubControllerEvent> ev = events();
  ASSERT_FALSE(ev.empty());
  bool served_here = false;
  for (const auto& e : ev) {
    served_here = served_here || (e.kind == StubControllerEvent::Kind::CallServed && e.floor == 0);
  }
  EXPECT_TRUE(served_here);
  // travel.call_stop_ms: the car stands at the call it served (the doors' time to open), then
  // sets off to the next.
  EXPECT_EQ(controller.snapshot().travel_kind, StubKind::None);
  now += milliseconds(defaults::kCallStopMs);
  controller.step(now);
  (void)events();  // the travel's start
  const StubSnapshot moving = controller.snapshot();
  EXPECT_EQ(moving.travel_kind, StubKind::Travel);
  EXPECT_EQ(moving.target_floor, 2U);
  ASSERT_EQ(moving.call_count, 1U);
  EXPECT_EQ(moving.calls[0], 2U);

  controller.land(now);
  controller.step(now);
  ev = events();
  ASSERT_EQ(ev.size(), 2U);
  EXPECT_EQ(ev[0].kind, StubControllerEvent::Kind::Travel);
  EXPECT_EQ(ev[0].travel.type, StubEvent::Type::Finished);
  EXPECT_EQ(ev[1].kind, StubControllerEvent::Kind::CallServed);
  EXPECT_EQ(ev[1].floor, 2U);
  EXPECT_EQ(controller.snapshot().call_count, 0U);
}

// docs/api.md `calls`: a car that comes to rest at a queued floor serves it there, first in the
// queue or not (issue #44: a car stopping at a floor that was queued sent no call_served, and the
// dispatcher reassigned a call already reached).
TEST_F(ControllerCoreTest, ATravelEndingAtAFloorQueuedLaterServesThatCall) {
  good_inputs();
  ASSERT_EQ(command(1, CallCommand::adding(3)).code, ReplyCode::Ok);
  ASSERT_EQ(command(2, CallCommand::adding(1)).code, ReplyCode::Ok);
  controller.step(now);
  (void)events();  // the travel to 3 starts
  ASSERT_EQ(controller.snapshot().target_floor, 3U);
  controller.land_at(1, now);  // it ends at floor 1 instead (a stop at the next floor it could)
  controller.step(now);
  const std::vector<StubControllerEvent> ev = events();
  ASSERT_EQ(ev.size(), 2U);
  EXPECT_EQ(ev[0].kind, StubControllerEvent::Kind::Travel);
  EXPECT_EQ(ev[1].kind, StubControllerEvent::Kind::CallServed);
  EXPECT_EQ(ev[1].floor, 1U);
  const StubSnapshot after = controller.snapshot();
  ASSERT_EQ(after.call_count, 1U);  // floor 3 stays queued, the car goes there next
  EXPECT_EQ(after.calls[0], 3U);
}

TEST_F(ControllerCoreTest, InputsGoStaleAndInspectionButtonsAreHeld) {
  controller.step(now);
  EXPECT_FALSE(controller.snapshot().inputs.valid);
  good_inputs();
  EXPECT_TRUE(controller.snapshot().inputs.valid);
  (void)command(1, InspectionCommand{true, Direction::Down});
  StubSnapshot s = controller.snapshot();
  EXPECT_TRUE(s.inputs.inspection);
  EXPECT_TRUE(s.inputs.button_down);
  EXPECT_FALSE(s.inputs.button_up);
  now += kHold + milliseconds(1);
  controller.step(now);
  s = controller.snapshot();
  EXPECT_TRUE(s.inputs.inspection);  // on until switched off; the button is released
  EXPECT_FALSE(s.inputs.button_down);
  now += kInputsTimeout;
  controller.step(now);
  EXPECT_FALSE(controller.snapshot().inputs.valid);
}

TEST_F(ControllerCoreTest, AFaultIsReportedOnceWhenItStartsAndOnceWhenItEnds) {
  controller.step(now);
  controller.step(now);
  std::vector<StubControllerEvent> ev = events();
  ASSERT_EQ(ev.size(), 1U);
  EXPECT_EQ(ev[0].kind, StubControllerEvent::Kind::FaultRaised);
  EXPECT_EQ(ev[0].fault, FaultCode::InputsLost);
  const auto i = static_cast<std::size_t>(FaultCode::InputsLost);
  EXPECT_TRUE(controller.snapshot().faults[i]);
  EXPECT_EQ(controller.snapshot().fault_since[i], now);
  good_inputs();
  ev = events();
  ASSERT_EQ(ev.size(), 1U);
  EXPECT_EQ(ev[0].kind, StubControllerEvent::Kind::FaultCleared);
}

TEST(TravelHelpers, DistanceAheadAndTerminalLevels) {
  EXPECT_EQ(distance_ahead(1000, 3000, Direction::Up), 2000);
  EXPECT_EQ(distance_ahead(1000, 3000, Direction::Down), -2000);
  FloorTable floors;
  ASSERT_TRUE(floors.assign(kLevels));
  EXPECT_TRUE(at_terminal_level(floors, Direction::Up, 9000));
  EXPECT_FALSE(at_terminal_level(floors, Direction::Up, 8999));
  EXPECT_TRUE(at_terminal_level(floors, Direction::Down, -1));
  EXPECT_FALSE(at_terminal_level(floors, Direction::None, 9000));
  EXPECT_FALSE(at_terminal_level(FloorTable{}, Direction::Up, 0));
}

TEST(TravelHelpers, MachineNeedsAndRefusalCauses) {
  const MachineNeeds travel = run_needs(StubKind::Travel, true, true);
  EXPECT_TRUE(travel.doors_locked);
  EXPECT_FALSE(travel.door_bridge_allowed);
  EXPECT_TRUE(travel.position);
  const MachineNeeds relevel = run_needs(StubKind::Relevel, true, false);
  EXPECT_TRUE(relevel.door_bridge_allowed);
  EXPECT_FALSE(relevel.position);
  const MachineNeeds inspection = run_needs(StubKind::Inspection, true, true);
  EXPECT_FALSE(inspection.doors_locked);
  EXPECT_FALSE(inspection.position);
  EXPECT_EQ(refusal_cause(MachineRefusal::SafetyChainOpen), Cause::SafetyChainOpen);
  EXPECT_EQ(refusal_cause(MachineRefusal::DoorsNotLocked), Cause::DoorsNotLocked);
  EXPECT_EQ(refusal_cause(MachineRefusal::None), Cause::None);
  EXPECT_EQ(shared_cause_code(Cause::InputsLost), ReplyCode::Fault);
  EXPECT_EQ(shared_cause_code(Cause::DoorsNotLocked), ReplyCode::NotReady);
  EXPECT_EQ(shared_cause_text(Cause::DriveNotReady), "not possible now");
  // A kind's own table wins over the shared answer; a cause it does not name keeps the shared.
  const CauseRefusal own[] = {{Cause::DriveNotReady, ReplyCode::NotReady, "RDY = 0"},
                              {Cause::InputsLost, ReplyCode::NotReady, "own inputs text"}};
  EXPECT_EQ(refusal_for(own, Cause::DriveNotReady).detail, "RDY = 0");
  EXPECT_EQ(refusal_for(own, Cause::InputsLost).code, ReplyCode::NotReady);
  EXPECT_EQ(refusal_for(own, Cause::SafetyChainOpen).code, ReplyCode::Fault);
  EXPECT_EQ(refusal_for(own, Cause::SafetyChainOpen).detail, "safety chain open");
}

TEST_F(ControllerCoreTest, ATravelThatEndsEarlyEmptiesTheCallsQueue) {
  // docs/api.md `calls`: a travel that ends early empties the queue, whoever dispatches the lift
  // decides again: the car must not set off by itself, once the fault cleared, to a call the
  // dispatcher may have given to another car.
  good_inputs();
  EXPECT_EQ(command(1, CallCommand::adding(2)).code, ReplyCode::Ok);
  EXPECT_EQ(command(2, CallCommand::adding(3)).code, ReplyCode::Ok);
  ASSERT_EQ(controller.snapshot().travel_kind, StubKind::Travel);
  controller.abort(Cause::SafetyChainOpen, now);
  controller.step(now);
  const StubSnapshot after = controller.snapshot();
  EXPECT_EQ(after.call_count, 0U);
  EXPECT_EQ(after.travel_kind, StubKind::None);
  controller.step(now);
  EXPECT_EQ(controller.snapshot().travel_kind, StubKind::None) << "a call was served anyway";
}

TEST_F(ControllerCoreTest, WhatEmptiesTheQueueIsNamedOnceAndCancellingTheTargetTooLateIsSaid) {
  // docs/api.md `calls_dropped`: the floors and the cause, once; `calls` cancel of the floor the
  // travel runs to when it can no longer stop before it (the stub lands at its target): busy,
  // and the queue stays as it was.
  good_inputs();
  EXPECT_EQ(command(1, CallCommand::adding(2)).code, ReplyCode::Ok);
  EXPECT_EQ(command(2, CallCommand::adding(3)).code, ReplyCode::Ok);
  ASSERT_EQ(controller.snapshot().travel_kind, StubKind::Travel);
  EXPECT_EQ(controller.snapshot().next_possible_stop, std::optional<std::size_t>(2));
  const CommandReply late = command(3, CallCommand::cancelling(2));
  EXPECT_EQ(late.code, ReplyCode::Busy);
  EXPECT_EQ(late.detail, kTooLateToCancel);
  EXPECT_EQ(controller.snapshot().call_count, 2U);
  (void)events();
  controller.abort(Cause::SafetyChainOpen, now);
  controller.step(now);
  controller.step(now);
  std::vector<StubControllerEvent> dropped;
  for (const StubControllerEvent& e : events()) {
    if (e.kind == StubControllerEvent::Kind::CallsDropped) dropped.push_back(e);
  }
  ASSERT_EQ(dropped.size(), 1U);
  EXPECT_EQ(dropped[0].cause, Cause::SafetyChainOpen);
  EXPECT_TRUE(dropped[0].dropped.floors.test(2));
  EXPECT_TRUE(dropped[0].dropped.floors.test(3));
  EXPECT_EQ(dropped[0].dropped.floors.count(), 2U);
}

}  // namespace
}  // namespace liftd::lift
