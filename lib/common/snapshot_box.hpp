// A snapshot box (triple buffer): one writer publishes whole values, one reader always gets
// the newest complete one. Neither side ever waits for the other; no allocation after
// construction as long as copying T does not allocate.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <type_traits>

namespace liftd {

/// Latest-value handoff between exactly one writer thread and one reader thread.
template <class T>
class SnapshotBox {
  static_assert(std::is_nothrow_copy_assignable_v<T>, "T is copied on the real-time path");

 public:
  /// Starts with three default values; read() returns T{} until the first publish().
  SnapshotBox() = default;

  /// Writer: stores a copy of `value` as the newest snapshot.
  void publish(const T& value) noexcept {
    buffers_[back_] = value;
    // Hand the filled buffer over and take whichever one was in the middle.
    const std::uint8_t old =
        middle_.exchange(static_cast<std::uint8_t>(back_ | kFresh), std::memory_order_acq_rel);
    back_ = old & kIndexMask;
  }

  /// Reader: copies the newest snapshot into `out`. True when it is newer than the last read.
  bool read(T& out) noexcept {
    bool fresh = false;
    if ((middle_.load(std::memory_order_relaxed) & kFresh) != 0) {
      const std::uint8_t old = middle_.exchange(front_, std::memory_order_acq_rel);
      front_ = old & kIndexMask;
      fresh = true;
    }
    out = buffers_[front_];
    return fresh;
  }

  /// Reader: the newest snapshot by value.
  T read() noexcept {
    T out{};
    read(out);
    return out;
  }

 private:
  static constexpr std::uint8_t kFresh = 0x4;      // middle buffer holds an unread publish
  static constexpr std::uint8_t kIndexMask = 0x3;  // buffer index 0..2

  std::array<T, 3> buffers_{};
  std::uint8_t back_ = 0;                // writer's buffer (writer only)
  std::atomic<std::uint8_t> middle_{1};  // the exchanged buffer, plus the fresh flag
  std::uint8_t front_ = 2;               // reader's buffer (reader only)
};

}  // namespace liftd
