// Shared plumbing of the travel state machines: the per-cycle context and command builders.
#pragma once

#include <cstdint>
#include <optional>

#include "common/fixed_queue.hpp"
#include "dcp/travel/gate.hpp"
#include "dcp/travel/types.hpp"

namespace liftd::travel {

/// Capacity of the controller's event ring.
inline constexpr std::size_t kEventCapacity = 64;
/// The event ring type the controller drains.
using EventQueue = FixedQueue<Event, kEventCapacity>;

/// What a state machine gets for one step, and where it leaves its side effects.
struct StepContext {
  const TravelConfig& config;                       ///< tunables
  const CycleInput& in;                             ///< this cycle's inputs
  EventQueue& events;                               ///< events out
  std::optional<ChannelRequest> channel_request{};  ///< at most one channel request per cycle

  /// Queues an event stamped with this cycle's time and position.
  void emit(Event::Type type, TravelKind kind, lift::Cause cause, std::int64_t target_mm) noexcept {
    Event event;
    event.type = type;
    event.kind = kind;
    event.cause = cause;
    event.at = in.now;
    event.target_mm = target_mm;
    event.position_mm = in.position_mm;
    static_cast<void>(events.push(event));
  }
  /// The end of a travel: Finished when `cause` is None, else Aborted with the cause.
  void emit_end(TravelKind kind, lift::Cause cause, std::int64_t target_mm) noexcept {
    emit(cause == lift::Cause::None ? Event::Type::Finished : Event::Type::Aborted, kind, cause,
         target_mm);
  }
};

/// A command byte from its message nibble B3..B0 plus the direction bit B4 (DCP 3.1, 3.5).
constexpr std::uint8_t command_byte(std::uint8_t nibble, Direction direction) noexcept {
  return static_cast<std::uint8_t>(
      nibble | (direction == Direction::Down ? dcp::command_bit::kDirectionDown : 0));
}

/// Message nibbles B3..B0 used by the sequencers (DCP 3.5.1 / 3.5.2).
namespace nibble {
inline constexpr std::uint8_t kIdle = 0x0;         ///< 0000 idle
inline constexpr std::uint8_t kStop = 0x1;         ///< 0001 B0: stop mode
inline constexpr std::uint8_t kRelevelling = 0x3;  ///< 0011 B1+B0
inline constexpr std::uint8_t kDistance = 0x5;     ///< 0101 B2+B0: remaining distance / decel
inline constexpr std::uint8_t kTravel = 0x7;       ///< 0111 B2+B1+B0
inline constexpr std::uint8_t kSpeed = 0x9;        ///< 1001 B3+B0
inline constexpr std::uint8_t kAfterFastStartDcp3 = 0xF;  ///< 1111 (DCP 3.5.1)
inline constexpr std::uint8_t kAfterFastStartDcp4 = 0xD;  ///< 1101 (DCP 3.5.2)
}  // namespace nibble

/// The speed-after-fast-start nibble of a dialect (DCP 12.1.3, 13.1).
constexpr std::uint8_t after_fast_start_nibble(dcp::Protocol protocol) noexcept {
  return protocol == dcp::Protocol::Dcp3 ? nibble::kAfterFastStartDcp3
                                         : nibble::kAfterFastStartDcp4;
}

/// Cycles a speed message stays on the wire: at least one, whatever the configuration says.
constexpr std::uint32_t speed_cycles(const TravelConfig& config) noexcept {
  return config.speed_message_cycles == 0 ? 1 : config.speed_message_cycles;
}

/// Milliseconds since `since`.
constexpr std::int64_t elapsed_ms(MonoTime now, MonoTime since) noexcept {
  return std::chrono::duration_cast<std::chrono::milliseconds>(now - since).count();
}

/// The stop tail every DCP travel ends with: the stop message stays on the wire until the drive
/// is at rest (brake closed, S6 = 0, and S1 = 0: DCP 9.1.1 holds B0 until then). True when the
/// travel is over: at rest, or `stop_timeout_ms` passed, in which case `end_cause` becomes
/// DriveDidNotStop.
constexpr bool stop_tail_done(const CycleInput& in, std::int64_t since_ms,
                              const TravelConfig& config, lift::Cause& end_cause) noexcept {
  if (!in.status.brake_open && !in.status.travel_active) return true;
  if (since_ms >= static_cast<std::int64_t>(config.stop_timeout_ms)) {
    end_cause = lift::Cause::DriveDidNotStop;
    return true;
  }
  return false;
}

/// Remaining distance from the position to the target along `direction` (negative once passed).
constexpr std::int64_t remaining_mm(std::int64_t target_mm, std::int64_t position_mm,
                                    Direction direction) noexcept {
  return direction == Direction::Down ? position_mm - target_mm : target_mm - position_mm;
}

}  // namespace liftd::travel
