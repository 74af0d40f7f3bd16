// A bounded single-producer single-consumer queue for the real-time boundary: no locks, no
// allocation after construction, wait-free push and pop.
#pragma once

#include <array>
#include <atomic>
#include <cstddef>
#include <new>
#include <type_traits>

namespace liftd {

/// Size of a cache line, to keep the producer's and the consumer's indices apart.
inline constexpr std::size_t kCacheLine = 64;

/// Ring of N slots (N a power of two) holding up to N elements. Exactly one
/// thread may push and exactly one thread may pop. T must be copy/move assignable.
template <class T, std::size_t N>
class SpscQueue {
  static_assert(N >= 2 && (N & (N - 1)) == 0, "capacity must be a power of two");
  static_assert(std::is_nothrow_copy_assignable_v<T> || std::is_nothrow_move_assignable_v<T>,
                "elements are assigned on the real-time path and must not throw");

 public:
  /// The number of elements the queue holds at most.
  static constexpr std::size_t capacity() noexcept { return N; }

  /// Producer: appends a copy of `value`. False (and nothing changes) when full.
  bool try_push(const T& value) noexcept {
    const std::size_t tail = tail_.load(std::memory_order_relaxed);
    if (tail - head_cache_ == N) {
      head_cache_ = head_.load(std::memory_order_acquire);
      if (tail - head_cache_ == N) return false;
    }
    slots_[tail & (N - 1)] = value;
    tail_.store(tail + 1, std::memory_order_release);
    return true;
  }

  /// Consumer: moves the oldest element into `out`. False when empty.
  bool try_pop(T& out) noexcept {
    const std::size_t head = head_.load(std::memory_order_relaxed);
    if (head == tail_cache_) {
      tail_cache_ = tail_.load(std::memory_order_acquire);
      if (head == tail_cache_) return false;
    }
    out = std::move(slots_[head & (N - 1)]);
    head_.store(head + 1, std::memory_order_release);
    return true;
  }

  /// Either side: elements queued right now (a snapshot; may change at once).
  std::size_t size_approx() const noexcept {
    return tail_.load(std::memory_order_acquire) - head_.load(std::memory_order_acquire);
  }

 private:
  alignas(kCacheLine) std::atomic<std::size_t> head_{0};  // next slot to pop (consumer owns)
  std::size_t tail_cache_ = 0;                            // consumer's last view of tail_
  alignas(kCacheLine) std::atomic<std::size_t> tail_{0};  // next slot to push (producer owns)
  std::size_t head_cache_ = 0;                            // producer's last view of head_
  alignas(kCacheLine) std::array<T, N> slots_{};
};

}  // namespace liftd
