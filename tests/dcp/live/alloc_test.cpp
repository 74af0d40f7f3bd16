// No heap allocation on the cycle thread of the REAL engine (DcpController: master link, travel
// sequencer, lift model, snapshots and queues) over a real pty, during a travel. The process's
// malloc family and operator new are replaced for this test binary; calls are counted only on
// a thread that switched counting on, and the cycle thread does that after a warm-up.
#include <gtest/gtest.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <new>

#include "dcp/trace.hpp"
#include "link_judge.hpp"
#include "live_rig.hpp"

#include "support/heap_hooks.hpp"

namespace liftd::integration {
namespace {

// Forwards every call to the real controller; on the first frame after arm() it switches
// counting on for the cycle thread, and off again after disarm().
class CountingEngine final : public rt::CycleEngine {
 public:
  explicit CountingEngine(control::DcpController& inner) : inner_(inner) {}
  void arm() noexcept { wanted_.store(true); }
  void disarm() noexcept { wanted_.store(false); }
  /// Cycles fully run with counting on.
  std::uint64_t counted_cycles() const noexcept { return counted_.load(); }

  std::span<const std::uint8_t> frame_to_send(MonoTime now) noexcept override {
    heap_hooks::counting = wanted_.load(std::memory_order_relaxed);
    return inner_.frame_to_send(now);
  }
  std::size_t reply_size() const noexcept override { return inner_.reply_size(); }
  bool on_reply(std::span<const std::uint8_t> reply, MonoTime now) noexcept override {
    return inner_.on_reply(reply, now);
  }
  void on_no_reply(MonoTime now) noexcept override { inner_.on_no_reply(now); }
  void on_port_lost(MonoTime now) noexcept override { inner_.on_port_lost(now); }
  void on_port_ready(MonoTime now) noexcept override { inner_.on_port_ready(now); }
  void after_cycle(MonoTime now) noexcept override {
    inner_.after_cycle(now);
    if (heap_hooks::counting) counted_.fetch_add(1, std::memory_order_relaxed);
  }

