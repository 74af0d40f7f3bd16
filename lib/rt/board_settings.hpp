// The system settings a board needs around the real-time threads (docs/operations.md,
// "Real-time settings of a board") that liftd cannot make itself, checked at the start so that
// the journal says which are missing. Sans-I/O: the facts are read by BoardFacts::current().
#pragma once

#include <optional>
#include <string>
#include <vector>

namespace liftd::rt {

/// What the check looks at, as the kernel shows it.
struct BoardFacts {
  std::vector<int> usable_cpus;  ///< the process's affinity mask
  /// /sys/devices/virtual/workqueue/cpumask (hexadecimal, 32-bit words separated by commas);
  /// nothing when it cannot be read.
  std::optional<std::string> workqueue_mask;
  /// /sys/devices/system/cpu/cpuidle/current_driver ("none" or nothing: the CPU halts when idle).
  std::optional<std::string> cpuidle_driver;
  /// /sys/devices/system/cpu/cpu<rt.cpu>/power/pm_qos_resume_latency_us ("n/a": no idle state
  /// with any exit latency).
  std::optional<std::string> rt_cpu_resume_latency;

  /// Reads them for `rt_cpu` (-1: the resume latency is not read).
  static BoardFacts current(int rt_cpu);
};

/// The CPUs a kernel cpumask in hexadecimal names ("3" = 0 and 1; "1,00000000" = 32); nothing
/// when the text is not one.
std::optional<std::vector<int>> parse_cpumask(const std::string& text);

/// One sentence per setting that is missing for the real-time threads on `rt_cpu` (-1: not
/// pinned); empty when the board has them all, or when it has a single CPU (nothing to split).
std::vector<std::string> missing_board_settings(int rt_cpu, const BoardFacts& facts);

}  // namespace liftd::rt
