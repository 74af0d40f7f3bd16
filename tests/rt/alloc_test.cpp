// No allocation inside the cycle: malloc and operator new are hooked for the whole test
// binary and count calls made on the cycle thread while counting is switched on.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <new>
#include <thread>

#include "echo_engine.hpp"
#include "fake_responder.hpp"
#include "io/pty.hpp"
#include "pty_device.hpp"
#include "rt/cycle_runner.hpp"

#include "support/heap_hooks.hpp"

namespace liftd::rt {
namespace {

using std::chrono::milliseconds;

// Switches counting on for the cycle thread after a warm-up; the flag then stays on for every
// later cycle, including cycles without a port.
class CountingEngine : public testing::EchoEngine {
 public:
  explicit CountingEngine(std::uint64_t warm_up) : warm_up_(warm_up) {}
  std::span<const std::uint8_t> frame_to_send(MonoTime now) noexcept override {
    if (++frames_ == warm_up_) {
      heap_hooks::counting = true;
      counting_.store(true);
    }
    if (heap_hooks::counting) counted_frames_.fetch_add(1, std::memory_order_relaxed);
    return EchoEngine::frame_to_send(now);
  }
  std::atomic<bool> counting_{false};
  std::atomic<std::uint64_t> counted_frames_{0};

 private:
  std::uint64_t warm_up_;
  std::uint64_t frames_ = 0;
};

TEST(RtCycleAlloc, NoAllocationOnTheCycleThreadAfterWarmUpNorAfterDeviceLoss) {
  if (!LIFTD_HEAP_HOOKS) GTEST_SKIP() << "allocation hooks are off under sanitizers";
  ASSERT_TRUE(heap_hooks::counts_allocations()) << "the hooks must see an allocation";

  auto pty = io::PtyPair::create();
  ASSERT_TRUE(pty.ok());
  testing::FakeResponder responder(pty.value().master_fd(), std::chrono::microseconds(1500));
  ASSERT_EQ(responder.start(), 0);
  // The runner opens the pty through a name of this test's own: once the pty is gone, its
  // /dev/pts number is free for the next pty any other test on the machine creates, and a
  // runner retrying that number would find a device again (a second "loss" that is not this
  // test's). The name points nowhere before the pty goes, so every retry fails as it should.
  testing::DeviceLink device;
  device.point_to(pty.value().slave_path());
  CountingEngine engine(50);
  CycleConfig config;
  config.device_path = device.path();
  config.thread.priority = 20;
  config.thread.lock_memory = false;
  // The spec's largest send window (DCP 7.2: 1.375 ms, the default): late wake-ups on a busy
  // machine still send, and a skipped cycle allocates nothing either.
  CycleRunner runner(config, engine);
  ASSERT_EQ(runner.start(), 0);
  // 300 counted cycles of normal traffic (statistics, recorder, snapshots of stats read from
  // this thread meanwhile).
  ASSERT_TRUE([&] {
    for (int i = 0; i < 2000 && engine.counted_frames_.load() < 300; ++i) {
      (void)runner.stats();
      (void)runner.recorder().copy();
      std::this_thread::sleep_for(milliseconds(5));
    }
    return engine.counted_frames_.load() >= 300;
  }());
  EXPECT_EQ(heap_hooks::mallocs.load(), 0U) << "malloc calls on the cycle thread";
  EXPECT_EQ(heap_hooks::news.load(), 0U) << "operator new calls on the cycle thread";

  // Device loss: the loss path and the cycles without a port must not allocate either.
  device.point_to(device.path() + ".absent");
  responder.stop();
  pty.value().close();
  // Waits for the loss, then for 20 more cycles without a port (the retry path), however long
  // a loaded machine takes for them.
  using testing::wait_for;
  ASSERT_TRUE(
      wait_for([&] { return runner.stats().counters.port_losses >= 1; }, milliseconds(10000)));
  const auto periods = [&] {
    const CycleCounters c = runner.stats().counters;
    return c.cycles + c.skipped_cycles;  // run or skipped: each a pass of the loss path
  };
  const std::uint64_t at_loss = periods();
  ASSERT_TRUE(wait_for([&] { return periods() >= at_loss + 20; }, milliseconds(10000)))
      << "the cycle goes on without its port";
  EXPECT_EQ(runner.stats().counters.port_losses, 1U);
  const std::uint64_t mallocs = heap_hooks::mallocs.load();
  const std::uint64_t news = heap_hooks::news.load();
  runner.stop();
  EXPECT_EQ(mallocs, 0U);
  EXPECT_EQ(news, 0U);
  EXPECT_TRUE(engine.counting_.load());
}

}  // namespace
}  // namespace liftd::rt
