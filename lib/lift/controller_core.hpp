// The command plumbing every lift controller shares (the DCP, SCH001 and USS controllers): for
// the commands every lift takes (lift/commands.hpp), the lock-free queues and the snapshot box
// between the real-time thread and the io thread with the bound on replies owed, the handling
// of the commands that do not depend on the drive (inputs, inspection, calls, and on SCH001 and
// USS stop and service stop), the first gates of a travel command, the travel events and the
// fault table. The rules underneath (inputs, inspection, start grace, calls) are LiftRules
// (lift/rules.hpp).
//
// A controller derives from ControllerCore<Types>, where Types names its command, reply, event,
// snapshot, travel sequencer, travel event and tick input types; the drive's own parts (its link,
// its travel and relevelling starts, its snapshot fields) stay in the controller. The members
// that drive the travel sequencer (handle_travel, the stop and shutdown handling, inspection,
// drain_travel, fill_lift_snapshot) need one with kind(), phase(), direction(), target(),
// busy(), stop(floors, in), abort(cause, now), drive_forbidding(in), poll_event() and
// dropped_events(), reporting causes as lift::Cause (lift/cause.hpp); the DCP controller
// sequences its travels itself (DCP 10-13) and uses the rest.
//
// A kind whose travels run through the core (SCH001, USS) steps them with step_lift(), one order
// for every such kind, and supplies what only it knows through these members (ControllerCore is
// its friend): build_input(now), handle(command, in) (its own commands; every lift's through
// handle_lift), drive_travel_refusal(travel command) -> optional<Refusal>,
// inspect_run(direction, in), start_call_travel(floor, in),
// start_relevel_run(floor, direction, in) -> Cause, run_travel(in),
// start_learn_leg(target_mm, direction, in) -> bool, drive_learn_refusal(in) -> optional<Answer>,
// update_faults(in, now), relevel_policy(), and the static refusal(cause) of its travels' causes
// (refusal_for over its own table).
//
// Threads: the real-time thread calls the protected members; ONE other thread (the daemon's io
// thread) calls post(), poll_reply(), poll_event(), snapshot() and dropped_events().
#pragma once

#include <algorithm>
#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <optional>
#include <span>
#include <stdexcept>
#include <string_view>
#include <type_traits>

#include "common/level_zone_source.hpp"
#include "common/mono_time.hpp"
#include "common/snapshot_box.hpp"
#include "common/spsc_queue.hpp"
#include "lift/calls.hpp"
#include "lift/car_snapshot.hpp"
#include "lift/cause.hpp"
#include "lift/commands.hpp"
#include "lift/faults.hpp"
#include "lift/floors.hpp"
#include "lift/inputs.hpp"
#include "lift/learning_travel.hpp"
#include "lift/lift_model.hpp"
#include "lift/rules.hpp"
#include "lift/travel_sample.hpp"

namespace liftd::lift {

/// When a lift relevels by itself and when the relevel command finds nothing to do.
struct RelevelPolicy {
  bool automatic = false;                  ///< relevel by itself
  std::uint32_t threshold_mm = 0;          ///< once the car at rest is further than this
  std::uint32_t zone_mm = kRelevelZoneMm;  ///< ... and no further (beyond: it was moved away)
  std::uint32_t level_tolerance_mm = 0;    ///< the relevel command: "the car is level" within
};

/// What a controller's command handling needs besides its travel sequencer's own settings.
struct ControllerCoreConfig {
  LiftConfig lift;                          ///< level tolerance: status car.floor, "already there"
  std::span<const std::int64_t> floors_mm;  ///< strictly increasing levels (config `floors`)
  MonoTime inputs_timeout{};                ///< inputs.timeout_ms
  MonoTime inspection_hold{};               ///< travel.inspection_hold_ms
  MonoTime start{};                         ///< when the controller was made
  /// The simulated shaft's level zone, read at the cycle's instant beside the machine inputs'
  /// level zone by the learning travel (liftd --simulate; nullptr otherwise).
  const LevelZoneSource* level_zone_source = nullptr;
};

/// The core's part of a kind's controller configuration: every kind's has these members (the
/// lift, the floor levels, the inputs' timeout, the inspection hold, the level zone source).
template <class KindConfig>
ControllerCoreConfig core_config_of(const KindConfig& config, MonoTime start = MonoTime{}) {
  return {config.lift, config.floors_mm,        config.inputs_timeout, config.inspection_hold,
          start,       config.level_zone_source};
}

template <typename Types>
class ControllerCore {
 public:
  /// The types the controller works on (its Command, Reply, Event, Snapshot, TravelKind, ...):
  /// the io-side template (host/controller_lift.hpp) takes them from here.
  using CoreTypes = Types;

