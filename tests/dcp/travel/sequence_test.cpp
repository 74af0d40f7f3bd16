// Each travel type against the scripted drive, with a fake clock: the exact command bytes and
// data words in the order of the DCP 1.0.0.13 figures' numbered steps (chapters 9 to 13).
#include <gtest/gtest.h>

#include "fake_drive.hpp"
#include "sequence_requests.hpp"

namespace liftd::travel::test {
namespace {

TEST(Dcp4Travel, LongV4TravelFollowsFigure11_3) {
  Rig rig(Protocol::Dcp4);
  rig.cycle();  // controller learns the idle state
  ASSERT_EQ(rig.controller.start(dcp4_request(10000)), StartResult::Accepted);
  ASSERT_TRUE(rig.run_to_idle());

  // I7 first (DCP 11.1.2.1 example 2: V4, 1000 cm); the I9 after the stop is the DCP
  // controller's (tests/dcp/control, DCP 5.12.9).
  ASSERT_TRUE(rig.records[1].channel_request.has_value());
  EXPECT_EQ(body_text(*rig.records[1].channel_request), "I7201000");
  // Step 1 speed message V4 (G7 = 0x0080), steps 2..4 B2+B0, then B0 until S1 = 0, then idle.
  EXPECT_EQ(rig.command_runs(1), (std::vector<std::uint8_t>{0x00, 0x09, 0x05, 0x01, 0x00}));
  const std::size_t speed_at = rig.first(0x09);
  EXPECT_EQ(rig.records[speed_at].data_word, 0x0080);
  EXPECT_EQ(rig.count(0x09), 2U);  // speed_message_cycles
  // The remaining distance every cycle, from the position the controller saw (15-bit, mm).
  for (const auto& r : rig.records) {
    if (r.command != 0x05) continue;
    EXPECT_EQ(r.data_word,
              dcp::remaining_distance_word(10000 - r.position_mm, dcp::DistanceWidth::Bits15));
  }
  // B2 held until S6 fell (DCP 11.1.2 step 4): the last 0x05 frame still saw S6 = 1 or the
  // first frame after it saw S6 = 0.
  const std::size_t stop_at = rig.first(0x01);
  EXPECT_TRUE(rig.records[stop_at - 1].status.brake_open);
  EXPECT_FALSE(rig.records[stop_at].status.brake_open);
  // B0 held until S1 = 0 (11.1.4 step 5).
  const std::size_t idle_at = rig.first(0x00, stop_at);
  EXPECT_TRUE(rig.records[idle_at - 1].status.travel_active);
  EXPECT_FALSE(rig.records[idle_at].status.travel_active);
  EXPECT_EQ(rig.event_types(), (std::vector<Type>{Type::Started, Type::Finished}));
  EXPECT_NEAR(rig.drive.position_mm(), 10000.0, 1.0);
}

TEST(Dcp4Travel, KeepsI7FiguresAndDrivesContactorsAndBrakeFromStatus) {
  Rig rig(Protocol::Dcp4);
  rig.cycle();
  ASSERT_EQ(rig.controller.start(dcp4_request(10000)), StartResult::Accepted);
  std::vector<CycleOutput> outs;
  for (int i = 0; i < 4000; ++i) {
    outs.push_back(rig.cycle());
    if (rig.controller.dcp4().start_parameters()) break;
  }
  ASSERT_TRUE(rig.controller.dcp4().start_parameters().has_value());
  EXPECT_EQ(rig.controller.dcp4().start_parameters()->min_distance_cm, 520U);  // Sg
  EXPECT_EQ(*rig.controller.decel_distance_mm(), 2500U);  // Sv until the data bytes say more
  while (rig.controller.active_kind() != TravelKind::None || rig.drive.status().travel_active) {
    outs.push_back(rig.cycle());
    ASSERT_LT(outs.size(), 4000U);
  }
  for (std::size_t i = 0; i < outs.size(); ++i) {
    const auto& seen = rig.records[rig.records.size() - outs.size() + i].status;
    EXPECT_EQ(outs[i].brake_open, seen.brake_open) << i;  // DCP 9.1.7
    EXPECT_EQ(outs[i].contactors_on, (outs[i].command & 0x01) != 0 || seen.travel_active) << i;
  }
}

TEST(Dcp4Travel, DriveFaultEdgesAreReported) {
  Rig rig(Protocol::Dcp4);
  rig.cycle();
  rig.drive.status().general_fault = true;
  rig.cycle();
  rig.cycle();
  rig.drive.status().general_fault = false;
  rig.cycle();
  EXPECT_EQ(rig.event_types(), (std::vector<Type>{Type::DriveFault, Type::DriveFaultCleared}));
}

TEST(TravelConfigCheck, NamesTheFirstBadField) {
  // Legend: a change to the defaults -> the field reported (nullopt: valid).
  struct Case {
    void (*change)(TravelConfig&);
    std::optional<std::string_view> field;
  };
  const std::vector<Case> cases = {
      {[](TravelConfig&) {}, std::nullopt},
      {[](TravelConfig& c) { c.speed_message_cycles = 0; }, "speed_message_cycles"},
      {[](TravelConfig& c) { c.dcp3_speed_count = 8; }, "dcp3_speed_count"},
      {[](TravelConfig& c) { c.dcp3_speed_count = 0; }, "dcp3_speed_count"},
      {[](TravelConfig& c) { c.relevel_threshold_mm = 2; }, "relevel_threshold_mm"},
      {[](TravelConfig& c) { c.relevel_zone_mm = 10; }, "relevel_zone_mm"},
      {[](TravelConfig& c) { c.stop_timeout_ms = 0; }, "stop_timeout_ms"},
      {[](TravelConfig& c) { c.data_info_type = static_cast<dcp::DataInfoType>('9'); },
       "data_info_type"},
  };
  for (const auto& c : cases) {
    TravelConfig config;
    c.change(config);
    EXPECT_EQ(validate(config), c.field);
  }
}

TEST(Dcp4Travel, DownwardV3TravelKeepsB4SetThroughout) {
  TravelConfig config;
  config.use_i7 = false;
  Rig rig(Protocol::Dcp4, config);
  rig.drive.set_position_mm(9000);
  rig.cycle();
  ASSERT_EQ(rig.controller.start(dcp4_request(3000, Speed::V3)), StartResult::Accepted);
  ASSERT_TRUE(rig.run_to_idle());
  EXPECT_EQ(rig.command_runs(1), (std::vector<std::uint8_t>{0x19, 0x15, 0x11, 0x00}));
  EXPECT_EQ(rig.records[rig.first(0x19)].data_word, 0x0040);  // V3 = G6
  EXPECT_NEAR(rig.drive.position_mm(), 3000.0, 1.0);
}

TEST(Dcp4Travel, LoadIsSentWithI8BeforeTheSpeedMessage) {
  TravelConfig config;
  config.use_i7 = false;
  Rig rig(Protocol::Dcp4, config);
  rig.cycle();
  TravelRequest request = dcp4_request(3000);
  request.load_percent = 25;
  ASSERT_EQ(rig.controller.start(request), StartResult::Accepted);
  rig.cycle();
  ASSERT_TRUE(rig.records.back().channel_request.has_value());
  EXPECT_EQ(body_text(*rig.records.back().channel_request), "I8025");
  EXPECT_EQ(rig.records.back().command, 0x00);
  ASSERT_TRUE(rig.run_to_idle());
  EXPECT_EQ(rig.command_runs(1), (std::vector<std::uint8_t>{0x00, 0x09, 0x05, 0x01, 0x00}));
}

TEST(Dcp4Travel, StartsWithoutI8ReplyAfterTimeout) {
  TravelConfig config;
  config.use_i7 = false;
  config.i8_timeout_ms = 300;
  Rig rig(Protocol::Dcp4, config);
  rig.answer_channel = false;
  rig.cycle();
  TravelRequest request = dcp4_request(3000);
  request.load_percent = 50;
  ASSERT_EQ(rig.controller.start(request), StartResult::Accepted);
  ASSERT_TRUE(rig.run_until([&] { return rig.records.back().command == 0x09; }));
  // DCP 5.12.8.3: go without the reply; 300 ms = 20 cycles of waiting.
  EXPECT_EQ(rig.first(0x09), 22U);
}

TEST(Dcp4Travel, SixteenBitRemainingDistanceForDataInfoType3) {
  TravelConfig config;
  config.use_i7 = false;
  config.data_info_type = dcp::DataInfoType::Decel16;
  Rig rig(Protocol::Dcp4, config);
  rig.cycle();
  ASSERT_EQ(rig.controller.start(dcp4_request(40000)), StartResult::Accepted);
  ASSERT_TRUE(rig.run_until([&] { return rig.records.back().command == 0x05; }));
  EXPECT_EQ(rig.records.back().data_word, 40000);  // 0x9C40: above the 15-bit limit
}

TEST(Dcp4Travel, FifteenBitRemainingDistanceClampsAt7FFF) {
  TravelConfig config;
  config.use_i7 = false;
  Rig rig(Protocol::Dcp4, config);
  rig.cycle();
  ASSERT_EQ(rig.controller.start(dcp4_request(40000)), StartResult::Accepted);
  ASSERT_TRUE(rig.run_until([&] { return rig.records.back().command == 0x05; }));
  EXPECT_EQ(rig.records.back().data_word, 0x7FFF);  // DCP 3.5.3.4
}

TEST(Dcp4Travel, TargetExtensionRules) {
  Rig rig(Protocol::Dcp4);
  rig.cycle();
  ASSERT_EQ(rig.controller.start(dcp4_request(10000)), StartResult::Accepted);
  rig.cycle();
  // Not further in the travel direction: refused at any time.
  EXPECT_EQ(rig.controller.extend_target(9000), ExtendResult::NotFurther);
  ASSERT_TRUE(rig.run_until([&] { return rig.drive.speed_mm_s() > 1000; }));
  // Far from the deceleration point: sent, and the next frame carries the new distance; the
  // drive's S5 in the reply to that frame confirms it (DCP 4.1), and only then is it reported.
  ASSERT_EQ(rig.controller.extend_target(15000), ExtendResult::Pending);
  rig.cycle();
  EXPECT_EQ(rig.records.back().data_word, 15000 - rig.records.back().position_mm);
  EXPECT_EQ(rig.controller.extend_target(15500), ExtendResult::Busy);  // one change at a time
  rig.cycle();
  ASSERT_FALSE(rig.events.empty());
  EXPECT_EQ(rig.events.back().type, Type::TargetExtended);
  EXPECT_EQ(rig.events.back().target_mm, 15000);
  // S2 set: DCP 9.1.5 forbids extending.
  rig.drive.status().advance_warning = true;
  rig.cycle();
  EXPECT_EQ(rig.controller.extend_target(16000), ExtendResult::AdvanceWarning);
  rig.drive.status().advance_warning = false;
  rig.cycle();
  // Inside deceleration distance + lead: too late (DCP 7.2, 11.1.2 note).
  ASSERT_TRUE(rig.run_until([&] {
    const auto decel = rig.controller.decel_distance_mm();
    return decel && 15000 - rig.drive.position_mm() < *decel + 10.0;
  }));
  EXPECT_EQ(rig.controller.extend_target(20000), ExtendResult::TooLate);
  ASSERT_TRUE(rig.run_to_idle());
  EXPECT_NEAR(rig.drive.position_mm(), 15000.0, 1.0);
}

/// Hand-made cycles of a car running at 1600 mm/s (24 mm per 15 ms cycle, DCP 7.2) whose
/// drive reports a live deceleration distance of 1600 mm; `position` advances with it.
void run_at_full_speed(TravelController& controller, CycleInput& in, std::int64_t& position,
                       int cycles) {
  for (int i = 0; i < cycles; ++i) {
    in.now += kCycle;
    position += 24;
    in.position_mm = position;
    in.status.travel_active = in.status.brake_open = true;
    in.decel_distance_mm = 1600;
    controller.step(in);
  }
}

TEST(Dcp4Travel, ExtensionLeadCoversThirtyMsPlusTwoCycles) {
  // Hand-made cycles: the car runs at 1600 mm/s (24 mm per 15 ms cycle), the drive reports a
  // deceleration distance of 1600 mm. Lead = 1600 mm/s * (30 ms + 2 cycles) = 96 mm (DCP 7.2),
  // margin 0: an extension is accepted while remaining > 1600 + 96 mm.
  // Legend: remaining distance when asking -> result.
  struct Case {
    std::int64_t remaining_mm;
    ExtendResult expected;
  };
  const std::vector<Case> cases = {
      {5000, ExtendResult::Pending},
      {1697, ExtendResult::Pending},
      {1696, ExtendResult::TooLate},
      {1600, ExtendResult::TooLate},
  };
  for (const auto& c : cases) {
    TravelConfig config;
    config.use_i7 = false;
    config.speed_message_cycles = 1;
    config.extension_margin_mm = 0;
    TravelController controller(config);
    CycleInput in;
    in.link_up = true;
    in.handshake_done = true;
    in.reply_fresh = true;
    in.protocol = Protocol::Dcp4;
    in.status.ready = true;
    in.status.accepted = true;  // S5: the drive took the speed message
    in.inputs.valid = in.inputs.safety_chain_closed = true;
    in.inputs.doors_closed = in.inputs.doors_locked = true;
    const std::int64_t target = 30000;
    std::int64_t position = target - c.remaining_mm - 24 * 5;
    in.position_mm = position;
    controller.step(in);
    ASSERT_EQ(controller.start(dcp4_request(target)), StartResult::Accepted);
    run_at_full_speed(controller, in, position, 5);  // speed message, then B2 + B0
    ASSERT_EQ(controller.dcp4().state(), Dcp4Travel::State::Distance);
    EXPECT_EQ(controller.extend_target(target + 1000), c.expected) << c.remaining_mm;
  }
}

TEST(Dcp4Travel, ExtensionLimitIsTheLargerOfSvAndTheLiveDistance) {
  // DCP 11.1.2 note: extend "while it is greater than the deceleration distance the drive
  // controller had transmitted before the beginning of the travel" (I7's Sv, 2500 mm here),
  // even while the live value (1600 mm, still growing while the car accelerates) is smaller.
  // Lead as above: 1600 mm/s * 60 ms = 96 mm, margin 0.
  struct Case {
    std::int64_t remaining_mm;
    ExtendResult expected;
  };
  const std::vector<Case> cases = {
      {2597, ExtendResult::Pending},
      {2596, ExtendResult::TooLate},
      {2000, ExtendResult::TooLate},  // beyond live + lead, inside Sv + lead
  };
  for (const auto& c : cases) {
    TravelConfig config;
    config.speed_message_cycles = 1;
    config.extension_margin_mm = 0;
    TravelController controller(config);
    CycleInput in;
    in.link_up = in.handshake_done = in.reply_fresh = true;
    in.protocol = Protocol::Dcp4;
    in.status.ready = in.status.accepted = true;
    in.inputs.valid = in.inputs.safety_chain_closed = true;
    in.inputs.doors_closed = in.inputs.doors_locked = true;
    const std::int64_t target = 30000;
    std::int64_t position = target - c.remaining_mm - 24 * 4;
    in.position_mm = position;
    controller.step(in);
    ASSERT_EQ(controller.start(dcp4_request(target)), StartResult::Accepted);
    in.now += kCycle;
    controller.step(in);  // I7 goes out
    ChannelReply i7;
    i7.kind = ChannelRequest::Kind::StartParameters;
    i7.decel_distance_cm = 250;
    in.channel_reply = i7;
    for (int i = 0; i < 5; ++i) {
      in.now += kCycle;
      controller.step(in);
      in.channel_reply.reset();
    }
    run_at_full_speed(controller, in, position, 4);
    ASSERT_EQ(controller.dcp4().state(), Dcp4Travel::State::Distance);
    EXPECT_EQ(controller.extend_target(target + 1000), c.expected) << c.remaining_mm;
  }
}

TEST(Dcp4Travel, NoTravelCommandUntilTheDriveAcceptsTheSpeed) {
  // DCP 4.1 S5 "Desired distance / speed accepted": without it after the speed message no B2
  // goes out; after travel.start_timeout_ms the travel ends as refused.
  TravelConfig config;
  config.use_i7 = false;
  config.speed_message_cycles = 1;
  TravelController controller(config);
  CycleInput in;
  in.link_up = in.handshake_done = in.reply_fresh = true;
  in.protocol = Protocol::Dcp4;
  in.status.ready = true;  // S5 never comes
  in.inputs.valid = in.inputs.safety_chain_closed = true;
  in.inputs.doors_closed = in.inputs.doors_locked = true;
  in.position_mm = 0;
  controller.step(in);
  ASSERT_EQ(controller.start(dcp4_request(3000)), StartResult::Accepted);
  const int cycles = static_cast<int>(config.start_timeout_ms / 15) + 3;
  for (int i = 0; i < cycles; ++i) {
    in.now += kCycle;
    const CycleOutput out = controller.step(in);
    EXPECT_EQ(out.command & dcp::command_bit::kStopSwitch, 0) << "cycle " << i;
  }
  EXPECT_EQ(controller.active_kind(), TravelKind::None);
  std::optional<Event> last;
  while (auto e = controller.pop_event()) last = e;
  ASSERT_TRUE(last);
  EXPECT_EQ(last->type, Type::Aborted);
  EXPECT_EQ(last->cause, lift::Cause::TargetRefused);
}

TEST(Dcp4Travel, DriveStoppingShortIsReportedAsOffLevel) {
  // Hand-made cycles: the drive drops S6 and then S1 600 mm before the target.
  TravelConfig config;
  config.use_i7 = false;
  config.speed_message_cycles = 1;
  TravelController controller(config);
  CycleInput in;
  in.link_up = in.handshake_done = in.reply_fresh = true;
  in.protocol = Protocol::Dcp4;
  in.status.ready = true;
  in.status.accepted = true;  // S5: the drive took the speed message
  in.inputs.valid = in.inputs.safety_chain_closed = true;
  in.inputs.doors_closed = in.inputs.doors_locked = true;
  in.position_mm = 0;
  controller.step(in);
  ASSERT_EQ(controller.start(dcp4_request(3000)), StartResult::Accepted);
  std::vector<std::uint8_t> commands;
  auto cycle = [&] {
    in.now += kCycle;
    commands.push_back(controller.step(in).command);
  };
  cycle();  // speed message
  in.status.travel_active = in.status.brake_open = true;
  for (int i = 0; i < 5; ++i) cycle();
  in.position_mm = 2400;
  in.status.brake_open = false;  // drive stops on its own
  cycle();
  cycle();
  in.status.travel_active = false;
  cycle();
  EXPECT_EQ(commands,
            (std::vector<std::uint8_t>{0x09, 0x05, 0x05, 0x05, 0x05, 0x05, 0x01, 0x01, 0x00}));
  std::optional<Event> last;
  while (auto e = controller.pop_event()) last = e;
  ASSERT_TRUE(last.has_value());
  EXPECT_EQ(last->type, Type::Aborted);
  EXPECT_EQ(last->cause, lift::Cause::StoppedOffLevel);
}

TEST(Dcp4Relevel, AutoRelevelOnDriftWithVnAndRemainingDistance) {
  TravelConfig config;
  config.relevel_threshold_mm = 15;
  Rig rig(Protocol::Dcp4, config);
  rig.controller.set_home_level(0);
  rig.drive.set_position_mm(-10);  // within threshold: nothing
  for (int i = 0; i < 5; ++i) rig.cycle();
  EXPECT_EQ(rig.command_runs(), (std::vector<std::uint8_t>{0x00}));
  rig.drive.set_position_mm(-30);  // rope stretch: 30 mm below the level
  ASSERT_TRUE(rig.run_until([&] { return rig.records.back().command == 0x09; }));
  EXPECT_EQ(rig.records.back().data_word, 0x0002);  // VN = G1, no I7 for VN'
  EXPECT_FALSE(rig.records.back().channel_request.has_value());
  rig.cycle();
  rig.cycle();
  EXPECT_EQ(rig.records.back().command, 0x05);
  EXPECT_EQ(rig.records.back().data_word, 30);
  ASSERT_TRUE(rig.run_to_idle());
  EXPECT_EQ(rig.command_runs(5), (std::vector<std::uint8_t>{0x09, 0x05, 0x01, 0x00}));
  EXPECT_NEAR(rig.drive.position_mm(), 0.0, 1.0);
  ASSERT_FALSE(rig.events.empty());
  EXPECT_EQ(rig.events.back().kind, TravelKind::Dcp4Relevel);
  EXPECT_EQ(rig.events.back().type, Type::Finished);
}

TEST(Dcp4Relevel, OnRequestDownward) {
  Rig rig(Protocol::Dcp4);
  rig.drive.set_position_mm(5040);
  rig.cycle();
  TravelRequest request;
  request.kind = TravelKind::Dcp4Relevel;
  request.target_mm = 5000;
  ASSERT_EQ(rig.controller.start(request), StartResult::Accepted);
  ASSERT_TRUE(rig.run_to_idle());
  EXPECT_EQ(rig.command_runs(1), (std::vector<std::uint8_t>{0x19, 0x15, 0x11, 0x00}));
  EXPECT_NEAR(rig.drive.position_mm(), 5000.0, 1.0);
}

}  // namespace
}  // namespace liftd::travel::test
