// Where the real-time side of any drive kind reads the car's absolute position: the simulated
// encoder, a position fed through the API, a CAN encoder. Read on the real-time thread: must not
// block, lock or allocate.
#pragma once

#include <atomic>
#include <cstdint>
#include <optional>

#include "common/mono_time.hpp"

namespace liftd {

/// A source of the car's absolute position.
class PositionSource {
 public:
  virtual ~PositionSource() = default;
  /// The position now, or nullopt when the source is invalid or stale.
  virtual std::optional<std::int64_t> position_mm(MonoTime now) const noexcept = 0;
};

/// A position fed from another thread (API inputs, CAN encoder): one writer, the real-time
/// thread reads. A value older than `max_age` counts as lost.
class PositionFeed final : public PositionSource {
 public:
  explicit PositionFeed(MonoTime max_age) noexcept : max_age_(max_age) {}
  /// Writer side: a new reading taken at `at`.
  void set(std::int64_t position_mm, MonoTime at) noexcept {
    position_mm_.store(position_mm, std::memory_order_relaxed);
    at_ns_.store(at.count(), std::memory_order_release);
  }
  /// Writer side: the source says its value is invalid.
  void invalidate() noexcept { at_ns_.store(-1, std::memory_order_release); }
  std::optional<std::int64_t> position_mm(MonoTime now) const noexcept override {
    const std::int64_t at = at_ns_.load(std::memory_order_acquire);
    if (at < 0 || now - MonoTime(at) > max_age_) return std::nullopt;
    return position_mm_.load(std::memory_order_relaxed);
  }

 private:
  MonoTime max_age_;
  std::atomic<std::int64_t> position_mm_{0};
  std::atomic<std::int64_t> at_ns_{-1};  // -1: invalid
};

}  // namespace liftd
