// Cross-check of two independent readings of the spec: the daemon's DCP master engine
// (lib/dcp/master_link) against the simulated drive, frame by frame on a fake clock.
// The simulator does not use the master's code; this test only wires the two together.
#include <gtest/gtest.h>

#include <cmath>

#include "dcp/master_link.hpp"
#include "dcp/sim/drive_sim.hpp"

namespace liftd::dcp::sim {
namespace {

using namespace std::chrono_literals;

struct Loop {
  explicit Loop(dcp::MasterLinkConfig mc = {}, DriveConfig dc = {}) : master(mc), drive(dc, now) {}

  // One 15 ms cycle: master frame -> drive -> reply -> master.
  void cycle() {
    now += 15ms;  // DCP 7.2
    const dcp::FrameBytes f = master.next_frame(now);
    const Reply r = drive.on_master_frame(f, now);
    if (r.size == dcp::kFrameSize) {
      master.on_reply(std::span<const std::uint8_t, 6>(r.bytes.data(), 6), now + 3ms);
    } else {
      master.on_no_reply(now + 14ms);
    }
  }
  void run(int n) {
    for (int i = 0; i < n; ++i) cycle();
  }

  MonoTime now{};
  dcp::MasterLink master;
  DriveSim drive;
};

TEST(SimInterop, MasterLinkComesUpAgainstTheSimulatedDrive) {
  dcp::MasterLinkConfig mc;
  mc.data_info_type = dcp::DataInfoType::Decel15;
  mc.extended_position = true;
  Loop loop(mc);
  loop.run(300);
  EXPECT_EQ(loop.master.state(), dcp::LinkState::Up);
  ASSERT_TRUE(loop.master.protocol().has_value());
  EXPECT_EQ(*loop.master.protocol(), dcp::Protocol::Dcp4);
  ASSERT_TRUE(loop.master.drive_info().has_value());
  EXPECT_EQ(loop.master.drive_info()->maker, (dcp::Code2{'K', 'W'}));
  EXPECT_EQ(loop.master.active_data_info_type(), dcp::DataInfoType::Decel15);
  EXPECT_TRUE(loop.master.extended_position_active());
  EXPECT_TRUE(loop.drive.initialised());
  EXPECT_EQ(loop.drive.data_info_type(), dcp::DataInfoType::Decel15);
}

TEST(SimInterop, I7ThroughTheMasterGivesTheSpecExample) {
  Loop loop;
  loop.run(300);
  ASSERT_EQ(loop.master.state(), dcp::LinkState::Up);
  ASSERT_EQ(loop.master.submit(dcp::StartParamsRequest{dcp::MaxSpeed::V4, 300}, 7),
            dcp::SubmitResult::Accepted);
  std::optional<dcp::Completion> done;
  for (int i = 0; i < 100 && !done; ++i) {
    loop.cycle();
    done = loop.master.pop_completion();
  }
  ASSERT_TRUE(done.has_value());
  EXPECT_EQ(done->result, dcp::RequestResult::Ok);
  ASSERT_TRUE(done->reply.has_value());
  const auto* r = std::get_if<dcp::StartParamsReply>(&*done->reply);
  ASSERT_NE(r, nullptr);
  EXPECT_EQ(*r, (dcp::StartParamsReply{dcp::TravelKind::Short, 300, 143}));
}

TEST(SimInterop, Dcp4TravelThroughTheMasterLands) {
  Loop loop;
  loop.run(300);
  ASSERT_TRUE(loop.master.travel_allowed());
  loop.master.set_process(0x09, dcp::speed_word(dcp::Speed::V4));  // speed message
  loop.cycle();
  bool moved = false;
  for (int i = 0; i < 2000; ++i) {
    const double rd = std::max(0.0, 6000.0 - loop.drive.position_mm());
    loop.master.set_process(
        0x05, dcp::remaining_distance_word(std::llround(rd), dcp::DistanceWidth::Bits15));
    loop.cycle();
    const auto s = loop.drive.status_byte();
    moved |= (s & dcp::status_bit::kBrakeOpen) != 0;
    if (moved && (s & dcp::status_bit::kBrakeOpen) == 0) break;
  }
  loop.master.set_process(0x01, 0);
  loop.run(20);
  // The master's position is one cycle old when it builds the frame; the drive ignores that
  // lag (within its tolerance) and lands on the target it took at the start.
  EXPECT_NEAR(loop.drive.position_mm(), 6000.0, 1.0);
  EXPECT_EQ(loop.master.state(), dcp::LinkState::Up);
  const auto c = loop.master.counters();
  EXPECT_EQ(c.bad_checksum + c.missing_replies + c.decode_errors + c.data_word_errors, 0U);
}

}  // namespace
}  // namespace liftd::dcp::sim
