// The CPUs a thread may run on, as a sorted list, and the kernel's way of writing such a list.
#pragma once

#include <string>
#include <vector>

namespace liftd {

/// The CPUs the calling thread may run on (its affinity mask: online CPUs its cgroup's cpuset
/// and the unit's CPUAffinity= allow), in ascending order; empty when it cannot be read.
std::vector<int> current_cpus();

/// CPUs written as the kernel lists them (`Cpus_allowed_list`): "0-3,6". Expects ascending order.
std::string cpu_list_text(const std::vector<int>& cpus);

}  // namespace liftd
