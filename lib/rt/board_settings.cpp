#include "rt/board_settings.hpp"

#include <algorithm>
#include <fstream>

#include "common/cpu_set.hpp"

namespace liftd::rt {
namespace {

std::optional<std::string> first_line(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  if (!in || !std::getline(in, line)) return std::nullopt;
  while (!line.empty() && (line.back() == ' ' || line.back() == '\n')) line.pop_back();
  return line;
}

int hex_digit(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

}  // namespace

BoardFacts BoardFacts::current(int rt_cpu) {
  BoardFacts facts;
  facts.usable_cpus = current_cpus();
  facts.workqueue_mask = first_line("/sys/devices/virtual/workqueue/cpumask");
  facts.cpuidle_driver = first_line("/sys/devices/system/cpu/cpuidle/current_driver");
  if (rt_cpu >= 0) {
    facts.rt_cpu_resume_latency = first_line(
        "/sys/devices/system/cpu/cpu" + std::to_string(rt_cpu) + "/power/pm_qos_resume_latency_us");
  }
  return facts;
}

std::optional<std::vector<int>> parse_cpumask(const std::string& text) {
  // Read from the right: the last hexadecimal digit is CPUs 0-3; commas only separate words.
  std::vector<int> cpus;
  int bit = 0;
  bool any_digit = false;
  for (auto it = text.rbegin(); it != text.rend(); ++it) {
    if (*it == ',') continue;
    const int value = hex_digit(*it);
    if (value < 0) return std::nullopt;
    any_digit = true;
    for (int i = 0; i < 4; ++i) {
      if ((value >> i) & 1) cpus.push_back(bit + i);
    }
    bit += 4;
  }
  if (!any_digit) return std::nullopt;
  std::sort(cpus.begin(), cpus.end());
  return cpus;
}

std::vector<std::string> missing_board_settings(int rt_cpu, const BoardFacts& facts) {
  std::vector<std::string> missing;
  if (facts.usable_cpus.size() < 2) return missing;
  const std::string cpu = std::to_string(rt_cpu);
  if (rt_cpu < 0) {
    missing.push_back(
        "rt.cpu is not set: the real-time threads share every CPU with the rest of the machine");
    return missing;  // the other settings are about that CPU
  }
  if (facts.workqueue_mask) {
    const auto workqueue = parse_cpumask(*facts.workqueue_mask);
    if (workqueue && *workqueue != std::vector<int>{rt_cpu}) {
      missing.push_back(
          "the unbound workqueue (the tty's flip-buffer worker, which carries every "
          "received byte) runs on CPU(s) " +
          cpu_list_text(*workqueue) + ", not only on rt.cpu " + cpu);
    }
  }
  const bool has_idle_states =
      facts.cpuidle_driver && !facts.cpuidle_driver->empty() && *facts.cpuidle_driver != "none";
  if (has_idle_states && facts.rt_cpu_resume_latency && *facts.rt_cpu_resume_latency != "n/a") {
    missing.push_back("CPU " + cpu + " may enter idle states that take time to leave " +
                      "(pm_qos_resume_latency_us is " + *facts.rt_cpu_resume_latency +
                      ", not n/a)");
  }
  return missing;
}

}  // namespace liftd::rt
