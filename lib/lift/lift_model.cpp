#include "lift/lift_model.hpp"

namespace liftd::lift {

bool LiftModel::set_floors(std::span<const std::int64_t> levels_mm) noexcept {
  if (!floors_.assign(levels_mm)) return false;
  calls_.clear();  // floor indices of the old table mean nothing now
  current_floor_.reset();
  next_stop_.reset();
  return true;
}

void LiftModel::update(std::optional<std::int64_t> position_mm, Direction direction,
                       std::optional<std::uint32_t> decel_distance_mm) noexcept {
  position_mm_ = position_mm;
  direction_ = direction;
  current_floor_.reset();
  next_stop_.reset();
  if (!position_mm) return;
  current_floor_ = floors_.floor_at(*position_mm, config_.level_tolerance_mm);
  if (direction == Direction::None) {
    next_stop_ = current_floor_ ? current_floor_ : floors_.nearest(*position_mm);
    return;
  }
  if (!decel_distance_mm) return;
  next_stop_ = lift::next_possible_stop(floors_, *position_mm, direction, *decel_distance_mm,
                                        config_.stop_margin_mm);
}

}  // namespace liftd::lift
