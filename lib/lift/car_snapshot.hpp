// What every lift controller publishes after each step that means the same on every drive kind:
// the car, the travel's direction and target, the machine inputs, the calls, the faults and the
// controller's mode. Each kind's ControllerSnapshot derives from it and adds its own drive's facts
// (its link, its counters; its travel kind and phase through SequencedSnapshot where its travel
// sequencer reports them as the core expects); ControllerCore::fill_core_snapshot and
// fill_lift_snapshot write this part. Plain data, copied whole through a SnapshotBox to the io
// thread.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>

#include "common/mono_time.hpp"
#include "lift/calls.hpp"
#include "lift/faults.hpp"
#include "lift/inputs.hpp"

namespace liftd::lift {

/// Bound on the queued calls a snapshot shows.
inline constexpr std::size_t kMaxSnapshotCalls = 64;

struct CarSnapshot {
  MonoTime at{};  ///< when it was published
  std::optional<std::int64_t> position_mm;
  std::optional<std::size_t> floor;               ///< the floor the car stopped at last
  std::optional<std::size_t> next_possible_stop;  ///< a moving travel's: where a stop now lands
  Direction direction = Direction::None;
  std::optional<std::size_t> target_floor;
  Inputs inputs{};  ///< the effective inputs (the provider's, with the API's inspection)
  std::array<std::uint8_t, kMaxSnapshotCalls> calls{};
  std::size_t call_count = 0;
  std::array<bool, static_cast<std::size_t>(FaultCode::kCount)> faults{};
  std::array<MonoTime, static_cast<std::size_t>(FaultCode::kCount)> fault_since{};
  bool shutting_down = false;  ///< the shutdown command was taken
  bool learning = false;       ///< a learning travel runs (status service.reason)
  /// Shutting down and at rest: no run, and the drive told so (each kind says how).
  bool quiesced = false;
  /// The drive lets a travel start now: the travel's drive_forbidding(), the check every travel
  /// start makes first (status `drive.state`).
  bool drive_allows_travel = false;

  /// The first kMaxSnapshotCalls floors of `queue`, in order, and how many there are.
  void set_calls(const CallQueue& queue) noexcept {
    call_count = queue.size() < kMaxSnapshotCalls ? queue.size() : kMaxSnapshotCalls;
    for (std::size_t i = 0; i < call_count; ++i) calls[i] = static_cast<std::uint8_t>(queue.at(i));
  }
};

/// A CarSnapshot with the step count and the travel sequencer's kind and phase: what
/// ControllerCore::fill_lift_snapshot writes besides the car.
template <typename TravelKind, typename Phase>
struct SequencedSnapshot : CarSnapshot {
  std::uint64_t steps = 0;
  TravelKind travel_kind = TravelKind::None;
  Phase phase = Phase::Idle;
};

}  // namespace liftd::lift
