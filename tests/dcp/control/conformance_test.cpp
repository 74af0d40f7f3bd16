// The DCP rules a master most easily gets wrong, through the real DcpController
// against the simulated drive on a fake clock: S5 confirms target changes (DCP 4.1, 7.2), the
// communication channel never ends a travel (DCP 5.1, 5.4), older drives (DCP 5.12.3.1), I9
// after every stop (DCP 5.12.9), S0 dropping during a travel (DCP 9.1.3, 5.5), the service stop.
#include <gtest/gtest.h>

#include <algorithm>

#include "controller_rig.hpp"

namespace liftd::control {
namespace {

using testing::enable_of;
using testing::Rig;
using namespace std::chrono_literals;
namespace sb = dcp::status_bit;
namespace cb = dcp::command_bit;

constexpr double kLandingMm = 2.0;

// ---- S5: a target change counts once the drive accepted it (DCP 4.1, 7.2) -------------------

TEST(TargetChange, TheReplyWaitsForTheDrivesS5) {
  Rig rig;
  ASSERT_TRUE(rig.warm_up());
  ASSERT_EQ(rig.command(TravelCommand{2, std::nullopt, std::nullopt, false}).code, ReplyCode::Ok);
  ASSERT_TRUE(rig.run_until([&] { return rig.sim.position_mm() > 300.0; }, 20s));
  const std::size_t asked_at = rig.log.size();
  const CommandReply r = rig.command(TravelCommand{4, std::nullopt, std::nullopt, false});
  ASSERT_EQ(r.code, ReplyCode::Ok) << r.detail;
  EXPECT_TRUE(r.extended);
  // Frame N carries the new distance, the reply to it carries S5: the answer comes after it.
  EXPECT_GE(rig.log.size() - asked_at, 2U);
  ASSERT_EQ(rig.travel_events(travel::Event::Type::TargetExtended).size(), 1U);
  ASSERT_TRUE(rig.run_until([&] { return rig.finished_travels(1) && rig.idle(); }, 60s));
  EXPECT_NEAR(rig.sim.position_mm(), 12000.0, kLandingMm);
}

TEST(TargetChange, RefusedByTheDriveEndsTheTravelWithB2HeldUntilS6) {
  Rig rig;
  ASSERT_TRUE(rig.warm_up());
  ASSERT_EQ(rig.command(TravelCommand{2, std::nullopt, std::nullopt, false}).code, ReplyCode::Ok);
  ASSERT_TRUE(rig.run_until([&] { return rig.sim.position_mm() > 300.0; }, 20s));
  rig.sim.refuse_next_target();
  const CommandReply r = rig.command(TravelCommand{4, std::nullopt, std::nullopt, false});
  EXPECT_EQ(r.code, ReplyCode::Fault);
  EXPECT_FALSE(r.extended);
  EXPECT_NE(r.detail.find("refused"), std::string_view::npos) << r.detail;
  ASSERT_TRUE(rig.run_until([&] { return rig.idle(); }, 30s));
  EXPECT_TRUE(rig.travel_events(travel::Event::Type::TargetExtended).empty());
  ASSERT_EQ(rig.travel_events(travel::Event::Type::TargetRefused).size(), 1U);
  const auto aborted = rig.travel_events(travel::Event::Type::Aborted);
  ASSERT_EQ(aborted.size(), 1U);
  EXPECT_EQ(aborted[0].cause, lift::Cause::TargetRefused);
  // The drive stopped on its emergency ramp; we kept B2 until it dropped S6 (DCP 11.1.1 d).
  for (std::size_t i = 1; i < rig.log.size(); ++i) {
    const bool dropped = (rig.log[i - 1].frame[0] & cb::kStopSwitch) != 0 &&
                         (rig.log[i].frame[0] & cb::kStopSwitch) == 0;
    if (dropped) {
      EXPECT_FALSE(*rig.log[i].seen & sb::kBrakeOpen) << "frame " << i;
    }
  }
  EXPECT_FALSE(enable_of(rig.frames.back()));
  EXPECT_EQ(rig.sim.counters().violations, 0U);
}

// ---- the communication channel is subordinate (DCP 5.1) ----------------------------------------

class ChannelFaultDuringTravel : public ::testing::TestWithParam<dcp::sim::ChannelFault> {};

TEST_P(ChannelFaultDuringTravel, B0StaysUntilTheCarStandsThenTheHandshakeRunsAgain) {
  Rig rig;
  ASSERT_TRUE(rig.warm_up());
  ASSERT_EQ(rig.command(TravelCommand{5, std::nullopt, std::nullopt, false}).code, ReplyCode::Ok);
  ASSERT_TRUE(rig.run_until([&] { return rig.sim.velocity_mps() > 1.0; }, 20s));
  const std::size_t from = rig.log.size();
  rig.sim.inject_channel(GetParam(), rig.now);
  ASSERT_TRUE(rig.run_until([&] { return rig.finished_travels(1) && rig.idle(); }, 60s));
  // Every frame from the fault to the end of the travel kept B0 (the car was moving).
  std::size_t last_b0 = from;
  for (std::size_t i = from; i < rig.log.size(); ++i) {
    if (enable_of(rig.log[i].frame)) last_b0 = i;
  }
  for (std::size_t i = from; i <= last_b0; ++i) {
    EXPECT_TRUE(enable_of(rig.log[i].frame)) << "B0 withdrawn in frame " << i;
  }
  EXPECT_NEAR(rig.sim.position_mm(), 15000.0, kLandingMm);
  EXPECT_TRUE(rig.travel_events(travel::Event::Type::Aborted).empty());
  EXPECT_EQ(rig.raised(FaultCode::LinkFault), 0U);
  // At rest the channel is usable again and the next travel goes.
  rig.run(3s);
  EXPECT_TRUE(rig.link_up());
  ASSERT_EQ(rig.command(TravelCommand{3, std::nullopt, std::nullopt, false}).code, ReplyCode::Ok);
  ASSERT_TRUE(rig.run_until([&] { return rig.finished_travels(2) && rig.idle(); }, 60s));
  EXPECT_EQ(rig.sim.counters().violations, 0U);
}

INSTANTIATE_TEST_SUITE_P(Dcp5, ChannelFaultDuringTravel,
                         ::testing::Values(dcp::sim::ChannelFault::Partial,
                                           dcp::sim::ChannelFault::Garbage,
                                           dcp::sim::ChannelFault::Silence),
                         [](const auto& p) {
                           return std::string(p.param == dcp::sim::ChannelFault::Partial ? "Partial"
                                              : p.param == dcp::sim::ChannelFault::Garbage
                                                  ? "Garbage"
                                                  : "Silence");
                         });

// ---- older drives (DCP 5.12.3.1, 5.12.2.2) -----------------------------------------------------

TEST(OlderDrive, IgnoringI1AndOddI0FieldsStillTravels) {
  ControllerConfig config = testing::default_config(dcp::Protocol::Dcp4);
  config.link.data_info_type = dcp::DataInfoType::Decel16;  // asks for 16 bits; gets type '0'
  dcp::sim::DriveConfig drive = testing::sim_config(dcp::Protocol::Dcp4);
  drive.older_drive = true;
  Rig rig(config, drive);
  ASSERT_TRUE(rig.warm_up()) << "the handshake must complete without an I1 reply";
  EXPECT_EQ(rig.controller.link().active_data_info_type(), dcp::DataInfoType::Alternating);
  ASSERT_TRUE(rig.controller.link().drive_info());
  EXPECT_NE(rig.controller.link().drive_info()->anomalies, 0);
  ASSERT_EQ(rig.command(TravelCommand{3, std::nullopt, std::nullopt, false}).code, ReplyCode::Ok);
  ASSERT_TRUE(rig.run_until([&] { return rig.finished_travels(1) && rig.idle(); }, 60s));
  EXPECT_NEAR(rig.sim.position_mm(), 9000.0, kLandingMm);
}

// ---- I9 after every stop (DCP 5.12.9) ----------------------------------------------------------

class PositionAfterStop : public ::testing::TestWithParam<dcp::Protocol> {};

TEST_P(PositionAfterStop, AfterFinishedAndAbortedTravelsBeforeTheNextOne) {
  Rig rig(GetParam());
  ASSERT_TRUE(rig.warm_up());
  ASSERT_EQ(rig.command(TravelCommand{2, std::nullopt, std::nullopt, false}).code, ReplyCode::Ok);
  ASSERT_TRUE(rig.run_until([&] { return rig.finished_travels(1) && rig.idle(); }, 60s));
  rig.run(1s);
  EXPECT_NEAR(static_cast<double>(rig.sim.controller_position_mm()), 6000.0, 3.0);
  // An aborted travel is a stop too: the safety chain opens mid-way.
  ASSERT_EQ(rig.command(TravelCommand{5, std::nullopt, std::nullopt, false}).code, ReplyCode::Ok);
  ASSERT_TRUE(rig.run_until([&] { return rig.sim.position_mm() > 7500.0; }, 20s));
  rig.inputs.safety_chain_closed = false;
  ASSERT_TRUE(rig.run_until([&] { return rig.sim.stationary() && rig.idle(); }, 20s));
  rig.inputs.safety_chain_closed = true;
  rig.run(1s);
  EXPECT_NEAR(static_cast<double>(rig.sim.controller_position_mm()), rig.sim.position_mm(), 3.0);
  // The next travel starts right away: it waits for the I9 if one is still owed.
  ASSERT_EQ(rig.command(TravelCommand{0, std::nullopt, std::nullopt, false}).code, ReplyCode::Ok);
  ASSERT_TRUE(rig.run_until([&] { return rig.finished_travels(2) && rig.idle(); }, 60s));
  EXPECT_EQ(rig.sim.violations(dcp::sim::Violation::NoPositionAfterStop), 0U);
}

INSTANTIATE_TEST_SUITE_P(Dialects, PositionAfterStop,
                         ::testing::Values(dcp::Protocol::Dcp4, dcp::Protocol::Dcp3),
                         [](const auto& p) {
                           return std::string(p.param == dcp::Protocol::Dcp4 ? "Dcp4" : "Dcp3");
                         });

// ---- S0 during a travel (DCP 9.1.3, 4.1, 5.5) --------------------------------------------------

TEST(DriveNotReady, DuringATravelItFinishesThenNoNewTravelStarts) {
  Rig rig;
  ASSERT_TRUE(rig.warm_up());
  ASSERT_EQ(rig.command(TravelCommand{3, std::nullopt, std::nullopt, false}).code, ReplyCode::Ok);
  ASSERT_TRUE(rig.run_until([&] { return rig.sim.velocity_mps() > 1.0; }, 20s));
  rig.sim.set_not_ready(true);
  ASSERT_TRUE(rig.run_until([&] { return rig.finished_travels(1) && rig.idle(); }, 60s));
  EXPECT_NEAR(rig.sim.position_mm(), 9000.0, kLandingMm);
  EXPECT_TRUE(rig.travel_events(travel::Event::Type::Aborted).empty());
  const CommandReply r = rig.command(TravelCommand{0, std::nullopt, std::nullopt, false});
  EXPECT_EQ(r.code, ReplyCode::NotReady);
  EXPECT_EQ(r.detail, "drive not ready (S0 = 0)");
  rig.sim.set_not_ready(false);
  rig.run(100ms);
  EXPECT_EQ(rig.command(TravelCommand{0, std::nullopt, std::nullopt, false}).code, ReplyCode::Ok);
}

TEST(DriveNotReady, TheSnapshotAllowsATravelExactlyWhenS0Does) {
  // status drive.state reads drive_allows_travel: the drive's side of the check a travel command
  // passes (DCP 9.1.3), so `ready` and an accepted travel go together.
  Rig rig;
  ASSERT_TRUE(rig.warm_up());
  EXPECT_TRUE(rig.controller.snapshot().drive_allows_travel);
  rig.sim.set_not_ready(true);
  rig.run(100ms);
  ControllerSnapshot s = rig.controller.snapshot();
  ASSERT_TRUE(s.status_byte.has_value());
  EXPECT_EQ(*s.status_byte & dcp::status_bit::kReady, 0);
  EXPECT_FALSE(s.drive_allows_travel);
  EXPECT_TRUE(std::none_of(s.faults.begin(), s.faults.end(), [](bool f) { return f; }))
      << "S0 = 0 is no fault";
  const CommandReply r = rig.command(TravelCommand{3, std::nullopt, std::nullopt, false});
  EXPECT_EQ(r.code, ReplyCode::NotReady);
  EXPECT_EQ(r.detail, "drive not ready (S0 = 0)");
  EXPECT_FALSE(rig.controller.snapshot().drive_allows_travel);
  rig.sim.set_not_ready(false);
  rig.run(100ms);
  EXPECT_TRUE(rig.controller.snapshot().drive_allows_travel);
  EXPECT_EQ(rig.command(TravelCommand{3, std::nullopt, std::nullopt, false}).code, ReplyCode::Ok);
}

TEST(DriveReset, IsRefusedWhileATravelRuns) {
  Rig rig;
  ASSERT_TRUE(rig.warm_up());
  ASSERT_EQ(rig.command(TravelCommand{3, std::nullopt, std::nullopt, false}).code, ReplyCode::Ok);
  ASSERT_TRUE(rig.run_until([&] { return rig.sim.velocity_mps() > 0.5; }, 20s));
  const CommandReply r = rig.command(LinkCommand{dcp::SwitchRequest{dcp::SwitchFunction::Reset}});
  EXPECT_EQ(r.code, ReplyCode::Busy);
  ASSERT_TRUE(rig.run_until([&] { return rig.finished_travels(1) && rig.idle(); }, 60s));
}

// ---- the service stop ---------------------------------------------------------------------------

TEST(ServiceStop, DuringATravelLandsAtAFloorThenQuiescesWithB0Off) {
  Rig rig;
  ASSERT_TRUE(rig.warm_up());
  ASSERT_EQ(rig.command(TravelCommand{5, std::nullopt, std::nullopt, false}).code, ReplyCode::Ok);
  ASSERT_TRUE(rig.run_until([&] { return rig.sim.velocity_mps() > 1.2; }, 20s));
  ASSERT_EQ(rig.command(ShutdownCommand{false}).code, ReplyCode::Ok);
  EXPECT_EQ(rig.command(TravelCommand{1, std::nullopt, std::nullopt, false}).code,
            ReplyCode::NotReady);
  ASSERT_TRUE(rig.run_until([&] { return rig.controller.snapshot().quiesced; }, 30s));
  EXPECT_EQ(rig.finished_travels(1), true);
  const double at = rig.sim.position_mm();
  EXPECT_NEAR(at, 3000.0 * std::round(at / 3000.0), kLandingMm);
  EXPECT_LT(at, 15000.0);
  // A DCP 7.3 supervision window of B0-off frames has gone out before "quiesced".
  std::size_t off = 0;
  for (std::size_t i = rig.frames.size(); i > 0 && !enable_of(rig.frames[i - 1]); --i) ++off;
  EXPECT_GE(off, 10U);
  EXPECT_EQ(rig.sim.counters().violations, 0U);
  EXPECT_FALSE(rig.sim.status_byte() & sb::kGeneralFault);
}

TEST(ServiceStop, ForcedEndsTheTravelAtOnceWithB0Off) {
  Rig rig;
  ASSERT_TRUE(rig.warm_up());
  ASSERT_EQ(rig.command(TravelCommand{5, std::nullopt, std::nullopt, false}).code, ReplyCode::Ok);
  ASSERT_TRUE(rig.run_until([&] { return rig.sim.velocity_mps() > 1.2; }, 20s));
  ASSERT_EQ(rig.command(ShutdownCommand{true}).code, ReplyCode::Ok);
  EXPECT_FALSE(enable_of(rig.frames.back()));
  const auto aborted = rig.travel_events(travel::Event::Type::Aborted);
  ASSERT_EQ(aborted.size(), 1U);
  EXPECT_EQ(aborted[0].cause, lift::Cause::ShuttingDown);
}

TEST(ServiceStop, AtRestQuiescesWithinOneSupervisionWindow) {
  Rig rig;
  ASSERT_TRUE(rig.warm_up());
  rig.post(ShutdownCommand{false});
  rig.cycle();
  rig.cycle();
  EXPECT_TRUE(rig.controller.snapshot().quiesced) << "long at rest: B0 has been off for ages";
}

}  // namespace
}  // namespace liftd::control
