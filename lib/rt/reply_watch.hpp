#pragma once
// When the cycle first looks at the line for a drive's reply (issue #43: fewer wake-ups).
// Sans-I/O: offsets from the start of our frame in, the offset of the first look out.
//
// Each look at the line is a wake-up of the cycle thread. The earliest a reply can be complete
// is fixed by DCP 7.2: the drive may start sending 2.0624 ms after our frame began (our driver is
// off by then), and its frame then takes its length in character times. A drive answers with
// its own steady delay, so after a few exchanges the cycle knows when this drive's replies are
// there: it first looks then, and finds the reply complete at that one look. Every
// kProbeInterval-th exchange looks at the earliest time again, so a drive that became quicker
// is seen to be (and its reply latency in `stats` stays the drive's, within a reply's time on
// the line). A first look never comes later than the drive's latest completion DCP 7.2 allows
// (it starts sending by 11.5625 ms), so the deadline keeps its margin for a late wake-up.

#include <algorithm>
#include <array>
#include <chrono>
#include <cstddef>
#include <cstdint>

namespace liftd::rt {

class ReplyWatch {
 public:
  /// Replies remembered: the first look is at the earliest of the last kRemembered (one slow
  /// reply does not move it; 16 in a row, a quarter of a second, do).
  static constexpr std::size_t kRemembered = 16;
  /// Every this many exchanges the first look is at the spec's earliest time (about once a
  /// second at 15 ms).
  static constexpr std::uint32_t kProbeInterval = 64;

  /// `earliest`: the earliest offset a reply can be complete (DCP 7.2: earliest send start plus
  /// the reply's time on the line); `latest`: the latest offset a first look may have (the
  /// latest send start plus the reply's time on the line).
  constexpr ReplyWatch(std::chrono::nanoseconds earliest, std::chrono::nanoseconds latest) noexcept
      : earliest_(earliest), latest_(std::max(latest, earliest)) {}

  /// The offset from the frame's start of the next exchange's first look.
  constexpr std::chrono::nanoseconds first_look() const noexcept {
    if (remembered_ == 0 || exchanges_ % kProbeInterval == 0) return earliest_;
    auto soonest = seen_[0];
    for (std::size_t i = 1; i < remembered_; ++i) soonest = std::min(soonest, seen_[i]);
    return std::clamp(soonest, earliest_, latest_);
  }

  /// The exchange ended with its reply complete at a look `seen_at` after the frame's start.
  constexpr void note_complete(std::chrono::nanoseconds seen_at) noexcept {
    seen_[next_] = seen_at;
    next_ = (next_ + 1) % kRemembered;
    remembered_ = std::min(remembered_ + 1, kRemembered);
    ++exchanges_;
  }

  /// The exchange ended without a complete reply in time: nothing learned of the drive's timing.
  constexpr void note_no_reply() noexcept { ++exchanges_; }

  /// A new port (another adapter, another drive may stand behind it): learn again.
  constexpr void forget() noexcept {
    remembered_ = 0;
    next_ = 0;
    exchanges_ = 0;
  }

 private:
  std::chrono::nanoseconds earliest_;
  std::chrono::nanoseconds latest_;
  std::array<std::chrono::nanoseconds, kRemembered> seen_{};
  std::size_t remembered_ = 0;
  std::size_t next_ = 0;
  std::uint32_t exchanges_ = 0;
};

}  // namespace liftd::rt
