// The cycle path allocates nothing: operator new is counted while TravelController::step and
// pop_event run through whole travels (docs/architecture.md: no allocation inside the 15 ms cycle).
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <new>

#include "fake_drive.hpp"

namespace {
std::atomic<bool> g_counting{false};
std::atomic<int> g_allocations{0};
}  // namespace

// GCC flags free() inside a replaced operator delete as a mismatch; it pairs with malloc above.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
#endif
void* operator new(std::size_t size) {
  if (g_counting.load()) g_allocations.fetch_add(1);
  void* p = std::malloc(size == 0 ? 1 : size);
  if (p == nullptr) throw std::bad_alloc();
  return p;
}
void operator delete(void* p) noexcept {
  std::free(p);
}
void operator delete(void* p, std::size_t) noexcept {
  std::free(p);
}

namespace liftd::travel::test {
namespace {

TEST(CyclePath, AllocatesNothingThroughWholeTravels) {
  // The counter itself works (a std::string too long for the small-string buffer).
  g_counting = true;
  std::string probe(100, 'x');
  g_counting = false;
  ASSERT_EQ(g_allocations.load(), 1) << probe.size();
  g_allocations = 0;
  TravelConfig config;
  TravelController controller(config);
  FakeDrive drive(dcp::Protocol::Dcp4);
  CycleInput in;
  in.link_up = in.handshake_done = in.reply_fresh = true;
  in.protocol = dcp::Protocol::Dcp4;
  in.inputs.valid = in.inputs.safety_chain_closed = true;
  in.inputs.doors_closed = in.inputs.doors_locked = true;
  std::optional<ChannelReply> reply;
  int events = 0;
  auto cycle = [&] {
    in.now += kCycle;
    in.status = drive.status();
    in.decel_distance_mm = drive.decel_distance_mm();
    in.position_mm = std::llround(drive.position_mm());
    in.channel_reply = reply;
    reply.reset();
    g_counting = true;
    const CycleOutput out = controller.step(in);
    while (controller.pop_event()) ++events;
    g_counting = false;
    if (out.channel_request) {
      ChannelReply r;
      r.kind = out.channel_request->kind;
      r.decel_distance_cm = 250;
      reply = r;
    }
    drive.on_frame(out.command, out.data_word);
  };
  cycle();
  TravelRequest request;
  request.target_mm = 12000;
  request.load_percent = 30;
  ASSERT_EQ(controller.start(request), StartResult::Accepted);
  for (int i = 0; i < 300; ++i) cycle();
  EXPECT_EQ(controller.extend_target(16000), ExtendResult::Pending);
  for (int i = 0;
       i < 3000 && (controller.active_kind() != TravelKind::None || drive.status().travel_active);
       ++i) {
    cycle();
  }
  in.inputs.inspection = true;  // then an inspection travel
  in.inputs.button_down = true;
  for (int i = 0; i < 200; ++i) cycle();
  in.inputs.button_down = false;
  for (int i = 0; i < 50; ++i) cycle();
  EXPECT_GE(events, 4);
  EXPECT_EQ(g_allocations.load(), 0);
}

}  // namespace
}  // namespace liftd::travel::test
