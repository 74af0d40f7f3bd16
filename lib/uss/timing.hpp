// USS timing rules (A 5.1.1 cycle time, A 5.1.2 start pause, A 5.2.1 supervision, A 6
// definitions). Every result is rounded up to whole nanoseconds. Baud 0 gives 0 throughout.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <span>

namespace liftd::uss {

/// A 6.1 / B 3.2: a character frame is 11 bits (start, 8 data, even parity, stop).
inline constexpr std::uint32_t kBitsPerCharacter = 11;
/// A 5.1.2: the start pause is at least 2 character times.
inline constexpr std::uint32_t kStartPauseCharacters = 2;
/// A 5.2.1.1: the maximum reply delay is 20 ms (and never below the start pause).
inline constexpr std::chrono::nanoseconds kMaxReplyDelay = std::chrono::milliseconds(20);

/// A 6.1: tz = 11 * 1000 / baud [ms] (38400 baud: 286.459 us).
std::chrono::nanoseconds character_time(std::uint32_t baud) noexcept;
/// A 5.1.2: the character-free pause of at least 2 character times before STX
/// (38400 baud: 0.573 ms; Tabelle 5.1 rounds to 0.58 ms).
std::chrono::nanoseconds start_pause(std::uint32_t baud) noexcept;
/// Time to send `bytes` characters back to back ("bündig", A 6.2): bytes * tz.
std::chrono::nanoseconds transmission_time(std::uint32_t baud, std::size_t bytes) noexcept;
/// A 6.2: flush residual time (LGE, ADR, n payload characters, BCC back to back) = (n + 3) * tz,
/// n = number of payload characters ("Nutzzeichen", A 4.2: n = LGE - 2).
std::chrono::nanoseconds flush_residual_time(std::uint32_t baud,
                                             std::size_t payload_bytes) noexcept;
/// A 6.3: maximum residual telegram time 1.5 * (n + 3) * tz, counted from STX, n = number of
/// payload characters (not LGE; see max_residual_time_for_lge).
std::chrono::nanoseconds max_residual_time(std::uint32_t baud, std::size_t payload_bytes) noexcept;
/// The same for a telegram length byte: n = LGE - 2, i.e. 1.5 * (LGE + 1) * tz (LGE < 2 is
/// taken as n = 0).
std::chrono::nanoseconds max_residual_time_for_lge(std::uint32_t baud, std::uint8_t lge) noexcept;

/// One request/reply exchange of a polling list (A 5.1, Bild 5.2/5.3). Byte counts are whole
/// telegrams (STX..BCC). reply_bytes = 0: no reply is expected (broadcast, A 3).
struct Exchange {
  std::size_t request_bytes = 0;
  std::size_t reply_bytes = 0;
  std::chrono::nanoseconds reply_delay{};  ///< time from the request's BCC to the reply's STX
};

/// Expected duration of one pass of the polling list (A 5.1.1): the sum over its exchanges of
/// start pause + request transmission + reply delay + reply transmission (an exchange without a
/// reply contributes start pause + request only). A 5.1.1 says the cycle time is not
/// deterministic because reply delays and processing times vary; a master may realise a fixed
/// cycle time by determining the maximum cycle time of a configuration, defining it as the
/// absolute cycle time and, after the exchange with the last slave, waiting until it has
/// elapsed. Pass the maximum reply delay (20 ms, A 5.2.1.1) to get that maximum.
std::chrono::nanoseconds expected_cycle_time(std::uint32_t baud,
                                             std::span<const Exchange> exchanges) noexcept;

}  // namespace liftd::uss
