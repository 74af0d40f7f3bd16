// What the SCH001 and USS travel sequencers (lib/sch001/hydraulic_travel,
// lib/uss/drive/lift_travel) report to their controller: a run started, finished or was aborted,
// queued on the real-time thread until the controller drains it after the step.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string_view>

#include "common/fixed_queue.hpp"
#include "common/mono_time.hpp"
#include "lift/cause.hpp"
#include "lift/inputs.hpp"

namespace liftd::lift {

/// What the SCH001 or USS travel sequencer runs.
enum class TravelKind : std::uint8_t {
  None,
  Travel,  ///< to a floor (a call or the travel command)
  Relevel,
  Inspection,
  Learn,  ///< a leg of the learning travel (lift/learning_travel.hpp): ends by position
};
/// "idle", `travel_name` (the kind's name of a travel to a floor: "hydraulic", "speed"),
/// "relevel", "inspection", "learn" (status travel.state, travel events, the travel log).
constexpr std::string_view travel_kind_name(TravelKind kind,
                                            std::string_view travel_name) noexcept {
  switch (kind) {
    case TravelKind::None:
      return "idle";
    case TravelKind::Travel:
      return travel_name;
    case TravelKind::Relevel:
      return "relevel";
    case TravelKind::Inspection:
      return "inspection";
    case TravelKind::Learn:
      return "learn";
  }
  return "idle";
}

/// One event of a run of kind `Kind` (the travel's TravelKind), an abort with its `cause`.
template <typename Kind>
struct BasicTravelEvent {
  enum class Type : std::uint8_t { Started, Finished, Aborted };
  Type type = Type::Started;
  Kind kind = Kind::None;
  Direction direction = Direction::None;
  std::size_t floor = 0;  ///< target (started) or where it ended (finished)
  Cause cause = Cause::None;
  MonoTime at{};
  /// The run's target floor on every event of a travel or relevelling, however it ends; none
  /// for a run without one (inspection, a learning leg).
  std::optional<std::size_t> target{};
};

/// A travel's events until the controller polls them; a full queue drops and counts.
template <typename Event>
class TravelEventQueue {
 public:
  void push(const Event& event) noexcept { (void)events_.push(event); }
  /// The next event, if any.
  bool poll(Event& out) noexcept {
    const auto event = events_.pop();
    if (!event) return false;
    out = *event;
    return true;
  }
  /// Events lost because the queue was full.
  std::uint64_t dropped() const noexcept { return events_.dropped(); }

 private:
  FixedQueue<Event, 16> events_;
};

/// What a SCH001 or USS travel sequencer tells of its run and keeps for it: the kind, the
/// sequencer's own `Phase` (its Idle at rest), direction, target, the floor the car last stopped
/// at, and the run's events until the controller polls them.
template <typename Phase>
class RunState {
 public:
  using Event = BasicTravelEvent<TravelKind>;

  TravelKind kind() const noexcept { return kind_; }
  Phase phase() const noexcept { return phase_; }
  Direction direction() const noexcept { return direction_; }
  /// The floor a travel or relevelling runs to; none for inspection or a learning leg.
  std::optional<std::size_t> target() const noexcept {
    return kind_ == TravelKind::Travel || kind_ == TravelKind::Relevel
               ? std::optional<std::size_t>(target_)
               : std::nullopt;
  }
  /// The floor the car last stopped at.
  std::size_t current_floor() const noexcept { return current_floor_; }
  /// Where the car stands at start (the floor nearest the position).
  void set_current_floor(std::size_t floor) noexcept { current_floor_ = floor; }
  /// The next event, if any.
  bool poll_event(Event& out) noexcept { return events_.poll(out); }
  /// Events lost because the queue was full.
  std::uint64_t dropped_events() const noexcept { return events_.dropped(); }

 protected:
  RunState() = default;
  ~RunState() = default;

  TravelKind kind_ = TravelKind::None;
  Phase phase_ = Phase::Idle;
  Direction direction_ = Direction::None;
  std::size_t target_ = 0;
  std::int64_t target_mm_ = 0;  ///< where the run ends by position (the floor's level, the leg's)
  std::size_t current_floor_ = 0;
  MonoTime started_at_{};
  TravelEventQueue<Event> events_;
};

}  // namespace liftd::lift
