// Counts heap allocations made on threads that ask for it, for the "no allocation in the
// cycle" tests: the malloc family and operator new are replaced for the whole test binary.
// Include this header in exactly ONE source file of a test binary (it defines the replacements).
// Under AddressSanitizer or ThreadSanitizer the hooks are off (the sanitizers own malloc) and
// LIFTD_HEAP_HOOKS is 0: tests skip themselves then.
#pragma once

#include <atomic>
#include <cerrno>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <new>

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define LIFTD_HEAP_HOOKS 0
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer)
#define LIFTD_HEAP_HOOKS 0
#else
#define LIFTD_HEAP_HOOKS 1
#endif
#else
#define LIFTD_HEAP_HOOKS 1
#endif

namespace liftd::heap_hooks {

/// Set on a thread to count its allocations (e.g. on the cycle thread after warm-up).
inline thread_local bool counting = false;
/// malloc, calloc, realloc, aligned_alloc and posix_memalign calls counted.
inline std::atomic<std::uint64_t> mallocs{0};
/// operator new / new[] calls counted.
inline std::atomic<std::uint64_t> news{0};

/// Every counted heap call.
inline std::uint64_t calls() noexcept {
  return mallocs.load() + news.load();
}
/// Sets both counters to zero.
inline void reset() noexcept {
  mallocs = 0;
  news = 0;
}
inline void note_malloc() noexcept {
  if (counting) mallocs.fetch_add(1, std::memory_order_relaxed);
}
/// True when the hooks really count on this thread: one operator new and one malloc made while
/// counting are both seen (a test checks it before it trusts a count of zero). Leaves the
/// counters at zero.
inline bool counts_allocations() {
  void* (*volatile allocate)(std::size_t) = &std::malloc;  // volatile: kept by the optimiser
  reset();
  counting = true;
  void* by_new = ::operator new(32);
  void* by_malloc = allocate(32);
  counting = false;
  ::operator delete(by_new);
  std::free(by_malloc);
  const bool seen = news.load() >= 1 && mallocs.load() >= 1;
  reset();
  return seen;
}

}  // namespace liftd::heap_hooks

#if LIFTD_HEAP_HOOKS
// glibc's own entry points, for the replacements to forward to.
extern "C" {
void* __libc_malloc(std::size_t size);
void* __libc_calloc(std::size_t count, std::size_t size);
void* __libc_realloc(void* ptr, std::size_t size);
void* __libc_memalign(std::size_t alignment, std::size_t size);

void* malloc(std::size_t size) {
  liftd::heap_hooks::note_malloc();
  return __libc_malloc(size);
}
void* calloc(std::size_t count, std::size_t size) {
  liftd::heap_hooks::note_malloc();
  return __libc_calloc(count, size);
}
void* realloc(void* ptr, std::size_t size) {
  liftd::heap_hooks::note_malloc();
  return __libc_realloc(ptr, size);
}
void* aligned_alloc(std::size_t alignment, std::size_t size) {
  liftd::heap_hooks::note_malloc();
  return __libc_memalign(alignment, size);
}
int posix_memalign(void** out, std::size_t alignment, std::size_t size) {
  liftd::heap_hooks::note_malloc();
  *out = __libc_memalign(alignment, size);
  return *out != nullptr ? 0 : ENOMEM;
}
}  // extern "C"

// operator new may not go through the malloc symbol (inlined, or a static libstdc++): counted on
// its own. The default deletes call free(), which fits __libc_malloc.
void* operator new(std::size_t size) {
  if (liftd::heap_hooks::counting) {
    liftd::heap_hooks::news.fetch_add(1, std::memory_order_relaxed);
  }
  if (void* p = __libc_malloc(size != 0 ? size : 1)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t size) {
  return ::operator new(size);
}
#endif