  // ---- io thread ----
  /// Queues a command; false (nothing queued) when the queue is full or when kReplyQueueSize
  /// replies are owed already: every command with a tag gets exactly one reply, so the replies
  /// owed never exceed the reply queue and none is ever dropped.
  bool post(const typename Types::Command& command) noexcept {
    const bool wants_reply = command.tag != 0;
    if (wants_reply && replies_owed_ >= kReplyQueueSize) return false;
    if (!commands_.try_push(command)) return false;
    if (wants_reply) ++replies_owed_;
    return true;
  }
  bool poll_reply(typename Types::Reply& out) noexcept {
    if (!replies_.try_pop(out)) return false;
    if (replies_owed_ > 0) --replies_owed_;
    return true;
  }
  /// Replies owed for commands posted and not yet polled.
  std::size_t replies_owed() const noexcept { return replies_owed_; }
  /// Replies the real-time thread could not queue: 0 unless a command was answered twice.
  std::uint64_t lost_replies() const noexcept {
    return lost_replies_.load(std::memory_order_relaxed);
  }
  bool poll_event(typename Types::Event& out) noexcept { return events_.try_pop(out); }
  typename Types::Snapshot snapshot() noexcept { return snapshot_.read(); }
  /// Events lost because a queue was full: the controller's to the io thread or the travel's own
  /// (stats cycle.dropped_events).
  std::uint64_t dropped_events() const noexcept {
    return dropped_events_.load(std::memory_order_relaxed) +
           travel_dropped_.load(std::memory_order_relaxed);
  }

  /// The next sample of a travel's curve (io thread).
  bool poll_travel_sample(TravelSample& out) noexcept { return travel_samples_.try_pop(out); }
  /// Travel samples lost because the io thread did not take them in time.
  std::uint64_t dropped_travel_samples() const noexcept {
    return dropped_samples_.load(std::memory_order_relaxed);
  }

  /// Direct access for single-threaded tests.
  const typename Types::Travel& travel() const noexcept { return travel_; }

  /// io thread: the last learning travel's record (read after its ok reply).
  LearnRecord learn_record() noexcept { return learn_box_.read(); }

 protected:
  /// Throws std::invalid_argument on a floor table the lift model refuses (empty, too long, not
  /// strictly increasing).
  template <typename TravelConfig>
  ControllerCore(const ControllerCoreConfig& config, const TravelConfig& travel_config)
      : travel_(travel_config),
        lift_(config.lift),
        level_tolerance_mm_(config.lift.level_tolerance_mm),
        rules_(config.inputs_timeout, config.inspection_hold),
        level_zone_source_(config.level_zone_source) {
    rules_.start(config.start);
    if (!lift_.set_floors(config.floors_mm)) {
      throw std::invalid_argument("floors: need 2 or more strictly increasing levels");
    }
  }
  ~ControllerCore() = default;
  ControllerCore(const ControllerCore&) = delete;
  ControllerCore& operator=(const ControllerCore&) = delete;

  // ---- queues (real-time thread) ----
  bool next_command(typename Types::Command& out) noexcept { return commands_.try_pop(out); }
  void reply(std::uint32_t tag, ReplyCode code, std::string_view detail = {},
             std::optional<std::size_t> floor = std::nullopt) noexcept {
    if (tag == 0) return;
    typename Types::Reply r;
    r.tag = tag;
    r.code = code;
    r.detail = detail;
    r.floor = floor;
    push_reply(r);
  }
  void push_reply(const typename Types::Reply& r) noexcept {
    // post() never lets more replies be owed than the queue holds.
    if (!replies_.try_push(r)) lost_replies_.fetch_add(1, std::memory_order_relaxed);
  }
  void push_event(const typename Types::Event& event) noexcept {
    if (!events_.try_push(event)) dropped_events_.fetch_add(1, std::memory_order_relaxed);
  }
  void publish_snapshot(const typename Types::Snapshot& s) noexcept { snapshot_.publish(s); }

  // ---- inputs ----

  /// The provider's last inputs (valid while fresh) with the API's inspection (LiftRules).
  Inputs current_inputs(MonoTime now) const noexcept { return rules_.current_inputs(now); }
  /// The start grace of the link, the inputs and the position (LiftRules).
  bool start_grace_over(MonoTime now) const noexcept { return rules_.start_grace_over(now); }

