// A fixed-capacity FIFO for the real-time side: no allocation after construction, no locks.
// Single-threaded: the owner pushes and pops from the same thread (a real-time thread).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>

namespace liftd {

/// FIFO of at most N elements in fixed storage. A push into a full queue fails and is counted.
template <typename T, std::size_t N>
class FixedQueue {
  static_assert(N > 0, "FixedQueue needs room for at least one element");

 public:
  /// Appends a copy; false (and dropped() grows) if the queue is full.
  bool push(const T& value) noexcept {
    if (size_ == N) {
      ++dropped_;
      return false;
    }
    items_[(head_ + size_) % N] = value;
    ++size_;
    return true;
  }
  /// Removes and returns the oldest element, or nullopt if empty.
  std::optional<T> pop() noexcept {
    if (size_ == 0) return std::nullopt;
    std::optional<T> out(items_[head_]);
    head_ = (head_ + 1) % N;
    --size_;
    return out;
  }
  /// The oldest element without removing it; nullptr if empty.
  const T* front() const noexcept { return size_ == 0 ? nullptr : &items_[head_]; }
  /// Removes the oldest element if there is one.
  void drop_front() noexcept {
    if (size_ == 0) return;
    head_ = (head_ + 1) % N;
    --size_;
  }
  std::size_t size() const noexcept { return size_; }
  bool empty() const noexcept { return size_ == 0; }
  bool full() const noexcept { return size_ == N; }
  static constexpr std::size_t capacity() noexcept { return N; }
  /// Pushes that failed because the queue was full, since construction.
  std::uint64_t dropped() const noexcept { return dropped_; }

 private:
  std::array<T, N> items_{};
  std::size_t head_ = 0;
  std::size_t size_ = 0;
  std::uint64_t dropped_ = 0;
};

}  // namespace liftd
