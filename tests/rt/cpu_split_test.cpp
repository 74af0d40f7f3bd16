// Where the normal threads go when the real-time threads own rt.cpu, and the CPU lists the
// journal and the configuration errors print.
#include "rt/cpu_split.hpp"

#include <gtest/gtest.h>
#include <sched.h>

#include <string>
#include <thread>
#include <vector>

#include "common/cpu_set.hpp"
#include "rt/rt_thread.hpp"

namespace liftd::rt {
namespace {

struct SplitCase {
  std::vector<int> usable;
  int rt_cpu;
  std::vector<int> normal;  // empty: the normal threads keep the process's CPUs
};

TEST(CpuSplit, NormalThreadsGetEveryUsableCpuButTheRealTimeOne) {
  const SplitCase cases[] = {
      {{0, 1}, 1, {0}},
      {{0, 1}, 0, {1}},
      {{0, 1, 2, 3}, 3, {0, 1, 2}},
      {{2, 5, 7}, 5, {2, 7}},  // a unit's CPUAffinity= with gaps
      {{0, 1}, -1, {}},        // no pinning: nothing moves
      {{0}, 0, {}},            // one CPU: the normal threads share it
      {{0, 1}, 4, {}},         // rt.cpu not usable (the configuration check refuses it)
      {{}, 0, {}},             // affinity unreadable
  };
  for (const SplitCase& c : cases) {
    EXPECT_EQ(normal_thread_cpus(c.usable, c.rt_cpu), c.normal)
        << "usable " << cpu_list_text(c.usable) << ", rt.cpu " << c.rt_cpu;
  }
}

TEST(CpuSplit, ListsCpusAsTheKernelWritesThem) {
  const std::pair<std::vector<int>, std::string> cases[] = {
      {{}, ""},
      {{0}, "0"},
      {{0, 1}, "0-1"},
      {{0, 2}, "0,2"},
      {{0, 1, 2, 3, 6}, "0-3,6"},
      {{1, 3, 4, 5, 9, 10}, "1,3-5,9-10"},
  };
  for (const auto& [cpus, text] : cases) EXPECT_EQ(cpu_list_text(cpus), text);
}

// On the machine itself, in a thread of its own so that the test process keeps its mask: the
// calling thread moves off rt.cpu, a thread it starts inherits that, and a real-time thread
// pinned to rt.cpu still runs there.
TEST(CpuSplit, MovesTheCallerOffTheRealTimeCpuAndLetsTheLoopsPinThemselves) {
  const std::vector<int> usable = current_cpus();
  if (usable.size() < 2) GTEST_SKIP() << "one usable CPU: there is nothing to split";
  const int rt_cpu = usable.back();
  std::thread([&] {
    const CpuSplit split = keep_normal_threads_off(rt_cpu);
    ASSERT_EQ(split.error, 0);
    EXPECT_EQ(split.normal_cpus, normal_thread_cpus(usable, rt_cpu));
    EXPECT_EQ(current_cpus(), split.normal_cpus);
    std::vector<int> inherited;
    std::thread([&] { inherited = current_cpus(); }).join();
    EXPECT_EQ(inherited, split.normal_cpus);

    RtThread loop;
    RtThreadOptions options;
    options.priority = 0;  // normal scheduling: the pinning alone is under test
    options.cpu = rt_cpu;
    options.lock_memory = false;
    options.stack_prefault_bytes = 0;
    std::vector<int> pinned;
    ASSERT_EQ(loop.start(options, [&] { pinned = current_cpus(); }), 0);
    loop.join();
    EXPECT_TRUE(loop.status().pinned);
    EXPECT_EQ(pinned, std::vector<int>{rt_cpu});
  }).join();
  EXPECT_EQ(current_cpus(), usable) << "the test's own thread keeps its CPUs";
}

}  // namespace
}  // namespace liftd::rt