  // ---- commands every lift handles alike ----

  void handle_shared(std::uint32_t tag, const InputsCommand& body,
                     typename Types::Input& in) noexcept {
    rules_.take_inputs(body.inputs, in.now);
    reply(tag, ReplyCode::Ok);
  }
  void handle_shared(std::uint32_t tag, const ShutdownCommand& body,
                     typename Types::Input& in) noexcept {
    shutting_down_ = true;
    drop_calls(Cause::ShuttingDown, in.now);
    learning_.stop();
    if (body.force) {
      travel_.abort(Cause::ShuttingDown, in.now);
    } else {
      (void)travel_.stop(lift_.floors(), in);
    }
    reply(tag, ReplyCode::Ok);
  }
  void handle_shared(std::uint32_t tag, const StopCommand&, typename Types::Input& in) noexcept {
    learning_.stop();
    const auto floor = travel_.stop(lift_.floors(), in);
    drop_calls(Cause::StopRequested, in.now, floor);
    reply(tag, ReplyCode::Ok, {}, floor);
  }
  void handle_shared(std::uint32_t tag, const InspectionCommand& body,
                     typename Types::Input& in) noexcept {
    rules_.take_inspection(body.on, body.direction, in.now);
    reply(tag, ReplyCode::Ok);
  }
  void handle_shared(std::uint32_t tag, const CallCommand& body,
                     typename Types::Input& in) noexcept {
    const bool heading_for =
        travel_.busy() && travel_.target().has_value() && travel_.target() == lift_.calls().front();
    if (body.op == CallCommand::Op::Cancel && heading_for && body.floor == travel_.target() &&
        travel_.kind() == Types::TravelKind::Travel) {  // not a relevelling at that floor
      // docs/api.md `calls` cancel: the running travel stops at the next floor it can.
      const std::optional<std::size_t> landing = travel_.landing_floor(lift_.floors(), in);
      if (landing == body.floor) return (void)refuse(tag, ReplyCode::Busy, kTooLateToCancel);
      lift_.calls().pop_front();
      keep_calls_on_stop_ = true;
      const std::optional<std::size_t> stop_floor = travel_.stop(lift_.floors(), in);
      return reply(tag, ReplyCode::Ok, stop_floor ? kCancelStopsAt : kCancelStopsNow, stop_floor);
    }
    const Answer a = answer_call(body, heading_for);
    reply(tag, a.code, a.detail);
  }

  /// The travel command's gates in order (stopping, floor, the drive's own check, inspection,
  /// a run in progress, already there), then `start()` (the travel's start_travel; its Cause
  /// refusal is answered through `refusal_of`). `drive_gate()` answers an optional
  /// Refusal of the drive (e.g. a speed without setpoint). True when it started.
  template <typename DriveGate, typename Start, typename RefusalOf>
  bool handle_travel(std::uint32_t tag, const typename Types::TravelCommand& body,
                     const typename Types::Input& in, DriveGate drive_gate, Start start,
                     RefusalOf refusal_of) noexcept {
    if (const std::optional<Refusal> refusal = first_travel_refusal(body.floor)) {
      return refuse(tag, refusal->code, refusal->detail);
    }
    if (const std::optional<Refusal> refusal = drive_gate()) {
      return refuse(tag, refusal->code, refusal->detail);
    }
    if (in.inputs.button_mode()) return refuse(tag, ReplyCode::NotReady, kButtonModeText);
    if (travel_.busy()) return refuse(tag, ReplyCode::Busy, "a travel is running");
    if (at_level(in, body.floor)) {
      // docs/api.md `travel`: a request that cannot apply to the lift as it stands, as on DCP.
      return refuse(tag, ReplyCode::BadRequest, "the car is already at that level");
    }
    const Cause why = start();
    if (why != Cause::None) {
      const Refusal r = refusal_of(why);
      return refuse(tag, r.code, r.detail);
    }
    reply(tag, ReplyCode::Ok);
    return true;
  }
  /// The first gates of every travel command, on every lift: not while the service stops, and
  /// only to a floor of the installation.
  std::optional<Refusal> first_travel_refusal(std::size_t floor) const noexcept {
    if (shutting_down_) return Refusal{ReplyCode::NotReady, "the service is stopping"};
    if (floor >= lift_.floors().size()) return Refusal{ReplyCode::BadRequest, "no such floor"};
    return std::nullopt;
  }
  /// The first gates of a relevel command: not while stopping, not while a run is in progress.
  /// True when refused (answered).
  bool relevel_refused(std::uint32_t tag) noexcept {
    if (shutting_down_) return !refuse(tag, ReplyCode::NotReady, "the service is stopping");
    if (travel_.busy()) return !refuse(tag, ReplyCode::Busy, "a travel is running");
    return false;
  }

