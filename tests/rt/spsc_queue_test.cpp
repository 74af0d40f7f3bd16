// SpscQueue: order, capacity limits and a two-thread handoff (run it under TSan too); HeldEvent,
// which keeps a port loss the full queue could not take.
#include "common/spsc_queue.hpp"

#include <gtest/gtest.h>

#include <cerrno>
#include <chrono>
#include <cstdint>
#include <cstring>
#include <string>
#include <thread>

#include "rt/cycle_event.hpp"
#include "rt/port_keeper.hpp"

namespace liftd::rt {
namespace {

using namespace std::chrono_literals;

TEST(RtSpscQueue, PopsInPushOrder) {
  SpscQueue<int, 4> q;
  int out = 0;
  EXPECT_FALSE(q.try_pop(out));
  EXPECT_TRUE(q.try_push(1));
  EXPECT_TRUE(q.try_push(2));
  ASSERT_TRUE(q.try_pop(out));
  EXPECT_EQ(out, 1);
  ASSERT_TRUE(q.try_pop(out));
  EXPECT_EQ(out, 2);
  EXPECT_FALSE(q.try_pop(out));
}

TEST(RtSpscQueue, RefusesPushWhenFullAndKeepsContents) {
  SpscQueue<int, 4> q;
  for (int i = 0; i < 4; ++i) EXPECT_TRUE(q.try_push(i)) << i;
  EXPECT_FALSE(q.try_push(99));
  EXPECT_EQ(q.size_approx(), 4U);
  int out = -1;
  ASSERT_TRUE(q.try_pop(out));
  EXPECT_EQ(out, 0);
  EXPECT_TRUE(q.try_push(4));  // the freed slot is usable again
  for (int expected = 1; expected <= 4; ++expected) {
    ASSERT_TRUE(q.try_pop(out));
    EXPECT_EQ(out, expected);
  }
}

TEST(RtSpscQueue, WrapsAroundManyTimes) {
  SpscQueue<std::uint32_t, 8> q;
  std::uint32_t out = 0;
  for (std::uint32_t i = 0; i < 1000; ++i) {
    ASSERT_TRUE(q.try_push(i));
    ASSERT_TRUE(q.try_push(i + 100000));
    ASSERT_TRUE(q.try_pop(out));
    EXPECT_EQ(out, i);
    ASSERT_TRUE(q.try_pop(out));
    EXPECT_EQ(out, i + 100000);
  }
}

TEST(RtSpscQueue, TwoThreadsHandOverEveryElementInOrder) {
  // A producer pushes 200k sequence numbers through a small queue; the consumer must see each
  // exactly once and in order. Under TSan this also proves the memory ordering.
  struct Item {
    std::uint64_t seq = 0;
    std::uint64_t check = 0;  // seq * 3 + 1: a torn element would not match
  };
  constexpr std::uint64_t kCount = 200000;
  SpscQueue<Item, 16> q;
  std::thread producer([&q] {
    for (std::uint64_t i = 0; i < kCount;) {
      if (q.try_push(Item{i, i * 3 + 1})) {
        ++i;
      } else {
        std::this_thread::yield();
      }
    }
  });
  std::uint64_t expected = 0;
  std::uint64_t bad = 0;
  while (expected < kCount) {
    Item item;
    if (!q.try_pop(item)) {
      std::this_thread::yield();
      continue;
    }
    if (item.seq != expected || item.check != expected * 3 + 1) ++bad;
    expected = item.seq + 1;
  }
  producer.join();
  EXPECT_EQ(bad, 0U);
  EXPECT_EQ(expected, kCount);
}

// A port loss must reach the reader even when skip-run events filled the queue first: it is
// held and offered again, and a second loss while held is counted, not dropped.
TEST(HeldEvent, APortLossBehindAFullQueueArrivesOnceThereIsRoomWithEveryLossCounted) {
  SpscQueue<CycleEvent, 2> queue;
  CycleEvent skip;
  skip.kind = CycleEventKind::SkipRunStarted;
  ASSERT_TRUE(queue.try_push(skip));
  ASSERT_TRUE(queue.try_push(skip));

  HeldEvent held;
  held.push(queue, port_lost_event(MonoTime{} + 1s, EIO));
  EXPECT_TRUE(held.held);
  held.push(queue, port_lost_event(MonoTime{} + 2s, ENXIO));
  held.retry(queue);  // still full
  EXPECT_TRUE(held.held);

  CycleEvent out;
  ASSERT_TRUE(queue.try_pop(out));
  EXPECT_EQ(out.kind, CycleEventKind::SkipRunStarted);
  held.retry(queue);
  EXPECT_FALSE(held.held);
  ASSERT_TRUE(queue.try_pop(out));
  EXPECT_EQ(out.kind, CycleEventKind::SkipRunStarted);
  ASSERT_TRUE(queue.try_pop(out));
  EXPECT_EQ(out.kind, CycleEventKind::PortLost);
  EXPECT_EQ(out.time, MonoTime{} + 1s);  // when the first loss happened
  EXPECT_EQ(out.count, 2U);
  EXPECT_EQ(out.error_number, ENXIO);  // the last one's cause
  EXPECT_EQ(describe(out), "serial port lost 2 times, the last (" +
                               std::string(std::strerror(ENXIO)) + "), reopening");
  EXPECT_FALSE(queue.try_pop(out));

  // With room, a loss goes straight through, as one.
  held.push(queue, port_lost_event(MonoTime{} + 3s, 0));
  EXPECT_FALSE(held.held);
  ASSERT_TRUE(queue.try_pop(out));
  EXPECT_EQ(out.count, 1U);
  EXPECT_EQ(describe(out), "serial port lost (hang-up), reopening");
}

}  // namespace
}  // namespace liftd::rt
