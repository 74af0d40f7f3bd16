// Where liftd's normal threads run when the real-time threads own a CPU (rt.cpu): on every
// other CPU the process may use, so that the real-time CPU carries only the real-time threads
// and what the board's settings put there (the tty's flip-buffer worker, the UART's interrupt;
// docs/operations.md, "Real-time settings of a board").
#pragma once

#include <vector>

namespace liftd::rt {

/// The CPUs for the normal threads (the io thread with the API, the port keepers, everything
/// but the SCHED_FIFO loops) when the real-time threads are pinned to `rt_cpu`: every CPU in
/// `usable` but that one. Empty when nothing is to change: no pinning (`rt_cpu` < 0), `rt_cpu`
/// not among `usable`, or no other CPU left (on one CPU the normal threads share it).
std::vector<int> normal_thread_cpus(const std::vector<int>& usable, int rt_cpu);

/// What keep_normal_threads_off() did.
struct CpuSplit {
  std::vector<int> normal_cpus;  ///< the calling thread's CPUs now; empty: left as it was
  int error = 0;                 ///< errno of sched_setaffinity, 0 when it worked or was not needed
};

/// Restricts the calling thread, and every thread it starts from then on, to
/// normal_thread_cpus(liftd::current_cpus(), rt_cpu). Call it before the first thread starts; the
/// real-time threads pin themselves to `rt_cpu` (RtThreadOptions::cpu), which an affinity
/// inherited from their creator does not prevent.
CpuSplit keep_normal_threads_off(int rt_cpu);

}  // namespace liftd::rt
