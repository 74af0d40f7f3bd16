// Faults in the middle of a travel, end to end: the real DcpController against the simulator.
// For each: B0 off within the spec's bound, the travel ended with an Aborted event naming the
// cause, the fault raised exactly once, and B0 off while the car stands afterwards.
#include <gtest/gtest.h>

#include <functional>

#include "controller_rig.hpp"

namespace liftd::control {
namespace {

using testing::CycleRecord;
using testing::enable_of;
using testing::Rig;
using namespace std::chrono_literals;

constexpr std::uint8_t kMotionBits =
    dcp::command_bit::kDriveEnable | dcp::command_bit::kTravel | dcp::command_bit::kStopSwitch;

/// The first cycle record (index) whose frame must already have B0 off, from what the rig fed.
using BoundFn = std::function<std::optional<std::size_t>(const std::vector<CycleRecord>&)>;

struct FaultCase {
  const char* legend;
  dcp::Protocol protocol;
  std::function<void(Rig&)> inject;
  BoundFn bound;
  lift::Cause cause;
  FaultCode fault;
};

std::optional<std::size_t> first_where(const std::vector<CycleRecord>& log,
                                       const std::function<bool(const CycleRecord&)>& pred) {
  for (std::size_t i = 0; i < log.size(); ++i) {
    if (pred(log[i])) return i;
  }
  return std::nullopt;
}

// DCP 9.1.6: S3 -> B0 reset: the first frame built after a reply with S3.
std::optional<std::size_t> after_s3(const std::vector<CycleRecord>& log) {
  return first_where(log, [](const CycleRecord& r) {
    return r.seen && (*r.seen & dcp::status_bit::kGeneralFault) != 0;
  });
}
// DCP 9.1.1: safety chain interrupted -> B0 off: the first frame after the input says so.
std::optional<std::size_t> after_chain(const std::vector<CycleRecord>& log) {
  return first_where(log, [](const CycleRecord& r) { return !r.inputs.safety_chain_closed; });
}
// DCP 7.3: 10 consecutive missing replies (150 ms) -> link fault: the frame after the 10th.
std::optional<std::size_t> after_ten_missing(const std::vector<CycleRecord>& log) {
  std::size_t run = 0;
  for (std::size_t i = 0; i < log.size(); ++i) {
    if (run >= 10) return i;
    run = log[i].reply ? 0 : run + 1;
  }
  return std::nullopt;
}
// DCP4 travels run on the absolute position: the first frame built without one.
std::optional<std::size_t> after_position(const std::vector<CycleRecord>& log) {
  return first_where(log, [](const CycleRecord& r) { return !r.position_valid; });
}
// ControllerConfig::inputs_timeout (500 ms): the first frame with inputs older than that.
std::optional<std::size_t> after_inputs(const std::vector<CycleRecord>& log) {
  return first_where(log, [](const CycleRecord& r) { return r.at - r.inputs_at > 500ms; });
}

class FaultMidTravel : public ::testing::TestWithParam<FaultCase> {};

TEST_P(FaultMidTravel, DropsB0EndsTravelRaisesOnce) {
  const FaultCase c = GetParam();
  Rig rig(c.protocol);
  ASSERT_TRUE(rig.warm_up());
  ASSERT_EQ(rig.command(TravelCommand{5, std::nullopt, std::nullopt, false}).code, ReplyCode::Ok);
  ASSERT_TRUE(rig.run_until([&] { return rig.sim.velocity_mps() > 1.0; }, 20s)) << c.legend;
  const std::size_t from = rig.log.size();
  ASSERT_TRUE(enable_of(rig.frames.back())) << c.legend;
  c.inject(rig);
  rig.run(3s);

  const std::vector<CycleRecord> tail(rig.log.begin() + static_cast<std::ptrdiff_t>(from),
                                      rig.log.end());
  const auto bound = c.bound(tail);
  ASSERT_TRUE(bound) << c.legend << ": the fault never showed in what the rig fed";
  EXPECT_LE(*bound, 40U) << c.legend << ": injected but fed late";
  // Before the bound the travel may still run; from it on, never B0/B1/B2 again.
  for (std::size_t i = *bound; i < tail.size(); ++i) {
    ASSERT_EQ(tail[i].frame[0] & kMotionBits, 0) << c.legend << " at cycle " << i - *bound;
  }
  const auto aborted = rig.travel_events(travel::Event::Type::Aborted);
  ASSERT_EQ(aborted.size(), 1U) << c.legend;
  EXPECT_EQ(aborted[0].cause, c.cause) << c.legend << ": " << lift::to_string(aborted[0].cause);
  EXPECT_TRUE(rig.travel_events(travel::Event::Type::Finished).empty()) << c.legend;
  EXPECT_EQ(rig.raised(c.fault), 1U) << c.legend;
  EXPECT_TRUE(rig.sim.stationary()) << c.legend;
  EXPECT_EQ(rig.controller.snapshot().travel_kind, travel::TravelKind::None) << c.legend;
  // Well away from any level: the car stopped where the fault caught it.
  EXPECT_GT(rig.sim.position_mm(), 500.0) << c.legend;
  EXPECT_LT(rig.sim.position_mm(), 14000.0) << c.legend;
}

// Faults every dialect shares.
std::vector<FaultCase> fault_cases() {
  std::vector<FaultCase> cases;
  for (dcp::Protocol p : {dcp::Protocol::Dcp4, dcp::Protocol::Dcp3}) {
    const bool d4 = p == dcp::Protocol::Dcp4;
    cases.push_back({d4 ? "DCP4 drive fault S3" : "DCP3 drive fault S3", p,
                     [](Rig& r) { r.sim.set_general_fault(true, r.now); }, after_s3,
                     lift::Cause::DriveFault, FaultCode::DriveFault});
    cases.push_back({d4 ? "DCP4 safety chain opens" : "DCP3 safety chain opens", p,
                     [](Rig& r) { r.inputs.safety_chain_closed = false; }, after_chain,
                     lift::Cause::SafetyChainOpen, FaultCode::SafetyChain});
    cases.push_back({d4 ? "DCP4 replies stop for 1 s" : "DCP3 replies stop for 1 s", p,
                     [](Rig& r) {
                       r.drop_replies = true;
                       r.run(1s);
                       r.drop_replies = false;
                     },
                     after_ten_missing, lift::Cause::LinkDown, FaultCode::LinkFault});
    cases.push_back({d4 ? "DCP4 input provider falls silent" : "DCP3 input provider silent", p,
                     [](Rig& r) { r.post_inputs = false; }, after_inputs, lift::Cause::InputsLost,
                     FaultCode::InputsLost});
  }
  cases.push_back({"DCP4 position source lost", dcp::Protocol::Dcp4,
                   [](Rig& r) { r.position.valid = false; }, after_position,
                   lift::Cause::PositionLost, FaultCode::PositionLost});
  return cases;
}

INSTANTIATE_TEST_SUITE_P(Table, FaultMidTravel, ::testing::ValuesIn(fault_cases()),
                         [](const auto& p) { return "Case" + std::to_string(p.index); });

TEST(FaultRecovery, LinkComesBackAndTravelsAgain) {
  Rig rig;
  ASSERT_TRUE(rig.warm_up());
  ASSERT_EQ(rig.command(TravelCommand{2, std::nullopt, std::nullopt, false}).code, ReplyCode::Ok);
  ASSERT_TRUE(rig.run_until([&] { return rig.sim.velocity_mps() > 1.0; }, 20s));
  rig.drop_replies = true;
  rig.run(300ms);
  rig.drop_replies = false;
  ASSERT_TRUE(rig.run_until([&] { return rig.link_up(); }, 10s));
  rig.run(200ms);
  EXPECT_FALSE(rig.controller.snapshot().faults[static_cast<std::size_t>(FaultCode::LinkFault)]);
  EXPECT_EQ(rig.events_of(ControllerEvent::Kind::FaultCleared).size(), 1U);
  const CommandReply r = rig.command(TravelCommand{0, std::nullopt, std::nullopt, false});
  ASSERT_EQ(r.code, ReplyCode::Ok) << r.detail;
  ASSERT_TRUE(rig.run_until([&] { return rig.finished_travels(1) && rig.idle(); }, 60s));
  EXPECT_NEAR(rig.sim.position_mm(), 0.0, 2.0);
}

TEST(FaultRecovery, AReopenedPortStartsNothingOnTheStatusFromBeforeTheLoss) {
  Rig rig;
  ASSERT_TRUE(rig.warm_up());
  ASSERT_TRUE(rig.link_up());
  // The serial port is lost and opened again; the drive behind it stays silent. Its last status
  // (S0 = 1) is from the old port: no travel may start on it (DCP 7.3: the link is in fault
  // until good replies come, then the handshake runs again).
  rig.controller.on_port_lost(rig.now);
  rig.controller.on_port_ready(rig.now);
  rig.drop_replies = true;
  const std::size_t before = rig.frames.size();
  const CommandReply r = rig.command(TravelCommand{2, std::nullopt, std::nullopt, false});
  EXPECT_NE(r.code, ReplyCode::Ok) << r.detail;
  rig.run(300ms);
  for (std::size_t i = before; i < rig.frames.size(); ++i) {
    EXPECT_EQ(rig.frames[i][0] & 0x01, 0) << "drive enable (B0) in frame " << i;
  }
  EXPECT_EQ(rig.raised(FaultCode::LinkFault), 1U);
}

TEST(FaultRecovery, RefusesTravelWhileS3AndNamesIt) {
  Rig rig;
  ASSERT_TRUE(rig.warm_up());
  rig.sim.set_general_fault(true, rig.now);
  rig.run(100ms);
  const CommandReply r = rig.command(TravelCommand{2, std::nullopt, std::nullopt, false});
  EXPECT_EQ(r.code, ReplyCode::Fault);
  EXPECT_EQ(r.detail, "drive general fault (S3 = 1)");
  EXPECT_EQ(rig.raised(FaultCode::DriveFault), 1U);
}

}  // namespace
}  // namespace liftd::control