 private:
  control::DcpController& inner_;
  std::atomic<bool> wanted_{false};
  std::atomic<std::uint64_t> counted_{0};
};

TEST(LiveAlloc, RealEngineCycleAllocatesNothingDuringATravel) {
  if (!LIFTD_HEAP_HOOKS) GTEST_SKIP() << "allocation hooks are off under sanitizers";
  ASSERT_TRUE(heap_hooks::counts_allocations()) << "the hooks must see an allocation";

  io::PtyPair pty = make_pty();
  auto drive = serve(pty.master_fd(), control::testing::sim_config(dcp::Protocol::Dcp4));
  std::unique_ptr<CountingEngine> counting;
  LiveMaster m(pty.slave_path(), control::testing::default_config(dcp::Protocol::Dcp4),
               [&](control::DcpController& c) -> rt::CycleEngine& {
                 counting = std::make_unique<CountingEngine>(c);
                 return *counting;
               });
  m.position.attach(drive.get());
  liftd::testing::ReferenceLink reference;
  ASSERT_EQ(start_reference(reference), 0);
  ASSERT_EQ(m.start(), 0);
  // A travel to `floor` that finishes. One that a link fault ended while the reference link
  // missed as many replies in a row (the machine held up every pty: DCP 7.3's ten frames, the
  // reference at another phase may see two fewer) is the machine's: once ready, asked again,
  // at most twice.
  const auto travel_to = [&](std::uint8_t floor) -> ::testing::AssertionResult {
    for (int attempt = 1;; ++attempt) {
      const std::size_t finished = m.travel_events(travel::Event::Type::Finished);
      const std::size_t aborted = m.travel_events(travel::Event::Type::Aborted);
      const MonoTime from = mono_now();
      const auto r = m.command(control::TravelCommand{floor, dcp::Speed::V4, std::nullopt, false});
      if (r.code != control::ReplyCode::Ok) return ::testing::AssertionFailure() << r.detail;
      if (!m.wait_until(
              [&] {
                return m.idle() && (m.travel_events(travel::Event::Type::Finished) > finished ||
                                    m.travel_events(travel::Event::Type::Aborted) > aborted);
              },
              30000ms)) {
        return ::testing::AssertionFailure() << "the travel to " << int{floor} << " never ended";
      }
      if (m.travel_events(travel::Event::Type::Finished) > finished) {
        return ::testing::AssertionSuccess();
      }
      const std::uint64_t stall = reference.longest_miss_run_during(from, mono_now());
      if (stall < liftd::testing::kDriveStallRun || attempt == 3) {
        return ::testing::AssertionFailure() << "the travel to " << int{floor}
                                             << " was aborted; the reference link missed at most "
                                             << stall << " in a row meanwhile\n"
                                             << tail_of_trace(m.runner, 60);
      }
      std::printf(
          "[ info     ] travel to %d aborted while the reference link missed %llu in a row; "
          "again\n",
          int{floor}, static_cast<unsigned long long>(stall));
      const auto ready = ready_within(m, reference, 10000ms);
      if (!ready) return ready;
    }
  };
  // Warm-up: handshake, first travel (first use of every path), a link command.
  ASSERT_TRUE(ready_within(m, reference, 5000ms));
  m.run_for(300ms);
  ASSERT_TRUE(travel_to(1));
  m.run_for(300ms);

  // Counted: a few hundred cycles with a travel 1 -> 2, commands and inputs arriving.
  counting->arm();
  ASSERT_TRUE(m.wait_until([&] { return counting->counted_cycles() >= 20; }, 2000ms));
  ASSERT_TRUE(travel_to(2));
  // A link command. A reply the machine held up past its deadline takes the answer's channel
  // bytes with it (DCP 5.1) and the request times out: asked again, at most twice, and only
  // with a lost reply to explain each time-out.
  const std::uint64_t missing_before = m.controller.snapshot().link_counters.missing_replies;
  auto link_cmd = m.command(control::LinkCommand{dcp::LoadRequest{55}});
  for (int again = 0; again < 2 && link_cmd.code == control::ReplyCode::Timeout; ++again) {
    ASSERT_GT(m.controller.snapshot().link_counters.missing_replies, missing_before)
        << "a link command timed out without a lost reply";
    link_cmd = m.command(control::LinkCommand{dcp::LoadRequest{55}});
  }
  EXPECT_EQ(link_cmd.code, control::ReplyCode::Ok) << link_cmd.detail;
  m.run_for(300ms);
  counting->disarm();
  m.run_for(100ms);
  const std::uint64_t cycles = counting->counted_cycles();
  const std::uint64_t calls = heap_hooks::calls();
  m.runner.stop();
  m.position.attach(nullptr);

  EXPECT_NEAR(drive->position_mm(), 6000.0, 2.0);
  EXPECT_GE(cycles, 300U);
  EXPECT_EQ(calls, 0U) << "heap calls on the cycle thread in " << cycles << " cycles";
  std::printf("[ info     ] %llu cycles counted, %llu heap calls on the cycle thread\n",
              static_cast<unsigned long long>(cycles), static_cast<unsigned long long>(calls));
}

TEST(LiveAlloc, TraceFormattingAllocatesNothing) {
  if (!LIFTD_HEAP_HOOKS) GTEST_SKIP() << "allocation hooks are off under sanitizers";
  // Legend: a master travel frame, a drive frame with extended status, a corrupt one, a short
  // one: the decoder core writes into the caller's buffer only.
  const std::array<std::array<std::uint8_t, 6>, 3> frames = {{
      {0x17, 0x0B, 0xB7, 0x02, 0x1C, 0x17 ^ 0x0B ^ 0xB7 ^ 0x02 ^ 0x1C},
      {0x11, 0x80, 0x07, 0x00, 0x00, 0x11 ^ 0x80 ^ 0x07},
      {0x43, 0x05, 0x96, '0', '4', 0x00},
  }};
  dcp::TraceBuffer buffer;
  std::size_t written = 0;
  heap_hooks::reset();
  heap_hooks::counting = true;
  for (const auto& f : frames) {
    written += dcp::format_frame(f, dcp::FrameSide::Master, {}, buffer).size();
    written += dcp::format_frame(f, dcp::FrameSide::Drive, {}, buffer).size();
  }
  written +=
      dcp::format_frame(std::span(frames[0]).first(3), dcp::FrameSide::Drive, {}, buffer).size();
  heap_hooks::counting = false;
  EXPECT_GT(written, 100U);
  EXPECT_EQ(heap_hooks::calls(), 0U);
}

}  // namespace
}  // namespace liftd::integration
