// RtThread: real-time start where allowed, fallback with a reason where refused.
#include "rt/rt_thread.hpp"

#include <gtest/gtest.h>
#include <pthread.h>
#include <sched.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <string>

namespace liftd::rt {
namespace {

int policy_of_running_thread() {
  int policy = -1;
  sched_param p{};
  pthread_getschedparam(pthread_self(), &policy, &p);
  return policy;
}

TEST(RtThread, RunsBodyWithTheSchedulingItReports) {
  RtThreadOptions o;
  o.priority = 10;
  o.lock_memory = false;
  std::atomic<int> policy{-1};
  RtThread t;
  ASSERT_EQ(t.start(o, [&] { policy = policy_of_running_thread(); }), 0);
  t.join();
  // Whether SCHED_FIFO is permitted depends on the machine; the report must match reality.
  if (t.status().realtime) {
    EXPECT_EQ(policy.load(), SCHED_FIFO);
  } else {
    EXPECT_EQ(policy.load(), SCHED_OTHER);
    EXPECT_NE(t.status().sched_errno, 0);
    EXPECT_NE(t.status().describe().find("SCHED_FIFO refused"), std::string::npos);
  }
}

// The name is there when start() returns, whether or not the thread has run yet: the daemon
// says it is ready right after starting its loops, and ps -L or a test may look at once.
TEST(RtThread, IsNamedWhenStartReturns) {
  RtThreadOptions o;
  o.priority = 0;
  o.lock_memory = false;
  o.name = "rt-name-test-long";  // the kernel keeps the first 15 characters
  std::atomic<bool> release{false};
  RtThread t;
  ASSERT_EQ(t.start(o,
                    [&] {
                      while (!release.load()) sched_yield();
                    }),
            0);
  int named = 0;
  for (const auto& task : std::filesystem::directory_iterator("/proc/self/task")) {
    std::string comm;
    std::getline(std::ifstream(task.path() / "comm"), comm);
    if (comm == "rt-name-test-lo") ++named;
  }
  release = true;
  t.join();
  EXPECT_EQ(named, 1);
}

TEST(RtThread, FallsBackToNormalSchedulingWhenThePriorityIsRefused) {
  RtThreadOptions o;
  o.priority = 1000;  // outside SCHED_FIFO's 1..99: refused like EPERM would be
  o.lock_memory = false;
  std::atomic<int> policy{-1};
  RtThread t;
  ASSERT_EQ(t.start(o, [&] { policy = policy_of_running_thread(); }), 0);
  t.join();
  EXPECT_FALSE(t.status().realtime);
  EXPECT_EQ(t.status().sched_errno, EINVAL);
  EXPECT_EQ(policy.load(), SCHED_OTHER);
  EXPECT_NE(t.status().describe().find("SCHED_FIFO refused (EINVAL"), std::string::npos);
}

TEST(RtThread, PriorityZeroMeansNormalSchedulingWithoutComplaint) {
  RtThreadOptions o;
  o.priority = 0;
  o.lock_memory = false;
  RtThread t;
  ASSERT_EQ(t.start(o, [] {}), 0);
  t.join();
  EXPECT_FALSE(t.status().realtime);
  EXPECT_EQ(t.status().sched_errno, 0);
}

TEST(RtThread, ImpossibleCpuIsReportedNotFatal) {
  RtThreadOptions o;
  o.priority = 0;
  o.cpu = CPU_SETSIZE - 1;  // no machine here has that many CPUs
  o.lock_memory = false;
  std::atomic<bool> ran{false};
  RtThread t;
  ASSERT_EQ(t.start(o, [&] { ran = true; }), 0);
  t.join();
  EXPECT_TRUE(ran.load());
  EXPECT_FALSE(t.status().pinned);
  EXPECT_NE(t.status().affinity_errno, 0);
}

}  // namespace
}  // namespace liftd::rt
