// DCP3 travels (DCP 10), inspection travels and relevelling against the scripted drive.
#include <gtest/gtest.h>

#include "fake_drive.hpp"
#include "sequence_requests.hpp"

namespace liftd::travel::test {
namespace {

TEST(Dcp3Travel, V4TravelWithShaftSignalsFollowsFigure10_1) {
  Rig rig(Protocol::Dcp3, dcp3_shaft());
  rig.cycle();
  ASSERT_EQ(rig.controller.start(dcp3_request(Speed::V4, Direction::Up)), StartResult::Accepted);
  ASSERT_TRUE(rig.run_until([&] { return rig.drive.speed_mm_s() >= 1600.0; }));
  rig.input.inputs.decel_up[3] = true;  // the SV4 magnet of the target floor, travelling up
  ASSERT_TRUE(rig.run_until([&] { return rig.drive.speed_mm_s() <= 60.0; }));
  rig.cycle();
  rig.input.inputs.level_zone = true;
  ASSERT_TRUE(rig.run_to_idle());
  // 1: speed V4, 2: B1 (+B2, DCP 8.2 (2b)), 3: B1 off at SV4, 4: B2 positions, 5: B0 until S1=0.
  EXPECT_EQ(rig.command_runs(1), (std::vector<std::uint8_t>{0x09, 0x07, 0x05, 0x01, 0x00}));
  EXPECT_EQ(rig.records[rig.first(0x09)].data_word, 0x0080);
  const std::size_t idle_at = rig.first(0x00, rig.first(0x01));
  EXPECT_FALSE(rig.records[idle_at].status.travel_active);
  EXPECT_TRUE(rig.records[idle_at - 1].status.travel_active);
  EXPECT_FALSE(rig.records[idle_at].channel_request.has_value());  // no I9 in DCP3
  EXPECT_EQ(rig.event_types(), (std::vector<Type>{Type::Started, Type::Finished}));
}

TEST(Dcp3Travel, AV4TravelUpSlowsOnlyAtTheV4UpPoint) {
  // DCP 10.1.1 step 3: B1 goes off at the fixed deceleration point SVx of the travel's own speed.
  // Every other speed's point and the V4 point for travelling down pass by without effect.
  Rig rig(Protocol::Dcp3, dcp3_shaft());
  rig.cycle();
  ASSERT_EQ(rig.controller.start(dcp3_request(Speed::V4, Direction::Up)), StartResult::Accepted);
  ASSERT_TRUE(rig.run_until([&] { return rig.drive.speed_mm_s() >= 1600.0; }));
  for (std::size_t n = 0; n < 7; ++n) {
    rig.input.inputs.decel_down[n] = true;
    if (n != 3) rig.input.inputs.decel_up[n] = true;
  }
  for (int i = 0; i < 20; ++i) rig.cycle();
  EXPECT_EQ(rig.records.back().command, 0x07) << "B1 must stay on past other speeds' points";
  EXPECT_GE(rig.drive.speed_mm_s(), 1600.0);
  rig.input.inputs.decel_up[3] = true;
  rig.cycle();
  EXPECT_EQ(rig.records.back().command, 0x05) << "B1 off at the V4-up point";
}

TEST(Dcp3Travel, IntermediateSpeedByPositionClearsB1AtSvx) {
  TravelConfig config = dcp3_shaft();
  config.dcp3_reference = Dcp3Reference::Position;
  config.dcp3_decel_distance_mm[speed_index(Speed::V2)] = 600;  // SV2
  config.dcp3_speed_count = 3;                                  // V4, V3, V2 (DCP 3.5.3.7)
  Rig rig(Protocol::Dcp3, config);
  rig.with_position = true;
  rig.drive.set_position_mm(10000);
  rig.cycle();
  ASSERT_EQ(rig.controller.start(dcp3_request(Speed::V2, Direction::None, 6000)),
            StartResult::Accepted);
  ASSERT_TRUE(rig.run_to_idle());
  EXPECT_EQ(rig.command_runs(1), (std::vector<std::uint8_t>{0x19, 0x17, 0x15, 0x11, 0x00}));
  EXPECT_EQ(rig.records[rig.first(0x19)].data_word, 0x0020);  // V2 = G5
  const std::size_t creep_at = rig.first(0x15);
  EXPECT_LE(rig.records[creep_at].position_mm - 6000, 600);
  EXPECT_GT(rig.records[creep_at - 1].position_mm - 6000, 600);
  EXPECT_NEAR(rig.drive.position_mm(), 6000.0, 10.0);
}

TEST(Dcp3Travel, SpeedsOutsideTheInstallationsCountAreRefused) {
  // Legend: speed count, speed, accepted? (DCP 3.5.3.7 table)
  struct Case {
    int count;
    Speed speed;
    bool accepted;
  };
  const std::vector<Case> cases = {
      {1, Speed::V4, true},  {1, Speed::V3, false}, {2, Speed::V3, true},  {3, Speed::V1, false},
      {4, Speed::V1, true},  {5, Speed::V7, true},  {5, Speed::V6, false}, {7, Speed::V5, true},
      {7, Speed::VI, false}, {7, Speed::VF, false},
  };
  for (const auto& c : cases) {
    TravelConfig config = dcp3_shaft();
    config.dcp3_speed_count = c.count;
    Rig rig(Protocol::Dcp3, config);
    rig.cycle();
    const auto result = rig.controller.start(dcp3_request(c.speed, Direction::Up));
    EXPECT_EQ(result == StartResult::Accepted, c.accepted)
        << c.count << " " << dcp::to_string(c.speed);
  }
}

TEST(Dcp3Travel, CrawlTravelFollowsFigure10_3) {
  Rig rig(Protocol::Dcp3, dcp3_shaft());
  rig.cycle();
  ASSERT_EQ(rig.controller.start(dcp3_request(Speed::V0, Direction::Down)), StartResult::Accepted);
  for (int i = 0; i < 40; ++i) rig.cycle();
  rig.input.inputs.level_zone = true;
  ASSERT_TRUE(rig.run_to_idle());
  // 1: speed V0, 2: B1+B2, 3: both withdrawn, 4: B0 until S6 = 0 and S1 = 0.
  EXPECT_EQ(rig.command_runs(1), (std::vector<std::uint8_t>{0x19, 0x17, 0x11, 0x00}));
  EXPECT_EQ(rig.records[rig.first(0x19)].data_word, 0x0001);
  const std::size_t idle_at = rig.first(0x00, rig.first(0x11));
  EXPECT_FALSE(rig.records[idle_at].status.brake_open);
  EXPECT_FALSE(rig.records[idle_at].status.travel_active);
}

TEST(Dcp3Travel, CrawlWithoutLevelSignalStopsAfterCrawlTimeout) {
  TravelConfig config = dcp3_shaft();
  config.crawl_timeout_ms = 1500;
  Rig rig(Protocol::Dcp3, config);
  rig.cycle();
  ASSERT_EQ(rig.controller.start(dcp3_request(Speed::V0, Direction::Down)), StartResult::Accepted);
  ASSERT_TRUE(rig.run_to_idle());
  EXPECT_EQ(rig.command_runs(1), (std::vector<std::uint8_t>{0x19, 0x17, 0x11, 0x00}));
  EXPECT_EQ(rig.count(0x17), 100U);  // 1500 ms of B1 + B2
  EXPECT_EQ(rig.events.back().cause, lift::Cause::LevelNotReached);
}

TEST(Dcp3Travel, Dcp4DriveRunsDcp3TravelWithV4Only) {
  Rig rig(Protocol::Dcp4);
  rig.cycle();
  EXPECT_EQ(rig.controller.start(dcp3_request(Speed::V2, Direction::Up)), StartResult::BadSpeed);
  EXPECT_EQ(rig.controller.start(dcp3_request(Speed::V3, Direction::Up)), StartResult::Accepted);
}

TEST(Inspection, ViTravelCrawlAtEndZoneAndB0OffOnRelease) {
  Rig rig(Protocol::Dcp4);
  rig.input.inputs.inspection = true;
  for (int i = 0; i < 3; ++i) rig.cycle();  // stationary: B0 off
  rig.input.inputs.button_up = true;
  ASSERT_TRUE(rig.run_until([&] { return rig.drive.speed_mm_s() >= 300.0; }));
  rig.input.inputs.end_zone_top = true;
  for (int i = 0; i < 10; ++i) rig.cycle();
  rig.input.inputs.button_up = false;
  rig.cycle();
  const std::size_t released_at = rig.records.size() - 1;
  EXPECT_EQ(rig.records[released_at].command, 0x00);  // the same cycle (DCP 9.2.1.1 step 4)
  ASSERT_TRUE(rig.run_to_idle());
  EXPECT_EQ(rig.command_runs(), (std::vector<std::uint8_t>{0x00, 0x09, 0x07, 0x05, 0x00}));
  EXPECT_EQ(rig.records[rig.first(0x09)].data_word, 0x0010);  // VI = G4
  EXPECT_EQ(rig.event_types(), (std::vector<Type>{Type::Started, Type::Finished}));
  EXPECT_EQ(rig.events.back().kind, TravelKind::Inspection);
  // The I9 after the stop (DCP 5.12.9, also for VI travels) is the DCP controller's.
}

TEST(Inspection, FromInsideEndZoneStartsWithB2OnlyAfterViMessage) {
  Rig rig(Protocol::Dcp3, dcp3_shaft());
  rig.input.inputs.recall = true;
  rig.input.inputs.end_zone_bottom = true;
  rig.input.inputs.button_down = true;
  for (int i = 0; i < 20; ++i) rig.cycle();
  // DCP 9.2.1.2: VI speed message, then B2 only (crawl V0), direction down.
  EXPECT_EQ(rig.command_runs(), (std::vector<std::uint8_t>{0x19, 0x15}));
  EXPECT_EQ(rig.records[0].data_word, 0x0010);
  EXPECT_EQ(rig.controller.active_kind(), TravelKind::Recall);
  EXPECT_NEAR(rig.drive.speed_mm_s(), 60.0, 0.1);
}

TEST(Inspection, BothButtonsOrDirectionChangeDropB0) {
  Rig rig(Protocol::Dcp3, dcp3_shaft());
  rig.input.inputs.inspection = true;
  rig.input.inputs.button_up = true;
  for (int i = 0; i < 10; ++i) rig.cycle();
  EXPECT_EQ(rig.records.back().command, 0x07);
  rig.input.inputs.button_down = true;
  rig.cycle();
  EXPECT_EQ(rig.records.back().command, 0x00);
  rig.input.inputs.button_up = false;  // down only, but the drive still reports S1
  rig.cycle();
  EXPECT_EQ(rig.records.back().command, 0x00);
  ASSERT_TRUE(rig.run_until([&] { return rig.records.back().command == 0x19; }));
  EXPECT_FALSE(rig.records.back().status.travel_active);
}

TEST(Inspection, StartRequestsAreRefusedInInspectionMode) {
  Rig rig(Protocol::Dcp4);
  rig.input.inputs.inspection = true;
  rig.cycle();
  EXPECT_EQ(rig.controller.start(dcp4_request(3000)), StartResult::InspectionMode);
}

TEST(Inspection, SwitchingToInspectionEndsANormalTravelAtOnce) {
  TravelConfig config;
  config.use_i7 = false;
  Rig rig(Protocol::Dcp4, config);
  rig.cycle();
  ASSERT_EQ(rig.controller.start(dcp4_request(10000)), StartResult::Accepted);
  ASSERT_TRUE(rig.run_until([&] { return rig.drive.speed_mm_s() > 500; }));
  rig.input.inputs.inspection = true;
  rig.cycle();
  EXPECT_EQ(rig.records.back().command, 0x00);
  ASSERT_FALSE(rig.events.empty());
  EXPECT_EQ(rig.events.back().cause, lift::Cause::ModeChanged);
}

TravelRequest relevel_request(Direction direction) {
  TravelRequest request;
  request.kind = TravelKind::Relevel;
  request.direction = direction;
  return request;
}

TEST(Relevel, WithElectricStopFollowsFigure9_6) {
  Rig rig(Protocol::Dcp3, dcp3_shaft());
  rig.cycle();
  ASSERT_EQ(rig.controller.start(relevel_request(Direction::Up)), StartResult::Accepted);
  for (int i = 0; i < 30; ++i) rig.cycle();
  rig.input.inputs.level_zone = true;
  ASSERT_TRUE(rig.run_to_idle());
  // 1: speed VN, 2: B1 without B2, 3: B1 off, B0 held, 4: B0 off after S6 = 0 and S1 = 0.
  EXPECT_EQ(rig.command_runs(1), (std::vector<std::uint8_t>{0x09, 0x03, 0x01, 0x00}));
  EXPECT_EQ(rig.records[rig.first(0x09)].data_word, 0x0002);
  const std::size_t idle_at = rig.first(0x00, rig.first(0x01));
  EXPECT_FALSE(rig.records[idle_at].status.brake_open);
  EXPECT_FALSE(rig.records[idle_at].status.travel_active);
}

TEST(Relevel, StartsByItselfOnTheShaftsRelevelSignalWithoutPosition) {
  // Without a position the relevelling zones give the direction; the travel ends where the car is
  // in the level zone and the signal that asked for it has dropped.
  Rig rig(Protocol::Dcp3, dcp3_shaft());
  rig.cycle();
  rig.input.inputs.relevel_down = true;
  for (int i = 0; i < 3; ++i) rig.cycle();
  ASSERT_EQ(rig.controller.active_kind(), TravelKind::Relevel);
  EXPECT_EQ(rig.controller.direction(), Direction::Down);
  for (int i = 0; i < 30; ++i) rig.cycle();
  rig.input.inputs.level_zone = true;  // still beyond the tolerance: the travel goes on
  for (int i = 0; i < 5; ++i) rig.cycle();
  EXPECT_EQ(rig.controller.active_kind(), TravelKind::Relevel);
  rig.input.inputs.relevel_down = false;
  ASSERT_TRUE(rig.run_to_idle());
  // Figure 9.6 downwards: speed VN, B1 without B2, B1 off with B0 held, B0 off.
  EXPECT_EQ(rig.command_runs(rig.first(0x19)), (std::vector<std::uint8_t>{0x19, 0x13, 0x11, 0x00}));
  EXPECT_EQ(rig.event_types(), (std::vector<Type>{Type::Started, Type::Finished}));
  // Both zones at once contradict each other: nothing moves.
  rig.records.clear();
  rig.input.inputs.relevel_up = true;
  rig.input.inputs.relevel_down = true;
  for (int i = 0; i < 10; ++i) rig.cycle();
  EXPECT_EQ(rig.controller.active_kind(), TravelKind::None);
}

TEST(Relevel, WithoutElectricStopClearsB1AndB0Together) {
  TravelConfig config = dcp3_shaft();
  config.relevel_electric_stop = false;
  Rig rig(Protocol::Dcp3, config);
  rig.cycle();
  ASSERT_EQ(rig.controller.start(relevel_request(Direction::Down)), StartResult::Accepted);
  for (int i = 0; i < 30; ++i) rig.cycle();
  rig.input.inputs.level_zone = true;
  ASSERT_TRUE(rig.run_to_idle());
  EXPECT_EQ(rig.command_runs(1), (std::vector<std::uint8_t>{0x19, 0x13, 0x00}));
  EXPECT_EQ(rig.event_types(), (std::vector<Type>{Type::Started, Type::Finished}));
}

}  // namespace
}  // namespace liftd::travel::test
