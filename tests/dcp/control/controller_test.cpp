// The DcpController against the drive simulator, in process: link up, travels, gating, faults.
#include <gtest/gtest.h>

#include "controller_rig.hpp"

namespace liftd::control {
namespace {

using testing::Rig;
using namespace std::chrono_literals;

TEST(DcpController, LinkComesUpWithHandshake) {
  Rig rig;
  ASSERT_TRUE(rig.run_until([&] { return rig.link_up(); }, 5s));
  const auto s = rig.controller.snapshot();
  EXPECT_EQ(s.protocol, dcp::Protocol::Dcp4);
  ASSERT_TRUE(s.drive_info.has_value());
}

TEST(DcpController, Dcp4TravelLandsOnTheLevel) {
  Rig rig;
  ASSERT_TRUE(rig.run_until([&] { return rig.link_up(); }, 5s));
  rig.run(200ms);
  const CommandReply r = rig.command(TravelCommand{3, dcp::Speed::V4, std::nullopt, false});
  ASSERT_EQ(r.code, ReplyCode::Ok) << r.detail;
  ASSERT_TRUE(rig.run_until([&] { return rig.finished_travels(1) && rig.idle(); }, 60s));
  EXPECT_NEAR(rig.sim.position_mm(), 9000.0, 2.0);
  EXPECT_EQ(rig.controller.snapshot().floor, 3U);
  // B0 off once stationary.
  EXPECT_EQ(rig.frames.back()[0] & dcp::command_bit::kDriveEnable, 0);
}

TEST(DcpController, RefusesTravelWithSafetyChainOpenAndSaysWhy) {
  Rig rig;
  ASSERT_TRUE(rig.run_until([&] { return rig.link_up(); }, 5s));
  rig.inputs.safety_chain_closed = false;
  rig.run(200ms);
  const CommandReply r = rig.command(TravelCommand{2, std::nullopt, std::nullopt, false});
  EXPECT_EQ(r.code, ReplyCode::NotReady);
  EXPECT_EQ(r.detail, "safety chain open");
  EXPECT_TRUE(rig.controller.snapshot().faults[static_cast<std::size_t>(FaultCode::SafetyChain)]);
}

}  // namespace
}  // namespace liftd::control
