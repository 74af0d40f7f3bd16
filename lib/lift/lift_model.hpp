// The lift as the controller sees it: floors, where the car is, where it goes, the next floor it
// can still stop at, and the queue of destinations. Updated once per cycle; no allocation.
#pragma once

#include <cstdint>
#include <optional>
#include <span>

#include "common/defaults.hpp"
#include "lift/calls.hpp"
#include "lift/floors.hpp"
#include "lift/inputs.hpp"

namespace liftd::lift {

/// Tunables of the lift model.
struct LiftConfig {
  /// The car is "at" a floor while within this distance of its level.
  std::uint32_t level_tolerance_mm = defaults::kLevelToleranceMm;
  /// Added to the drive's deceleration distance before a floor counts as still reachable.
  std::uint32_t stop_margin_mm = 100;
  /// At a served call the car stands at least this long before the next queued travel (the
  /// machine's door operator opens the doors on arrival; the travel then waits for them locked).
  std::uint32_t call_stop_ms = defaults::kCallStopMs;
};

/// Floors, car position and direction, next possible stop and the calls queue.
class LiftModel {
 public:
  /// A model with the given tunables and no floors yet.
  explicit LiftModel(const LiftConfig& config = {}) noexcept : config_(config) {}
  /// The settings it was made with.
  const LiftConfig& config() const noexcept { return config_; }
  /// Sets the floor levels (strictly increasing); false if rejected (the old table stays).
  bool set_floors(std::span<const std::int64_t> levels_mm) noexcept;
  /// Feeds one cycle: absolute position if valid, direction of travel and the deceleration
  /// distance currently known (drive data bytes or I7's Sv), if any.
  void update(std::optional<std::int64_t> position_mm, Direction direction,
              std::optional<std::uint32_t> decel_distance_mm) noexcept;

  /// The floor table.
  const FloorTable& floors() const noexcept { return floors_; }
  /// Last valid position, if the source is valid now.
  std::optional<std::int64_t> position_mm() const noexcept { return position_mm_; }
  /// Direction of travel.
  Direction direction() const noexcept { return direction_; }
  /// The floor the car is level with (within the tolerance), if any.
  std::optional<std::size_t> current_floor() const noexcept { return current_floor_; }
  /// The nearest floor the car can still stop at: the current floor while stationary, the first
  /// floor ahead beyond deceleration distance + margin while travelling. nullopt without position,
  /// or travelling without a known deceleration distance.
  std::optional<std::size_t> next_possible_stop() const noexcept { return next_stop_; }
  /// Destinations, served in order.
  CallQueue& calls() noexcept { return calls_; }
  /// Destinations, read-only.
  const CallQueue& calls() const noexcept { return calls_; }

 private:
  LiftConfig config_;
  FloorTable floors_;
  CallQueue calls_;
  std::optional<std::int64_t> position_mm_;
  Direction direction_ = Direction::None;
  std::optional<std::size_t> current_floor_;
  std::optional<std::size_t> next_stop_;
};

}  // namespace liftd::lift
