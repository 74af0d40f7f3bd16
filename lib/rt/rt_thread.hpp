// Starting a real-time thread: SCHED_FIFO set in the thread attributes, memory locked, stack
// prefaulted, optional CPU affinity; each refusal is recorded, never fatal. And the absolute
// sleep the real-time loops keep their time with.
#pragma once

#include <pthread.h>

#include <cstddef>
#include <functional>
#include <string>

#include "common/mono_time.hpp"

namespace liftd::rt {

/// How to start the real-time thread.
struct RtThreadOptions {
  int priority = 80;        ///< SCHED_FIFO priority 1..99; 0 = normal scheduling on purpose
  int cpu = -1;             ///< pin to this CPU; -1 = no pinning
  bool lock_memory = true;  ///< mlockall(MCL_CURRENT | MCL_FUTURE) before starting
  std::size_t stack_prefault_bytes = 256 * 1024;  ///< stack touched before the body runs
  /// Thread name (at most 15 characters, pthread_setname_np) for ps -L, chrt and ftrace;
  /// empty = the process's name.
  std::string name;
};

/// What the thread actually got. The *_errno fields say why a wish was refused.
struct RtThreadStatus {
  bool realtime = false;       ///< runs under SCHED_FIFO
  int sched_errno = 0;         ///< pthread_create/attr error that forced normal scheduling
  bool memory_locked = false;  ///< mlockall succeeded
  int mlock_errno = 0;         ///< why not (ENOTSUP: skipped under a sanitizer)
  bool pinned = false;         ///< CPU affinity set
  int affinity_errno = 0;      ///< why not

  /// Lines for the non-real-time side to log once, e.g. "SCHED_FIFO refused (EPERM): ...".
  std::string describe() const;
};

/// A joinable thread started with RtThreadOptions. Move-only; joins on destruction.
class RtThread {
 public:
  /// A thread object with nothing started.
  RtThread() = default;
  RtThread(const RtThread&) = delete;
  RtThread& operator=(const RtThread&) = delete;
  ~RtThread();

  /// Starts `body` on a new thread. Returns 0, or an errno when no thread could be started at
  /// all (SCHED_FIFO refusals fall back to normal scheduling and return 0).
  int start(const RtThreadOptions& options, std::function<void()> body);

  /// Waits for the body to return (no-op when not started).
  void join() noexcept;

  /// Outcome of start().
  const RtThreadStatus& status() const noexcept { return status_; }

  /// True between a successful start() and join().
  bool joinable() const noexcept { return started_; }

 private:
  static void* trampoline(void* self) noexcept;

  pthread_t thread_{};
  bool started_ = false;
  RtThreadOptions options_{};
  RtThreadStatus status_{};
  std::function<void()> body_;
};

/// Sleeps until the monotonic time `when`. The deadline is absolute, so a periodic loop's
/// wake-up lateness does not add up from one sleep to the next; a signal does not cut the sleep
/// short. No allocation, no lock: for the real-time loops.
void sleep_until(MonoTime when) noexcept;

}  // namespace liftd::rt
