#include "uss/timing.hpp"

#include <limits>

namespace liftd::uss {
namespace {

constexpr std::uint64_t kNsPerSecond = 1'000'000'000;

// ceil(characters_x2 * 11 bits * 1e9 / (2 * baud)) in ns; characters are counted in halves so
// that A 6.3's factor 1.5 stays exact. Saturates instead of overflowing.
std::chrono::nanoseconds half_characters(std::uint32_t baud, std::uint64_t halves) noexcept {
  if (baud == 0) return std::chrono::nanoseconds{0};
  constexpr std::uint64_t kPerHalf = kBitsPerCharacter * kNsPerSecond;  // 1.1e10
  const std::uint64_t max_halves = std::numeric_limits<std::int64_t>::max() / kPerHalf;
  if (halves > max_halves) return std::chrono::nanoseconds::max();
  const std::uint64_t num = halves * kPerHalf;
  const std::uint64_t den = 2ULL * baud;
  return std::chrono::nanoseconds{static_cast<std::int64_t>((num + den - 1) / den)};
}

std::uint64_t clamp_count(std::size_t n) noexcept {
  return static_cast<std::uint64_t>(n);
}

}  // namespace

std::chrono::nanoseconds character_time(std::uint32_t baud) noexcept {
  return half_characters(baud, 2);  // A 6.1: tz = 11 / baud
}

std::chrono::nanoseconds start_pause(std::uint32_t baud) noexcept {
  return half_characters(baud, 2ULL * kStartPauseCharacters);  // A 5.1.2: 2 tz
}

std::chrono::nanoseconds transmission_time(std::uint32_t baud, std::size_t bytes) noexcept {
  const std::uint64_t n = clamp_count(bytes);
  if (n > std::numeric_limits<std::uint64_t>::max() / 2) return std::chrono::nanoseconds::max();
  return half_characters(baud, 2 * n);
}

std::chrono::nanoseconds flush_residual_time(std::uint32_t baud,
                                             std::size_t payload_bytes) noexcept {
  // A 6.2: LGE, ADR, n payload characters and BCC: (n + 3) tz.
  return transmission_time(baud, payload_bytes + 3);
}

std::chrono::nanoseconds max_residual_time(std::uint32_t baud, std::size_t payload_bytes) noexcept {
  // A 6.3: 1.5 * (n + 3) * tz = 3 * (n + 3) half characters.
  const std::uint64_t n = clamp_count(payload_bytes);
  if (n > std::numeric_limits<std::uint64_t>::max() / 4) return std::chrono::nanoseconds::max();
  return half_characters(baud, 3 * (n + 3));
}

std::chrono::nanoseconds max_residual_time_for_lge(std::uint32_t baud, std::uint8_t lge) noexcept {
  const std::size_t n = lge < 2 /* A 4.2: LGE = n + 2 */ ? 0 : static_cast<std::size_t>(lge) - 2;
  return max_residual_time(baud, n);
}

std::chrono::nanoseconds expected_cycle_time(std::uint32_t baud,
                                             std::span<const Exchange> exchanges) noexcept {
  std::chrono::nanoseconds total{0};
  for (const Exchange& e : exchanges) {
    total += start_pause(baud) + transmission_time(baud, e.request_bytes);
    if (e.reply_bytes > 0) total += e.reply_delay + transmission_time(baud, e.reply_bytes);
  }
  return total;
}

}  // namespace liftd::uss