  /// A command every lift takes, for a kind whose travels run through the core (SCH001, USS):
  /// travel (the gates of handle_travel, then its travel's start_travel), relevel, learn and the
  /// shared ones. The kind's parts: drive_travel_refusal(command) (a travel it cannot make, e.g.
  /// a speed without setpoint), refusal(cause), and those of handle_relevel and learn_gate.
  template <typename Kind, typename Body>
  void handle_lift(std::uint32_t tag, const Body& body, typename Types::Input& in,
                   Kind& kind) noexcept {
    if constexpr (std::is_same_v<Body, typename Types::TravelCommand>) {
      (void)handle_travel(
          tag, body, in, [&] { return kind.drive_travel_refusal(body); },
          [&] { return travel_.start_travel(lift_.floors(), body.floor, body.speed, in); },
          [](Cause cause) { return Kind::refusal(cause); });
    } else if constexpr (std::is_same_v<Body, RelevelCommand>) {
      handle_relevel(tag, in, kind);
    } else if constexpr (std::is_same_v<Body, LearnCommand>) {
      handle_learn(
          tag, in.position_mm, level_tolerance_mm_, [&] { return learn_gate(in, kind); },
          [&](std::int64_t target_mm, Direction direction) {
            return kind.start_learn_leg(target_mm, direction, in);
          });
    } else {
      handle_shared(tag, body, in);
    }
  }

  // ---- the learning travel (lift/learning_travel.hpp) ----

  /// The learn command's gates in order (a learning running, the first gates of a travel, the
  /// drive's and the machine's `gate()` (an optional Answer), the car position), then the first
  /// leg by `start_leg(target_mm, direction)` (true: it runs). Answered when the learning ends.
  /// `tolerance_mm`: a car this close above the approach's end goes up at once.
  template <typename Gate, typename StartLeg>
  void handle_learn(std::uint32_t tag, std::optional<std::int64_t> position_mm,
                    std::uint32_t tolerance_mm, Gate gate, StartLeg start_leg) noexcept {
    if (learning_.active()) return (void)refuse(tag, ReplyCode::Busy, kLearnRunning);
    if (const std::optional<Refusal> refusal = first_travel_refusal(0)) {
      return (void)refuse(tag, refusal->code, refusal->detail);
    }
    if (const std::optional<Answer> refusal = gate()) {
      return (void)refuse(tag, refusal->code, refusal->detail);
    }
    if (!position_mm) return (void)refuse(tag, ReplyCode::NotReady, kLearnNoPosition);
    if (!learning_.begin(tag, lift_.floors(), *position_mm, tolerance_mm, start_leg)) {
      return (void)refuse(tag, ReplyCode::NotReady, kLearnNotTaken);
    }
    relevel_held_ = true;
  }
  /// Once per step after the travel's: the learning's sample (the level zone of `inputs` or of
  /// the simulated shaft) and, after the last zone, the leg's end by `end_at(target_mm)`.
  template <typename EndAt>
  void sample_learning(std::optional<std::int64_t> position_mm, const Inputs& inputs, MonoTime now,
                       Direction direction, EndAt end_at) noexcept {
    if (learning_.phase() != LearningTravel::Phase::Up || !position_mm) return;
    const bool zone =
        inputs.level_zone || (level_zone_source_ != nullptr && level_zone_source_->level_zone(now));
    learning_.sample(position_mm, zone, direction, lift_.floors().size(), end_at);
  }
  /// A travel event: a leg of the learning ended (finished, or `aborted` with `cause`).
  void learning_leg_ended(bool aborted, Cause cause) noexcept {
    learning_.leg_ended(aborted, cause);
  }
  /// `stop`: the learning ends once its leg has.
  void stop_learning() noexcept { learning_.stop(); }
  /// After the step's travel events: the next leg (`gate()` and `start_leg` as for
  /// handle_learn) or the end, answered to the learn command; a learning that ended well
  /// publishes its record first. `leg_running`: a leg (or its tail) still runs.
  template <typename Gate, typename StartLeg>
  void step_learning(bool leg_running, Gate gate, StartLeg start_leg) noexcept {
    const std::optional<Answer> answer =
        learning_.step(leg_running, lift_.floors(), gate, start_leg);
    if (!answer) return;
    if (answer->code == ReplyCode::Ok) learn_box_.publish(learning_.record());
    reply(learning_.tag(), answer->code, answer->detail);
  }
  /// A learning travel runs.
  bool learning() const noexcept { return learning_.active(); }
  /// No automatic relevelling by the floor table: from a learning travel's start until the next
  /// travel to a floor. The car stands beyond the top level after learning, and the table it
  /// would relevel to may be the one the learning just found wrong.
  bool relevel_held() const noexcept { return relevel_held_; }

