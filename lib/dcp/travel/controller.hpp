// The travel controller: owns one state machine per travel type and the command gate, runs the
// active machine once per 15 ms cycle and hands out events. Sans-I/O: time and inputs come in
// with CycleInput, the next frame's command and data word go out with CycleOutput.
#pragma once

#include <cstdint>
#include <optional>

#include "dcp/travel/dcp3_travel.hpp"
#include "dcp/travel/dcp4_travel.hpp"
#include "dcp/travel/gate.hpp"
#include "dcp/travel/inspection_travel.hpp"
#include "dcp/travel/relevel_travel.hpp"
#include "dcp/travel/step_context.hpp"

namespace liftd::travel {

/// Runs travels. All calls come from the cycle thread (or one thread in tests); nothing here
/// allocates, locks, logs or throws.
class TravelController {
 public:
  /// A controller with the given tunables.
  explicit TravelController(const TravelConfig& config = {}) noexcept : config_(config) {}

  /// What a run of `kind` is called (status travel.state, travel events; to_string).
  static std::string_view kind_name(TravelKind kind) noexcept { return to_string(kind); }

  /// Queues a travel; it starts in the next step(). Validated against the last cycle's input.
  StartResult start(const TravelRequest& request) noexcept;
  /// Controlled stop of the running travel (stop message, wait for S6 and S1).
  void stop() noexcept;
  /// DCP 13: fast stop of the running travel.
  void fast_stop() noexcept;
  /// DCP4 target extension of the running distance travel.
  ExtendResult extend_target(std::int64_t target_mm) noexcept;
  /// A user stop at a level, for a travel that moves: DCP4 retargets its distance travel to
  /// `target_mm` (a nearer level it can still reach, else it keeps its target), DCP3 crawls from
  /// that level's deceleration point; anything else gets the controlled stop of stop(). Returns
  /// the level the car will stop at, or nullopt when it stops where stop() stops it.
  std::optional<std::int64_t> stop_at(std::int64_t target_mm) noexcept;
  /// A running crawl travel by position ends at `target_mm` instead (Dcp3Travel::end_crawl_at).
  bool end_crawl_at(std::int64_t target_mm) noexcept { return dcp3_.end_crawl_at(target_mm); }
  /// The shortest remaining distance a running DCP4 travel can be retargeted to now.
  std::optional<std::int64_t> stop_distance_mm() const noexcept;
  /// Service stop: no new travel, no automatic relevelling from now on; `force` also withdraws
  /// the drive enable at once (the deadline passed with the car still moving).
  void shut_down(bool force) noexcept;
  /// While held, a queued travel (and automatic relevelling) waits to begin: the DCP controller
  /// holds it until the I9 owed for the last stop has reached the drive (DCP 5.12.9).
  void hold_start(bool held) noexcept { start_held_ = held; }
  /// The level the car should stand at (auto relevelling reference); set after every travel to
  /// its target, or by the caller.
  void set_home_level(std::optional<std::int64_t> level_mm) noexcept { home_level_mm_ = level_mm; }

  /// This cycle's input, before the commands that arrived for it are judged (start() reads it):
  /// an inputs command queued just before a travel command counts for it.
  void observe(const CycleInput& in) noexcept { last_ = in; }
  /// One 15 ms cycle.
  CycleOutput step(const CycleInput& in) noexcept;
  /// Takes the oldest event, if any.
  std::optional<Event> pop_event() noexcept { return events_.pop(); }
  /// Events lost to a full ring.
  std::uint64_t dropped_events() const noexcept { return events_.dropped(); }

  /// Kind of the running travel (None when idle, and while a travel is only queued).
  TravelKind active_kind() const noexcept;
  /// True while a travel is queued (accepted by start(), not begun: held or before its step).
  bool travel_queued() const noexcept { return pending_.has_value(); }
  /// The destination of the run in progress (or the pending one), for its events; 0 for a run
  /// without one (inspection).
  std::int64_t active_target_mm() const noexcept;
  /// Direction of the running travel (None when idle).
  Direction direction() const noexcept;
  /// Deceleration distance known now (data bytes, or I7's Sv during a DCP4 travel).
  std::optional<std::uint32_t> decel_distance_mm() const noexcept;
  /// The DCP4 distance machine, for tests and diagnostics.
  const Dcp4Travel& dcp4() const noexcept { return dcp4_; }
  /// The DCP3 speed / crawl machine, for tests and diagnostics.
  const Dcp3Travel& dcp3() const noexcept { return dcp3_; }
  /// The inspection / recall machine, for tests and diagnostics.
  const InspectionTravel& inspection() const noexcept { return inspection_; }
  /// The relevelling (no remaining distance) machine, for tests and diagnostics.
  const RelevelTravel& relevel() const noexcept { return relevel_; }

 private:
  bool busy() const noexcept;
  void begin_pending(const CycleInput& in) noexcept;
  void maybe_auto_relevel(const CycleInput& in) noexcept;
  /// Automatic relevelling without a position: by the relevel_up / relevel_down shaft signals.
  void relevel_by_shaft_signals(const CycleInput& in) noexcept;
  void abort_all_immediately() noexcept;
  /// Drops the queued travel, if any, with an Aborted event for `cause`: a travel start()
  /// accepted ends with an event whatever ends it, even before it began.
  void drop_queued(lift::Cause cause) noexcept;

  TravelConfig config_;
  CommandGate gate_;
  EventQueue events_;
  Dcp4Travel dcp4_;
  Dcp3Travel dcp3_;
  InspectionTravel inspection_;
  RelevelTravel relevel_;
  std::optional<TravelRequest> pending_;
  Direction pending_direction_ = Direction::None;
  std::optional<std::int64_t> home_level_mm_;
  MonoTime relevel_blocked_until_{};
  CycleInput last_{};
  bool fault_seen_ = false;
  bool shut_down_ = false;
  bool start_held_ = false;
};

}  // namespace liftd::travel
