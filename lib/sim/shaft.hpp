// The simulated shaft: the true level of each floor (sim.shaft_levels_mm, by default the floor
// table) and a level zone of a fixed length (sim.level_zone_mm) centred on each, as a vane and
// its switch would mark them. Pure and fixed-size: evaluated on the real-time thread.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "lift/floors.hpp"

namespace liftd::sim {

/// True levels and their level zones.
class SimulatedShaft {
 public:
  SimulatedShaft() = default;
  /// At most lift::kMaxFloors levels (the rest are dropped), in mm from the lowest floor.
  SimulatedShaft(std::span<const std::int64_t> levels_mm, std::int64_t zone_mm) noexcept;
  std::size_t size() const noexcept { return size_; }
  std::int64_t level_mm(std::size_t index) const noexcept { return levels_mm_[index]; }
  std::int64_t zone_mm() const noexcept { return zone_mm_; }
  /// The car at `position_mm` is inside a level zone: within half the zone length of a level.
  bool level_zone(double position_mm) const noexcept;

 private:
  std::array<std::int64_t, lift::kMaxFloors> levels_mm_{};
  std::size_t size_ = 0;
  std::int64_t zone_mm_ = 0;
};

}  // namespace liftd::sim