  // ---- the step of a kind whose travels run through the core (SCH001, USS) ----

  /// One step in the one order: the commands (each judged against the input after the ones
  /// before it), the car's floor, inspection and recall, the fault table, the next call and the
  /// automatic relevelling (so that what they start runs in this step's output), the travel,
  /// then the learning travel. Returns the step's input (the kind writes its protocol from it).
  template <typename Kind>
  typename Types::Input step_lift(MonoTime now, Kind& kind) noexcept {
    ++steps_;
    typename Types::Input in = kind.build_input(now);
    typename Types::Command command;
    while (next_command(command)) {
      kind.handle(command, in);
      in = kind.build_input(now);  // an inputs command changes what follows
    }
    locate_car(in);
    follow_inspection(in, [&](Direction d) { kind.inspect_run(d, in); });
    // The faults before the travel: a watcher hears the fault before the travel it ends.
    kind.update_faults(in, now);
    if (!shutting_down_) {
      if (const auto floor = next_call(in)) kind.start_call_travel(*floor, in);  // waits if refused
      auto_relevel(in, kind);
    }
    kind.run_travel(in);
    sample_learning(in.position_mm, in.inputs, now, travel_.direction(),
                    [this](std::int64_t target_mm) { return travel_.end_learning_at(target_mm); });
    drain_travel(now);
    const bool was_busy = travel_.busy();
    step_learning(
        was_busy, [&] { return learn_gate(in, kind); },
        [&](std::int64_t target_mm, Direction direction) {
          return kind.start_learn_leg(target_mm, direction, in);
        });
    if (!was_busy && travel_.busy()) {  // the leg up after the approach: its output now
      kind.run_travel(in);
      drain_travel(now);
    }
    return in;
  }

  /// The relevel command: to the nearest floor's level by the position, or without one in the
  /// direction of the single relevelling signal (relevel_up / relevel_down); answered with the
  /// floor it relevels to.
  template <typename Kind>
  void handle_relevel(std::uint32_t tag, const typename Types::Input& in, Kind& kind) noexcept {
    if (relevel_refused(tag)) return;
    if (in.inputs.button_mode()) return (void)refuse(tag, ReplyCode::NotReady, kButtonModeText);
    std::size_t floor = travel_.current_floor();
    Direction direction = Direction::None;
    if (in.position_mm) {
      const auto nearest = lift_.floors().nearest(*in.position_mm);
      if (!nearest) return (void)refuse(tag, ReplyCode::NotReady, "no floor");
      floor = *nearest;
      if (std::llabs(*in.position_mm - lift_.floors().level_mm(floor)) <=
          static_cast<std::int64_t>(kind.relevel_policy().level_tolerance_mm)) {
        return (void)refuse(tag, ReplyCode::NotReady, "the car is level: nothing to relevel");
      }
    } else if (in.inputs.relevel_up != in.inputs.relevel_down) {
      direction = in.inputs.relevel_up ? Direction::Up : Direction::Down;
    } else {
      return (void)refuse(tag, ReplyCode::NotReady, kNoRelevelReference);
    }
    const Cause why = kind.start_relevel_run(floor, direction, in);
    if (why != Cause::None) {
      const Refusal r = Kind::refusal(why);
      return (void)refuse(tag, r.code, r.detail);
    }
    reply(tag, ReplyCode::Ok, {}, floor);
  }

  /// The automatic relevelling of a car at rest that left its floor's level (relevel_policy():
  /// beyond the threshold, inside the zone), or without a position one the shaft's single
  /// relevelling signal asks for. Only where it may start now; otherwise it waits (a refused
  /// relevelling is no event).
  template <typename Kind>
  void auto_relevel(const typename Types::Input& in, Kind& kind) noexcept {
    const RelevelPolicy policy = kind.relevel_policy();
    if (!policy.automatic || travel_.busy() || in.inputs.button_mode() || learning() ||
        relevel_held()) {
      return;
    }
    std::size_t floor = travel_.current_floor();
    Direction direction = Direction::None;
    if (in.position_mm) {
      const auto nearest =
          floor_to_relevel(lift_.floors(), *in.position_mm, policy.threshold_mm, policy.zone_mm);
      if (!nearest) return;
      floor = *nearest;
    } else if (in.inputs.relevel_up != in.inputs.relevel_down) {
      direction = in.inputs.relevel_up ? Direction::Up : Direction::Down;
    } else {
      return;
    }
    if (travel_.forbidding(Types::TravelKind::Relevel, in) == Cause::None) {
      (void)kind.start_relevel_run(floor, direction, in);
    }
  }

