// Journal lines for things that can happen thousands of times a second (a card's status byte
// flapping, CAN error frames, frames on our own identifier): the first few of each interval are
// journalled in full, the rest counted, and the count journalled when the interval ends, so a
// flood costs a handful of lines and journald's own rate limit never has to drop a real alarm.
// Runs on the io thread; the clock is the caller's, so tests drive it with made-up times.
#pragma once

#include <chrono>
#include <cstdint>
#include <optional>

#include "common/mono_time.hpp"

namespace liftd::log {

class Throttle {
 public:
  /// At most `burst` lines in full per `interval`.
  Throttle(std::uint64_t burst, std::chrono::nanoseconds interval) noexcept
      : burst_(burst), interval_(interval) {}

  /// `count` occurrences at `now` (a counter's growth since the last call): true when the caller
  /// journals them in full; otherwise they are counted for suppressed().
  bool admit(std::uint64_t count, MonoTime now) noexcept {
    if (count == 0) return false;
    roll(now);
    if (lines_ < burst_) {
      ++lines_;
      return true;
    }
    suppressed_ += count;
    return false;
  }

  /// Once an interval with suppressed occurrences has ended: how many (journal one summary).
  std::optional<std::uint64_t> suppressed(MonoTime now) noexcept {
    if (suppressed_ == 0 || now - window_start_ < interval_) return std::nullopt;
    const std::uint64_t n = suppressed_;
    suppressed_ = 0;
    roll(now);
    return n;
  }

  /// The growth of a monotonic counter since the last call (the first call counts from 0).
  std::uint64_t growth(std::uint64_t counter) noexcept {
    const std::uint64_t delta = counter >= last_counter_ ? counter - last_counter_ : counter;
    last_counter_ = counter;
    return delta;
  }

 private:
  void roll(MonoTime now) noexcept {
    if (now - window_start_ < interval_ || suppressed_ != 0) return;
    window_start_ = now;
    lines_ = 0;
  }

  std::uint64_t burst_;
  std::chrono::nanoseconds interval_;
  MonoTime window_start_{};
  std::uint64_t lines_ = 0;
  std::uint64_t suppressed_ = 0;
  std::uint64_t last_counter_ = 0;
};

}  // namespace liftd::log
