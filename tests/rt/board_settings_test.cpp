// The board settings liftd checks at the start (docs/operations.md, "Real-time settings of a
// board"), from the kernel's texts.
#include "rt/board_settings.hpp"

#include <gtest/gtest.h>

#include <optional>
#include <string>
#include <vector>

namespace liftd::rt {
namespace {

TEST(BoardSettings, ParsesTheKernelsHexadecimalCpuMasks) {
  const std::pair<std::string, std::optional<std::vector<int>>> cases[] = {
      {"3", std::vector<int>{0, 1}},
      {"2", std::vector<int>{1}},
      {"f0", std::vector<int>{4, 5, 6, 7}},
      {"0", std::vector<int>{}},
      {"1,00000000", std::vector<int>{32}},
      {"ff,ffffffff",
       [] {
         std::vector<int> all;
         for (int cpu = 0; cpu < 40; ++cpu) all.push_back(cpu);
         return all;
       }()},
      {"A", std::vector<int>{1, 3}},
      {"", std::nullopt},
      {",", std::nullopt},
      {"3x", std::nullopt},
      {"-1", std::nullopt},
  };
  for (const auto& [text, cpus] : cases) EXPECT_EQ(parse_cpumask(text), cpus) << "'" << text << "'";
}

struct Case {
  const char* what;
  int rt_cpu;
  BoardFacts facts;
  std::vector<std::string> missing;
};

TEST(BoardSettings, NamesEachMissingSettingOnce) {
  const std::string not_pinned =
      "rt.cpu is not set: the real-time threads share every CPU with the rest of the machine";
  const std::string workqueue_on_both =
      "the unbound workqueue (the tty's flip-buffer worker, which carries every received byte) "
      "runs on CPU(s) 0-1, not only on rt.cpu 1";
  const std::string idle_states =
      "CPU 1 may enter idle states that take time to leave (pm_qos_resume_latency_us is 0, not "
      "n/a)";
  const Case cases[] = {
      {"a tuned board", 1, {{0, 1}, "2", "psci_idle", "n/a"}, {}},
      {"a tuned board without a cpuidle driver", 1, {{0, 1}, "2", "none", "0"}, {}},
      {"one CPU: nothing to split", -1, {{0}, "1", "none", std::nullopt}, {}},
      {"not pinned", -1, {{0, 1}, "3", "psci_idle", std::nullopt}, {not_pinned}},
      {"workqueue everywhere", 1, {{0, 1}, "3", "none", "0"}, {workqueue_on_both}},
      {"deep idle allowed", 1, {{0, 1}, "2", "psci_idle", "0"}, {idle_states}},
      {"both", 1, {{0, 1}, "3", "intel_idle", "0"}, {workqueue_on_both, idle_states}},
      {"sysfs unreadable: nothing claimed",
       1,
       {{0, 1}, std::nullopt, std::nullopt, std::nullopt},
       {}},
      {"an unreadable mask text: nothing claimed", 1, {{0, 1}, "zz", "none", "0"}, {}},
  };
  for (const Case& c : cases) {
    EXPECT_EQ(missing_board_settings(c.rt_cpu, c.facts), c.missing) << c.what;
  }
}

}  // namespace
}  // namespace liftd::rt
