// Floors of the installation and the "next possible stop" (DCP 11.1.2.1: the lift controller
// must know which floors it can still serve while travelling). Fixed capacity, no allocation.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>

#include "lift/inputs.hpp"

namespace liftd::lift {

/// Largest number of floors one installation may have (fixed storage, no allocation).
inline constexpr std::size_t kMaxFloors = 128;

/// Floor levels in mm from the lowest level, strictly increasing.
class FloorTable {
 public:
  /// Replaces the table; false (table unchanged) if empty, too long or not strictly increasing.
  bool assign(std::span<const std::int64_t> levels_mm) noexcept;
  /// Number of floors.
  std::size_t size() const noexcept { return size_; }
  /// Level of floor `index` (0 = lowest); index must be < size().
  std::int64_t level_mm(std::size_t index) const noexcept { return levels_mm_[index]; }
  /// The floor whose level is within `tolerance_mm` of the position, if any.
  std::optional<std::size_t> floor_at(std::int64_t position_mm,
                                      std::uint32_t tolerance_mm) const noexcept;
  /// The floor nearest to the position (ties go to the lower floor); nullopt if the table is empty.
  std::optional<std::size_t> nearest(std::int64_t position_mm) const noexcept;

 private:
  std::array<std::int64_t, kMaxFloors> levels_mm_{};
  std::size_t size_ = 0;
};

/// How far `level_mm` lies ahead of the position for a car moving in `direction` (negative:
/// behind it): above the car for Up, below it otherwise.
constexpr std::int64_t distance_ahead(std::int64_t position_mm, std::int64_t level_mm,
                                      Direction direction) noexcept {
  return direction == Direction::Up ? level_mm - position_mm : position_mm - level_mm;
}

/// The car is at or beyond the terminal level it moves towards (false for Direction::None and
/// an empty table).
inline bool at_terminal_level(const FloorTable& floors, Direction direction,
                              std::int64_t position_mm) noexcept {
  if (floors.size() == 0) return false;
  if (direction == Direction::Up) return position_mm >= floors.level_mm(floors.size() - 1);
  if (direction == Direction::Down) return position_mm <= floors.level_mm(0);
  return false;
}

/// The door zone of common practice: a car at rest up to this far from a level is still at that
/// floor and is relevelled to it; farther, it is between floors and stays where it is.
inline constexpr std::uint32_t kRelevelZoneMm = 150;

/// The relevelling rule of every lift: a car at rest `drift_mm` (either sign) off its level is
/// relevelled when the drift is beyond `threshold_mm` and within `zone_mm`.
constexpr bool drift_needs_relevel(std::int64_t drift_mm, std::uint32_t threshold_mm,
                                   std::uint32_t zone_mm) noexcept {
  const std::int64_t magnitude = drift_mm < 0 ? -drift_mm : drift_mm;
  return magnitude > static_cast<std::int64_t>(threshold_mm) &&
         magnitude <= static_cast<std::int64_t>(zone_mm);
}

/// The floor a car at rest at `position_mm` is relevelled to by itself: its nearest floor, when
/// drift_needs_relevel() says so for the drift from that floor's level; nullopt otherwise.
std::optional<std::size_t> floor_to_relevel(const FloorTable& floors, std::int64_t position_mm,
                                            std::uint32_t threshold_mm,
                                            std::uint32_t zone_mm) noexcept;

/// The nearest floor ahead in `direction` whose level is at least `decel_distance_mm +
/// margin_mm` away from the position, i.e. where the car can still stop. nullopt when stationary
/// (Direction::None) or when no floor ahead is far enough.
std::optional<std::size_t> next_possible_stop(const FloorTable& floors, std::int64_t position_mm,
                                              Direction direction, std::uint32_t decel_distance_mm,
                                              std::uint32_t margin_mm) noexcept;

}  // namespace liftd::lift