  /// The learn command's and the next leg's gates beyond the first ones (handle_learn): not in
  /// inspection or recall, not while a run is in progress, the drive's own (a speed it lacks),
  /// then every gate of a travel (the drive, the safety chain, the doors, the inputs, the
  /// position: the travel's forbidding()).
  template <typename Kind>
  std::optional<Answer> learn_gate(const typename Types::Input& in, Kind& kind) const noexcept {
    if (in.inputs.button_mode()) return Answer{ReplyCode::NotReady, kButtonModeText};
    if (travel_.busy()) return Answer{ReplyCode::Busy, "a travel is running"};
    if (const std::optional<Answer> refusal = kind.drive_learn_refusal(in)) return refusal;
    const Cause why = travel_.forbidding(Types::TravelKind::Learn, in);
    if (why != Cause::None) {
      const Refusal r = Kind::refusal(why);
      return Answer{r.code, r.detail};
    }
    return std::nullopt;
  }

  /// The faults of the machine every lift raises alike: its inputs lost (after the start
  /// grace), the safety chain open, and the position lost where the drive steers by it
  /// (`position_needed`).
  void set_machine_faults(const Inputs& inputs, bool position_known, bool position_needed,
                          MonoTime now) noexcept {
    const bool started = start_grace_over(now);
    set_fault(FaultCode::InputsLost, started && !inputs.valid, now);
    set_fault(FaultCode::SafetyChain, inputs.valid && !inputs.safety_chain_closed, now);
    set_fault(FaultCode::PositionLost, started && position_needed && !position_known, now);
  }

  // ---- each step ----

  /// Once per step, after the travel's output: a sample of the curve while a run is in progress
  /// (`running`, its API name `kind`) and one more at the first step at rest.
  void sample_travel(MonoTime now, bool running, std::string_view kind,
                     std::optional<std::int64_t> position_mm,
                     std::optional<std::size_t> target_floor, const DriveBits& bits) noexcept {
    const auto sample = sampler_.step(now, running, kind, position_mm, target_floor, bits);
    if (sample && !travel_samples_.try_push(*sample)) {
      dropped_samples_.fetch_add(1, std::memory_order_relaxed);
    }
  }

