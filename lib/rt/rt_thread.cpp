#include "rt/rt_thread.hpp"

#include <sched.h>
#include <sys/mman.h>

#include <cerrno>
#include <cstdint>
#include <cstring>
#include <ctime>
#include <utility>

namespace liftd::rt {
namespace {

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
constexpr bool kUnderSanitizer = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer)
constexpr bool kUnderSanitizer = true;
#else
constexpr bool kUnderSanitizer = false;
#endif
#else
constexpr bool kUnderSanitizer = false;
#endif

std::string errno_text(int e) {
  return std::string(strerrorname_np(e) ? strerrorname_np(e) : "?") + ": " + std::strerror(e);
}

// Touches the stack the body will use, so its pages are mapped (and locked) before the first
// cycle instead of faulting inside it. Recursion keeps every chunk's frame live at once.
__attribute__((noinline)) void prefault_recursive(std::size_t remaining) noexcept {
  constexpr std::size_t kChunk = 4096;
  volatile unsigned char page[kChunk];
  page[0] = 1;
  page[kChunk - 1] = 1;
  if (remaining > kChunk) prefault_recursive(remaining - kChunk);
  (void)page[0];
}

}  // namespace

std::string RtThreadStatus::describe() const {
  std::string text;
  auto add = [&text](const std::string& line) {
    if (!text.empty()) text += "; ";
    text += line;
  };
  if (!realtime) {
    add(sched_errno != 0 ? "SCHED_FIFO refused (" + errno_text(sched_errno) +
                               "), cycle thread runs with normal scheduling"
                         : "cycle thread runs with normal scheduling (priority 0 configured)");
  }
  if (!memory_locked && mlock_errno != 0) {
    add(mlock_errno == ENOTSUP ? "memory not locked (skipped under a sanitizer)"
                               : "mlockall refused (" + errno_text(mlock_errno) + ")");
  }
  if (!pinned && affinity_errno != 0)
    add("CPU affinity refused (" + errno_text(affinity_errno) + ")");
  return text;
}

RtThread::~RtThread() {
  join();
}

int RtThread::start(const RtThreadOptions& options, std::function<void()> body) {
  if (started_) return EBUSY;
  options_ = options;
  body_ = std::move(body);
  status_ = RtThreadStatus{};

  if (options.lock_memory) {
    if (kUnderSanitizer) {
      // The sanitizers reserve terabytes of shadow memory; locking it cannot work.
      status_.mlock_errno = ENOTSUP;
    } else if (mlockall(MCL_CURRENT | MCL_FUTURE) == 0) {
      status_.memory_locked = true;
    } else {
      status_.mlock_errno = errno;
    }
  }

  pthread_attr_t attr;
  if (const int err = pthread_attr_init(&attr); err != 0) return err;
  int err = 0;
  if (options.priority > 0) {
    sched_param param{};
    param.sched_priority = options.priority;
    err = pthread_attr_setinheritsched(&attr, PTHREAD_EXPLICIT_SCHED);
    if (err == 0) err = pthread_attr_setschedpolicy(&attr, SCHED_FIFO);
    if (err == 0) err = pthread_attr_setschedparam(&attr, &param);
  }
  if (options.cpu >= 0) {
    cpu_set_t set;
    CPU_ZERO(&set);
    CPU_SET(static_cast<std::size_t>(options.cpu), &set);
    status_.affinity_errno = pthread_attr_setaffinity_np(&attr, sizeof set, &set);
  }
  if (err == 0) {
    err = pthread_create(&thread_, &attr, &RtThread::trampoline, this);
    if (err == 0) status_.realtime = options.priority > 0;
  }
  if (err != 0 && (err == EPERM || err == EINVAL || err == ENOTSUP) && options.priority > 0) {
    // Refused real-time scheduling: run anyway, with normal scheduling, and say so.
    status_.sched_errno = err;
    pthread_attr_setinheritsched(&attr, PTHREAD_INHERIT_SCHED);
    err = pthread_create(&thread_, &attr, &RtThread::trampoline, this);
  }
  if (err != 0 && options.cpu >= 0 && status_.affinity_errno == 0) {
    // The CPU may not exist or be allowed: drop the pinning rather than the thread.
    status_.affinity_errno = err;
    pthread_attr_t plain;
    pthread_attr_init(&plain);
    err = pthread_create(&thread_, &plain, &RtThread::trampoline, this);
    pthread_attr_destroy(&plain);
  }
  pthread_attr_destroy(&attr);
  if (err != 0) return err;
  if (!options_.name.empty()) {
    // Named here, before start() returns, not by the thread itself: whoever looks right after
    // (ps -L, the daemon's readiness, a test reading /proc) sees the name with the pinning that
    // the attributes already gave. The kernel keeps 15 characters (TASK_COMM_LEN 16); a longer
    // name is refused (ERANGE).
    char name[16] = {};
    options_.name.copy(name, sizeof name - 1);
    pthread_setname_np(thread_, name);
  }
  status_.pinned = options.cpu >= 0 && status_.affinity_errno == 0;
  started_ = true;
  return 0;
}

void RtThread::join() noexcept {
  if (!started_) return;
  pthread_join(thread_, nullptr);
  started_ = false;
}

void* RtThread::trampoline(void* self) noexcept {
  auto* thread = static_cast<RtThread*>(self);
  if (thread->options_.stack_prefault_bytes > 0) {
    prefault_recursive(thread->options_.stack_prefault_bytes);
  }
  thread->body_();
  return nullptr;
}

void sleep_until(MonoTime when) noexcept {
  constexpr std::int64_t kNsPerS = 1'000'000'000;
  const auto ns = when.count();
  const timespec ts{static_cast<time_t>(ns / kNsPerS), static_cast<long>(ns % kNsPerS)};
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
}

}  // namespace liftd::rt
