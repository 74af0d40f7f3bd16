#include "sim/shaft.hpp"

namespace liftd::sim {

SimulatedShaft::SimulatedShaft(std::span<const std::int64_t> levels_mm,
                               std::int64_t zone_mm) noexcept
    : zone_mm_(zone_mm) {
  for (const std::int64_t level : levels_mm) {
    if (size_ == levels_mm_.size()) break;
    levels_mm_[size_++] = level;
  }
}

bool SimulatedShaft::level_zone(double position_mm) const noexcept {
  const double half = static_cast<double>(zone_mm_) / 2.0;
  for (std::size_t i = 0; i < size_; ++i) {
    const double level = static_cast<double>(levels_mm_[i]);
    if (position_mm >= level - half && position_mm <= level + half) return true;
  }
  return false;
}

}  // namespace liftd::sim
