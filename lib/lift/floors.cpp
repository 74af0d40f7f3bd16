#include "lift/floors.hpp"

namespace liftd::lift {

bool FloorTable::assign(std::span<const std::int64_t> levels_mm) noexcept {
  if (levels_mm.empty() || levels_mm.size() > kMaxFloors) return false;
  for (std::size_t i = 1; i < levels_mm.size(); ++i) {
    if (levels_mm[i] <= levels_mm[i - 1]) return false;
  }
  for (std::size_t i = 0; i < levels_mm.size(); ++i) levels_mm_[i] = levels_mm[i];
  size_ = levels_mm.size();
  return true;
}

std::optional<std::size_t> FloorTable::floor_at(std::int64_t position_mm,
                                                std::uint32_t tolerance_mm) const noexcept {
  const auto nearest_floor = nearest(position_mm);
  if (!nearest_floor) return std::nullopt;
  const std::int64_t offset = position_mm - levels_mm_[*nearest_floor];
  const std::int64_t magnitude = offset < 0 ? -offset : offset;
  if (magnitude > static_cast<std::int64_t>(tolerance_mm)) return std::nullopt;
  return nearest_floor;
}

std::optional<std::size_t> FloorTable::nearest(std::int64_t position_mm) const noexcept {
  if (size_ == 0) return std::nullopt;
  std::size_t best = 0;
  std::int64_t best_gap = -1;
  for (std::size_t i = 0; i < size_; ++i) {
    const std::int64_t gap =
        levels_mm_[i] > position_mm ? levels_mm_[i] - position_mm : position_mm - levels_mm_[i];
    if (best_gap < 0 || gap < best_gap) {
      best = i;
      best_gap = gap;
    }
  }
  return best;
}

std::optional<std::size_t> next_possible_stop(const FloorTable& floors, std::int64_t position_mm,
                                              Direction direction, std::uint32_t decel_distance_mm,
                                              std::uint32_t margin_mm) noexcept {
  const std::int64_t needed_mm =
      static_cast<std::int64_t>(decel_distance_mm) + static_cast<std::int64_t>(margin_mm);
  if (direction == Direction::Up) {
    for (std::size_t i = 0; i < floors.size(); ++i) {
      if (floors.level_mm(i) - position_mm >= needed_mm) return i;
    }
  } else if (direction == Direction::Down) {
    for (std::size_t i = floors.size(); i > 0; --i) {
      if (position_mm - floors.level_mm(i - 1) >= needed_mm) return i - 1;
    }
  }
  return std::nullopt;
}

std::optional<std::size_t> floor_to_relevel(const FloorTable& floors, std::int64_t position_mm,
                                            std::uint32_t threshold_mm,
                                            std::uint32_t zone_mm) noexcept {
  const std::optional<std::size_t> nearest = floors.nearest(position_mm);
  if (!nearest) return std::nullopt;
  if (!drift_needs_relevel(floors.level_mm(*nearest) - position_mm, threshold_mm, zone_mm)) {
    return std::nullopt;
  }
  return nearest;
}

}  // namespace liftd::lift