  /// The current floor is the one the car last stopped at; at start, the nearest to the first
  /// position known.
  void locate_car(const typename Types::Input& in) noexcept {
    if (place_known_ || !in.position_mm) return;
    if (const auto nearest = lift_.floors().nearest(*in.position_mm)) {
      travel_.set_current_floor(*nearest);
      place_known_ = true;
    }
  }
  /// Inspection or recall (the car-roof switch, the API's, the recall key switch): hold-to-run
  /// with the buttons; a travel or relevelling running when either comes on ends with
  /// `mode_changed` (DCP 9.1.1). `inspect(direction)` hands the wanted direction to the travel
  /// (None: stand still).
  template <typename Inspect>
  void follow_inspection(const typename Types::Input& in, Inspect inspect) noexcept {
    if (in.inputs.button_mode()) {
      if (travel_.kind() != Types::TravelKind::None &&
          travel_.kind() != Types::TravelKind::Inspection) {
        travel_.abort(Cause::ModeChanged, in.now);  // a travel, a relevelling or a learning leg
      }
      const Direction d = in.inputs.button_up == in.inputs.button_down
                              ? Direction::None
                              : (in.inputs.button_up ? Direction::Up : Direction::Down);
      inspect(shutting_down_ ? Direction::None : d);
    } else if (travel_.kind() == Types::TravelKind::Inspection) {
      inspect(Direction::None);
    }
  }
  /// Forwards the travel's events; a finished travel to the first call's floor serves that call,
  /// a travel that ended early empties the queue (docs/api.md `calls`: whoever dispatches the
  /// lift decides again).
  void drain_travel(MonoTime now) noexcept {
    typename Types::TravelEvent t;
    while (travel_.poll_event(t)) {
      typename Types::Event e;
      e.kind = Types::Event::Kind::Travel;
      e.at = now;
      e.travel = t;
      push_event(e);
      if (t.type == Types::TravelEvent::Type::Started && t.kind == Types::TravelKind::Travel) {
        relevel_held_ = false;
      }
      if (learning_.active() && (t.type == Types::TravelEvent::Type::Finished ||
                                 t.type == Types::TravelEvent::Type::Aborted)) {
        learning_.leg_ended(t.type == Types::TravelEvent::Type::Aborted, t.cause);
      }
      if (t.type == Types::TravelEvent::Type::Finished && t.kind == Types::TravelKind::Travel) {
        served_on_arrival(t.floor, now);
      } else if (t.type == Types::TravelEvent::Type::Aborted) {
        calls_after_abort(t.cause, now);
      }
    }
    note_travel_dropped(travel_.dropped_events());
  }
  /// The travel sequencer's own count of events it lost (stats cycle.dropped_events).
  void note_travel_dropped(std::uint64_t count) noexcept {
    travel_dropped_.store(count, std::memory_order_relaxed);
  }
  /// The start grace (start_grace_over) counts from `now`: for a controller whose loop starts
  /// later than it was made.
  void restart_start_grace(MonoTime now) noexcept { rules_.start(now); }
  /// `floor` left the calls queue because the car is there (event call_served).
  void call_served(std::size_t floor, MonoTime now) noexcept {
    call_stop_until_ = now + std::chrono::milliseconds(lift_.config().call_stop_ms);
    typename Types::Event served;
    served.kind = Types::Event::Kind::CallServed;
    served.at = now;
    served.floor = floor;
    push_event(served);
  }
  /// A travel ended with the car standing at `reached`: the first queued stop there is served,
  /// whether it was first in the queue or not (the passengers there got their stop).
  void served_on_arrival(std::optional<std::size_t> reached, MonoTime now) noexcept {
    keep_calls_on_stop_ = false;
    if (reached && lift_.calls().cancel(*reached)) call_served(*reached, now);
  }
  /// Whether the next queued travel may start: not within travel.call_stop_ms of the car serving
  /// a call (the doors' time to open at that stop).
  bool call_stop_over(MonoTime now) const noexcept { return now >= call_stop_until_; }
  /// liftd empties the queue for `cause` (a stop, a fault, the service stop): the dispatcher
  /// is told which floors it lost (event calls_dropped). `keep`: the floor a stop ends at stays
  /// queued when it was, and is served there.
  void drop_calls(Cause cause, MonoTime now, std::optional<std::size_t> keep = {}) noexcept {
    const bool kept = keep && lift_.calls().contains(*keep);
    lift::DroppedCalls dropped = lift_.calls().drop();
    if (kept) {
      dropped.floors.reset(*keep);
      (void)lift_.calls().add(*keep, lift_.floors().size());
    }
    if (dropped.floors.none()) return;
    typename Types::Event event;
    event.kind = Types::Event::Kind::CallsDropped;
    event.at = now;
    event.dropped = dropped;
    event.cause = cause;
    push_event(event);
  }
  /// A travel ended early for `cause`: the queue is dropped, unless the travel was stopped by
  /// `calls cancel` of its target (the queue goes on without it).
  void calls_after_abort(Cause cause, MonoTime now) noexcept {
    if (!(keep_calls_on_stop_ && cause == Cause::StopRequested)) drop_calls(cause, now);
    keep_calls_on_stop_ = false;
  }
  /// `calls` (LiftRules::answer_call) answered; `heading_for`: a travel runs to the queue's
  /// first floor.
  Answer answer_call(const CallCommand& call, bool heading_for) noexcept {
    return LiftRules::answer_call(lift_, call, shutting_down_, heading_for);
  }

  /// The floor of the first call to travel to now, if any: none while a run is in progress or
  /// inspection or recall is on; a call to the floor the car is at is served at once.
  std::optional<std::size_t> next_call(const typename Types::Input& in) noexcept {
    if (travel_.busy() || in.inputs.button_mode() || learning_.active()) return std::nullopt;
    if (!call_stop_over(in.now)) return std::nullopt;
    const auto front = lift_.calls().front();
    if (!front) return std::nullopt;
    const std::size_t floor = *front;
    if (at_level(in, floor)) {
      lift_.calls().pop_front();  // already there
      call_served(floor, in.now);
      return std::nullopt;
    }
    return floor;
  }
  /// Records a fault starting or ending (the controllers call it for each code every step) and
  /// tells the io thread every transition it was not told yet. A transition whose event does not
  /// fit waits for a later step; a fault that came and went meanwhile is still told as one raise
  /// and one clear. So the journal never shows a clear without its raise, two raises in a row,
  /// or nothing of a short fault, whatever the load.
  void set_fault(FaultCode code, bool active, MonoTime now) noexcept {
    faults_.set(code, active, now, [&](FaultCode c, bool raised) {
      typename Types::Event e;
      e.kind = raised ? Types::Event::Kind::FaultRaised : Types::Event::Kind::FaultCleared;
      e.at = now;
      e.fault = c;
      return events_.try_push(e);
    });
  }

