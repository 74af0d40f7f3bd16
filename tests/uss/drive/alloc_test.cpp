// The USS controller's step runs on the bus thread after every exchange: it must not allocate
// (the real-time rules of docs/architecture.md). Counts heap calls made inside
// UssController::after_exchange() while the controller is warm: travels up and down, a
// parameter read, a mirror, the safety chain opening mid-travel, a drive fault and its
// acknowledge, a silent drive (link fault and recovery), calls, inspection, relevelling.
// heap_hooks.hpp replaces malloc for the whole binary: this file is alone in its executable.
#include <gtest/gtest.h>

#include "support/heap_hooks.hpp"
#include "uss/drive/bus.hpp"

namespace liftd::uss {
namespace {

using namespace test;

class CountedBus {
 public:
  CountedBus() {
    bus.around_step = [](bool entering) { heap_hooks::counting = entering; };
  }
  ~CountedBus() { heap_hooks::counting = false; }

  Bus bus;
};

bool replied(const Bus& bus, std::uint32_t tag) {
  return std::any_of(bus.replies.begin(), bus.replies.end(),
                     [tag](const CommandReply& r) { return r.tag == tag; });
}

TEST(UssControllerAlloc, TheStepAllocatesNothingThroughTravelsFaultsAndParameters) {
  if (!LIFTD_HEAP_HOOKS) GTEST_SKIP() << "allocation hooks are off under the sanitizers";
  CountedBus counted;
  Bus& bus = counted.bus;
  // Warm-up (the Bus ran 10 exchanges) and one whole travel, then count from zero.
  ASSERT_EQ(bus.command(1, TravelCommand{1, SpeedName::V4}).code, ReplyCode::Ok);
  ASSERT_TRUE(bus.run_until([&] { return bus.idle(); }));
  heap_hooks::reset();

  ASSERT_EQ(bus.command(2, TravelCommand{3, SpeedName::V4}).code, ReplyCode::Ok);
  ASSERT_TRUE(bus.run_until([&] { return bus.idle(); }));
  ASSERT_EQ(bus.command(3, TravelCommand{0, SpeedName::V3}).code, ReplyCode::Ok);
  ASSERT_TRUE(bus.run_until([&] { return bus.idle(); }));

  ParameterCommand read;
  read.address = kDrive;
  read.request.id = 1;  // C 4.2.1.1: request parameter value
  read.request.pnu = kParameter;
  bus.post(4, read);
  ASSERT_TRUE(bus.run_until([&] { return replied(bus, 4); }, 200));
  bus.post(5, MirrorCommand{kDrive});
  ASSERT_TRUE(bus.run_until([&] { return replied(bus, 5); }, 200));

  // The safety chain opens mid-travel (OFF2), then closes again.
  bus.post(6, TravelCommand{2, SpeedName::V4});
  ASSERT_TRUE(bus.run_until([&] { return bus.car.position_mm > 1500.0; }));
  bus.inputs.safety_chain_closed = false;
  for (int i = 0; i < 5; ++i) bus.exchange();
  bus.inputs.safety_chain_closed = true;
  ASSERT_TRUE(bus.run_until([&] { return bus.stw_sent.back() == 0x047E; }, 2000));

  // A drive fault, acknowledged on a rising edge.
  bus.post(7, TravelCommand{0, SpeedName::V4});
  ASSERT_TRUE(bus.run_until([&] { return !bus.idle(); }, 500));
  bus.drive.trip();
  for (int i = 0; i < 3; ++i) bus.exchange();
  bus.drive.clear_fault_cause();
  bus.post(8, DriveResetCommand{});
  for (int i = 0; i < 10; ++i) bus.exchange();

  // A silent drive: the link faults, then comes back.
  bus.drive_answers = false;
  for (int i = 0; i < 5; ++i) bus.exchange();
  bus.drive_answers = true;
  ASSERT_TRUE(bus.run_until([&] { return bus.stw_sent.back() == 0x047E; }, 2000));

  // Calls served in order, inspection hold-to-run, relevelling.
  bus.post(9, CallCommand::adding(0));
  bus.post(10, CallCommand::adding(2));
  ASSERT_TRUE(bus.run_until([&] { return bus.idle() && bus.controller.snapshot().floor == 2U; }));
  for (int i = 0; i < 60; ++i) {
    if (i % 20 == 0) bus.post(0, InspectionCommand{true, lift::Direction::Down});
    bus.exchange();
  }
  bus.post(11, InspectionCommand{false, lift::Direction::None});
  ASSERT_TRUE(bus.run_until([&] { return bus.idle(); }, 2000));
  bus.post(12, RelevelCommand{});
  ASSERT_TRUE(bus.run_until([&] { return replied(bus, 12) && bus.idle(); }, 5000));

  EXPECT_GT(bus.travel_events().size(), 8U) << "the scenario ran its travels";
  EXPECT_EQ(heap_hooks::mallocs.load(), 0U);
  EXPECT_EQ(heap_hooks::news.load(), 0U);
}

}  // namespace
}  // namespace liftd::uss
