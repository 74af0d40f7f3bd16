// Fast start, fast stop, start supervision, start checks and the channel request body.
#include <gtest/gtest.h>

#include <functional>

#include "fake_drive.hpp"
#include "sequence_requests.hpp"

namespace liftd::travel::test {
namespace {

TEST(FastStart, Dcp4HoldThenGoWhenDoorsLocked) {
  Rig rig(Protocol::Dcp4);
  rig.input.inputs.doors_locked = false;
  rig.input.inputs.doors_closed = false;
  rig.cycle();
  TravelRequest request = dcp4_request(8000);
  request.fast_start = true;
  request.load_percent = 40;  // DCP 5.12.8: never sent with fast start
  ASSERT_EQ(rig.controller.start(request), StartResult::Accepted);
  for (int i = 0; i < 30; ++i) rig.cycle();
  EXPECT_TRUE(rig.drive.status().brake_open);  // car held with open brake
  EXPECT_NEAR(rig.drive.position_mm(), 0.0, 0.01);
  rig.input.inputs.doors_closed = true;
  rig.input.inputs.doors_locked = true;
  ASSERT_TRUE(rig.run_to_idle());
  // I7, VF speed message (B3+B0), hold with remaining distance 0, go (1101 + V4), distance.
  EXPECT_EQ(rig.command_runs(1),
            (std::vector<std::uint8_t>{0x00, 0x09, 0x05, 0x0D, 0x05, 0x01, 0x00}));
  const std::size_t vf_at = rig.first(0x09);
  EXPECT_EQ(rig.records[vf_at].data_word, 0x0004);
  EXPECT_EQ(rig.records[rig.first(0x05)].data_word, 0x0000);  // DCP 12.1.2
  EXPECT_EQ(rig.records[rig.first(0x0D)].data_word, 0x0080);
  for (const auto& r : rig.records) {
    if (r.channel_request) {
      EXPECT_NE(r.channel_request->kind, ChannelRequest::Kind::Load);
    }
  }
  EXPECT_NEAR(rig.drive.position_mm(), 8000.0, 1.0);
  EXPECT_EQ(rig.event_types(),
            (std::vector<Type>{Type::FastStartArmed, Type::Started, Type::Finished}));
}

TEST(FastStart, Dcp3HoldIsTheVfSpeedMessageThenGoWith1111) {
  Rig rig(Protocol::Dcp3, dcp3_shaft());
  rig.input.inputs.doors_locked = false;
  rig.cycle();
  TravelRequest request = dcp3_request(Speed::V3, Direction::Up);
  request.fast_start = true;
  ASSERT_EQ(rig.controller.start(request), StartResult::Accepted);
  for (int i = 0; i < 20; ++i) rig.cycle();
  rig.input.inputs.doors_locked = true;
  for (int i = 0; i < 5; ++i) rig.cycle();
  EXPECT_EQ(rig.command_runs(1), (std::vector<std::uint8_t>{0x09, 0x0F, 0x07}));
  EXPECT_EQ(rig.records[rig.first(0x09)].data_word, 0x0004);
  EXPECT_EQ(rig.records[rig.first(0x0F)].data_word, 0x0040);
}

TEST(FastStart, DoorReversalAbortsControlledAndWaitsForS6) {
  TravelConfig config;
  config.use_i7 = false;
  Rig rig(Protocol::Dcp4, config);
  rig.input.inputs.doors_locked = false;
  rig.cycle();
  TravelRequest request = dcp4_request(8000);
  request.fast_start = true;
  ASSERT_EQ(rig.controller.start(request), StartResult::Accepted);
  for (int i = 0; i < 20; ++i) rig.cycle();
  ASSERT_TRUE(rig.drive.status().brake_open);
  rig.input.inputs.door_reversal = true;
  ASSERT_TRUE(rig.run_to_idle());
  // DCP 12.2.2: stop message (B2 = 0, B1 = 0, B0 = 1) until S6 and S1 are 0, then idle.
  EXPECT_EQ(rig.command_runs(1), (std::vector<std::uint8_t>{0x09, 0x05, 0x01, 0x00}));
  const std::size_t idle_at = rig.first(0x00, rig.first(0x01));
  EXPECT_FALSE(rig.records[idle_at].status.brake_open);
  ASSERT_FALSE(rig.events.empty());
  EXPECT_EQ(rig.events.back().type, Type::Aborted);
  EXPECT_EQ(rig.events.back().cause, lift::Cause::DoorReversal);
}

TEST(FastStart, TimeoutAbortsControlled) {
  TravelConfig config = dcp3_shaft();
  config.use_i7 = false;
  config.fast_start_timeout_ms = 1500;
  Rig rig(Protocol::Dcp3, config);
  rig.input.inputs.doors_locked = false;
  rig.cycle();
  TravelRequest request = dcp3_request(Speed::V4, Direction::Up);
  request.fast_start = true;
  ASSERT_EQ(rig.controller.start(request), StartResult::Accepted);
  ASSERT_TRUE(rig.run_to_idle());
  EXPECT_EQ(rig.command_runs(1), (std::vector<std::uint8_t>{0x09, 0x01, 0x00}));
  // 1500 ms = 100 cycles of VF hold.
  EXPECT_EQ(rig.count(0x09), 100U);
  EXPECT_EQ(rig.events.back().cause, lift::Cause::FastStartTimeout);
}

TEST(FastStop, Dcp4SendsSpeedAfterFastStartWithVf) {
  TravelConfig config;
  config.use_i7 = false;
  Rig rig(Protocol::Dcp4, config);
  rig.cycle();
  ASSERT_EQ(rig.controller.start(dcp4_request(20000)), StartResult::Accepted);
  ASSERT_TRUE(rig.run_until([&] { return rig.drive.speed_mm_s() >= 1600; }));
  rig.controller.fast_stop();
  ASSERT_TRUE(rig.run_to_idle());
  EXPECT_EQ(rig.command_runs(1), (std::vector<std::uint8_t>{0x09, 0x05, 0x0D, 0x01, 0x00}));
  EXPECT_EQ(rig.records[rig.first(0x0D)].data_word, 0x0004);  // DCP 13.1
  EXPECT_LT(rig.drive.position_mm(), 20000.0 - 500.0);
  EXPECT_EQ(rig.events.back().cause, lift::Cause::StopRequested);
}

TEST(FastStop, Dcp3SendsSpeedAfterFastStartWithVf) {
  Rig rig(Protocol::Dcp3, dcp3_shaft());
  rig.cycle();
  ASSERT_EQ(rig.controller.start(dcp3_request(Speed::V4, Direction::Down)), StartResult::Accepted);
  ASSERT_TRUE(rig.run_until([&] { return rig.drive.speed_mm_s() >= 1000; }));
  rig.controller.fast_stop();
  ASSERT_TRUE(rig.run_to_idle());
  EXPECT_EQ(rig.command_runs(1), (std::vector<std::uint8_t>{0x19, 0x17, 0x1F, 0x11, 0x00}));
  EXPECT_EQ(rig.records[rig.first(0x1F)].data_word, 0x0004);
}

TEST(Supervision, DriveThatNeverOpensTheBrakeIsStoppedAfterStartTimeout) {
  TravelConfig config;
  config.use_i7 = false;
  config.start_timeout_ms = 600;
  FakeDriveConfig drive_config;
  drive_config.preflux_cycles = 100000;  // never opens the brake
  Rig rig(Protocol::Dcp4, config, drive_config);
  rig.cycle();
  ASSERT_EQ(rig.controller.start(dcp4_request(5000)), StartResult::Accepted);
  ASSERT_TRUE(rig.run_until([&] { return rig.records.back().command == 0x01; }));
  EXPECT_EQ(rig.count(0x05), 40U);  // 600 ms of B2 + B0
  ASSERT_TRUE(rig.run_to_idle());
  EXPECT_EQ(rig.events.back().cause, lift::Cause::DriveDidNotStart);
}

TEST(StartChecks, RequestsThatCannotRunAreRefused) {
  // Legend: protocol, request, expected result.
  struct Case {
    Protocol protocol;
    TravelRequest request;
    StartResult expected;
  };
  TravelRequest vn_distance = dcp4_request(3000, Speed::VN);
  TravelRequest here = dcp4_request(2);
  // The car stands at 0: a DCP3 travel to a floor (no direction given) at that level is
  // refused as the DCP4 one is, whatever the dialect ("the car is already at that level").
  const std::vector<Case> cases = {
      {Protocol::Dcp3, dcp4_request(3000), StartResult::WrongProtocol},
      {Protocol::ComChan, dcp3_request(Speed::V4, Direction::Up), StartResult::WrongProtocol},
      {Protocol::Dcp4, vn_distance, StartResult::BadSpeed},
      {Protocol::Dcp4, here, StartResult::AlreadyThere},
      {Protocol::Dcp3, dcp3_request(Speed::V0, Direction::None, 2), StartResult::AlreadyThere},
      {Protocol::Dcp3, dcp3_request(Speed::V4, Direction::None, 0), StartResult::AlreadyThere},
      {Protocol::Dcp4, dcp3_request(Speed::V4, Direction::None, -2), StartResult::AlreadyThere},
      {Protocol::Dcp3, dcp3_request(Speed::V4, Direction::Down, 0), StartResult::Accepted},
  };
  for (const auto& c : cases) {
    Rig rig(c.protocol);
    rig.with_position = true;  // DCP3 by position, as the daemon's default lift
    rig.cycle();
    EXPECT_EQ(rig.controller.start(c.request), c.expected);
  }
  Rig rig(Protocol::Dcp4);
  rig.with_position = false;
  rig.cycle();
  EXPECT_EQ(rig.controller.start(dcp4_request(3000)), StartResult::NoPosition);
  // Without a position only the request can give the direction.
  Rig unplaced(Protocol::Dcp3);
  unplaced.with_position = false;
  unplaced.cycle();
  EXPECT_EQ(unplaced.controller.start(dcp3_request(Speed::V0, Direction::None)),
            StartResult::NoDirection);
  Rig busy(Protocol::Dcp4);
  busy.cycle();
  EXPECT_EQ(busy.controller.start(dcp4_request(3000)), StartResult::Accepted);
  EXPECT_EQ(busy.controller.start(dcp4_request(6000)), StartResult::Busy);
}

// A travel start() accepted that is still queued (held until the I9 of the last stop reached the
// drive, DCP 5.12.9) ends with one Aborted event naming what ended it, whatever ends it: a client
// told "ok" waits for the travel's end and must get it.
TEST(QueuedTravel, EndsWithAnAbortedEventWhateverEndsItBeforeItBegins) {
  // Legend: what ends the queued travel, the cause its event names.
  struct Case {
    const char* name;
    std::function<void(Rig&)> end;
    lift::Cause cause;
  };
  const std::vector<Case> cases = {
      {"stop", [](Rig& r) { r.controller.stop(); }, lift::Cause::StopRequested},
      {"fast stop", [](Rig& r) { r.controller.fast_stop(); }, lift::Cause::StopRequested},
      {"stop at a level", [](Rig& r) { (void)r.controller.stop_at(3000); },
       lift::Cause::StopRequested},
      {"service stop", [](Rig& r) { r.controller.shut_down(false); }, lift::Cause::ShuttingDown},
      {"forced service stop", [](Rig& r) { r.controller.shut_down(true); },
       lift::Cause::ShuttingDown},
      {"inspection switched on", [](Rig& r) { r.input.inputs.inspection = true; },
       lift::Cause::ModeChanged},
      {"recall switched on", [](Rig& r) { r.input.inputs.recall = true; },
       lift::Cause::ModeChanged},
      {"drive fault (S3)", [](Rig& r) { r.drive.status().general_fault = true; },
       lift::Cause::DriveFault},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    Rig rig(Protocol::Dcp4);
    rig.cycle();
    rig.controller.hold_start(true);
    ASSERT_EQ(rig.controller.start(dcp4_request(9000)), StartResult::Accepted);
    rig.cycle();
    ASSERT_TRUE(rig.controller.travel_queued());
    c.end(rig);
    rig.cycle();
    rig.cycle();
    EXPECT_FALSE(rig.controller.travel_queued());
    std::vector<Event> ends;
    for (const Event& e : rig.events) {
      if (e.type == Type::Aborted || e.type == Type::Finished || e.type == Type::Started) {
        ends.push_back(e);
      }
    }
    ASSERT_EQ(ends.size(), 1U);
    EXPECT_EQ(ends[0].type, Type::Aborted);
    EXPECT_EQ(ends[0].cause, c.cause);
    EXPECT_EQ(ends[0].kind, TravelKind::Dcp4Distance);
    EXPECT_EQ(ends[0].target_mm, 9000);
    // Released, nothing begins: the dropped travel is gone.
    rig.controller.hold_start(false);
    rig.cycle();
    EXPECT_EQ(rig.controller.active_kind(), TravelKind::None);
  }
}

TEST(ChannelRequestBody, MatchesTheSpecsTextLayout) {
  // Legend: request -> body between 0x1C and ETX (DCP 5.12.7 .. 5.12.9).
  ChannelRequest i7;
  i7.vmax = Speed::V4;
  i7.desired_distance_cm = 300;
  EXPECT_EQ(body_text(i7), "I7200300");  // DCP 11.1.2.1 example 1
  i7.vmax = Speed::V3;
  i7.desired_distance_cm = 123456;  // clamps to 5 digits
  EXPECT_EQ(body_text(i7), "I7199999");
  ChannelRequest i8;
  i8.kind = ChannelRequest::Kind::Load;
  i8.load_percent = 100;
  EXPECT_EQ(body_text(i8), "I8100");
  ChannelRequest i9;
  i9.kind = ChannelRequest::Kind::Position;
  i9.position_mm = 12345;
  EXPECT_EQ(body_text(i9), "I9+012345");
  i9.position_mm = -20;
  EXPECT_EQ(body_text(i9), "I9-000020");
  i9.position_mm.reset();
  EXPECT_EQ(body_text(i9), "I9E000000");
}

}  // namespace
}  // namespace liftd::travel::test
