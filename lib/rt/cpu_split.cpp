#include "rt/cpu_split.hpp"

#include <sched.h>

#include <algorithm>
#include <cerrno>

#include "common/cpu_set.hpp"

namespace liftd::rt {

std::vector<int> normal_thread_cpus(const std::vector<int>& usable, int rt_cpu) {
  if (rt_cpu < 0 || std::find(usable.begin(), usable.end(), rt_cpu) == usable.end()) return {};
  std::vector<int> others;
  for (const int cpu : usable) {
    if (cpu != rt_cpu) others.push_back(cpu);
  }
  std::sort(others.begin(), others.end());
  others.erase(std::unique(others.begin(), others.end()), others.end());
  return others;
}

CpuSplit keep_normal_threads_off(int rt_cpu) {
  CpuSplit split;
  const std::vector<int> cpus = normal_thread_cpus(current_cpus(), rt_cpu);
  if (cpus.empty()) return split;
  cpu_set_t set;
  CPU_ZERO(&set);
  for (const int cpu : cpus) {
    if (cpu < CPU_SETSIZE) CPU_SET(static_cast<std::size_t>(cpu), &set);
  }
  if (::sched_setaffinity(0, sizeof set, &set) != 0) {
    split.error = errno;
    return split;
  }
  split.normal_cpus = cpus;
  return split;
}

}  // namespace liftd::rt