  /// The snapshot fields the core itself holds, alike on every lift: when, the floor the car
  /// stopped at last, the effective inputs, the calls, the faults, shutting down and learning.
  void fill_core_snapshot(lift::CarSnapshot& s, MonoTime now, const Inputs& inputs) const noexcept {
    s.at = now;
    s.floor = lift_.current_floor();
    s.inputs = inputs;
    s.set_calls(lift_.calls());
    s.faults = faults_.active_all();
    s.fault_since = faults_.since_all();
    s.shutting_down = shutting_down_;
    s.learning = learning();
  }

  /// The snapshot fields every lift has: the core's (fill_core_snapshot()), the car and its
  /// travel as the travel sequencer tells them, and whether the drive lets a travel start by
  /// `in` (the travel's drive_forbidding(), the check every travel start makes first: status
  /// `drive.state`). A travel sequencer of another form (DCP's) fills the travel's part itself.
  void fill_lift_snapshot(typename Types::Snapshot& s, MonoTime now,
                          const typename Types::Input& in) const noexcept {
    fill_core_snapshot(s, now, in.inputs);
    s.drive_allows_travel = travel_.drive_forbidding(in) == Cause::None;
    s.steps = steps_;
    s.position_mm = lift_.position_mm();
    s.travel_kind = travel_.kind();
    s.next_possible_stop = travel_.landing_floor(lift_.floors(), in);
    s.phase = travel_.phase();
    s.direction = travel_.direction();
    s.target_floor = travel_.target();
  }

  typename Types::Travel travel_;
  /// `calls cancel` stopped the running travel: its stop keeps the rest of the queue.
  bool keep_calls_on_stop_ = false;
  /// No queued travel starts before this (travel.call_stop_ms after a call was served).
  MonoTime call_stop_until_{};
  LiftModel lift_;
  bool shutting_down_ = false;
  std::uint64_t steps_ = 0;

 private:
  /// Answers a refusal; false (nothing started).
  bool refuse(std::uint32_t tag, ReplyCode code, std::string_view detail) noexcept {
    reply(tag, code, detail);
    return false;
  }
  /// The car is within the level tolerance of `floor` (by position).
  bool at_level(const typename Types::Input& in, std::size_t floor) const noexcept {
    return in.position_mm && std::llabs(*in.position_mm - lift_.floors().level_mm(floor)) <=
                                 static_cast<std::int64_t>(level_tolerance_mm_);
  }
  std::uint32_t level_tolerance_mm_;
  LiftRules rules_;  ///< inputs, inspection, start grace and calls, as every lift has them
  const LevelZoneSource* level_zone_source_;  ///< the simulated shaft's (nullptr: none)
  LearningTravel learning_;                   ///< real-time thread
  bool relevel_held_ = false;                 ///< relevel_held()
  SnapshotBox<LearnRecord> learn_box_;        ///< the last record, to the io thread

  SpscQueue<typename Types::Command, kCommandQueueSize> commands_;
  SpscQueue<typename Types::Reply, kReplyQueueSize> replies_;
  SpscQueue<typename Types::Event, kEventQueueSize> events_;
  SnapshotBox<typename Types::Snapshot> snapshot_;
  std::atomic<std::uint64_t> dropped_events_{0};
  std::atomic<std::uint64_t> travel_dropped_{0};  ///< the travel's own count, copied each step
  SpscQueue<TravelSample, kTravelSampleQueueSize> travel_samples_;
  std::atomic<std::uint64_t> dropped_samples_{0};
  TravelSampler sampler_;  ///< real-time thread

  // Real-time-thread state.
  bool place_known_ = false;  ///< the travel was told the floor the car stands at
  FaultTable faults_;         ///< each raise and clear told once, never lost to a full queue
  std::atomic<std::uint64_t> lost_replies_{0};
  std::size_t replies_owed_ = 0;  ///< io thread only
};

}  // namespace liftd::lift
