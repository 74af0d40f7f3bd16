// What the API server needs from the rest of the daemon: snapshots to read and commands to
// forward. The daemon implements Backend; the tests use a fake.
#pragma once

#include <array>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "api/result.hpp"
#include "api/sim.hpp"
#include "common/mono_time.hpp"
#include "drive/drive.hpp"

namespace liftd::api {

/// State of the link to the drive as reported in status.link.state (every drive kind).
enum class LinkState : std::uint8_t {
  Down,   ///< nothing heard from the drive
  Init,   ///< the drive answers, its start-up exchange is not finished (DCP: I0)
  Up,     ///< process data flowing
  Fault,  ///< link supervision tripped (e.g. 10 lost DCP frames); drive enable is off
};
/// "down", "init", "up", "fault".
std::string_view to_string(LinkState state) noexcept;

/// One active fault.
struct FaultInfo {
  std::string code;                             ///< snake_case, stable, e.g. "link_fault"
  std::string text;                             ///< human-readable explanation
  std::chrono::system_clock::time_point since;  ///< when it became active (wall clock)
  bool operator==(const FaultInfo&) const = default;
};

/// Real-time scheduling the cycle thread obtained.
struct RtInfo {
  bool realtime = false;       ///< true when the requested SCHED_FIFO priority was obtained
  std::string policy;          ///< "SCHED_FIFO", "SCHED_OTHER", ...
  int priority = 0;            ///< scheduling priority obtained
  bool memory_locked = false;  ///< mlockall() succeeded
  bool operator==(const RtInfo&) const = default;
};

/// A JSON value that copies share. `status` is the request a dispatcher sends most: each one
/// copies the lift's snapshot, compares it with the last one answered and, rarely, serialises
/// it. A kind's detail object rarely changes, so its copies share one value (a reference count,
/// not a deep copy) and two copies of one value compare equal without a look inside. Changing
/// it (`edit`) first makes a private copy when another copy shares it.
class SharedJson {
 public:
  /// An empty object.
  SharedJson();
  explicit SharedJson(nlohmann::json value);
  SharedJson& operator=(nlohmann::json value);

  const nlohmann::json& operator*() const noexcept { return *value_; }
  const nlohmann::json* operator->() const noexcept { return value_.get(); }
  /// The value to change; no other copy sees the change.
  nlohmann::json& edit();

  bool operator==(const SharedJson& other) const {
    return value_ == other.value_ || *value_ == *other.value_;
  }

 private:
  std::shared_ptr<nlohmann::json> value_;
};

/// `history`: which travels of the lift's record, newest first.
struct HistoryArgs {
  std::optional<std::int64_t> from_unix_ms;  ///< started at or after (`from`)
  std::optional<std::int64_t> to_unix_ms;    ///< started before (`to`)
  std::optional<int> floor;                  ///< from or to this floor
  std::optional<std::string> outcome;        ///< "arrived" or "aborted"
  std::optional<std::string> cause;          ///< the end's cause ("arrived", "link_down", ...)
  std::size_t limit = 100;                   ///< travels returned at most
  bool curves = false;                       ///< with each travel's curve where kept
};

/// `trend`: floor-to-floor time and stopping error per floor and day.
struct TrendArgs {
  std::optional<std::int64_t> from_unix_ms;  ///< days from (`from`)
  std::optional<std::int64_t> to_unix_ms;    ///< days before (`to`)
  std::optional<int> floor;                  ///< one floor only
};

/// `eta`: the arrival times, and optionally a floor added to the calls queue.
struct EtaArgs {
  std::optional<int> floor;             ///< a floor to add (`floor`)
  std::optional<std::size_t> position;  ///< where in the calls queue (`position`); none: the end
};

/// `calls`: what to do to the queue of destinations (validated by the command).
struct CallsArgs {
  std::string action = "list";          ///< list, add, cancel, insert or set
  std::optional<int> floor;             ///< add, cancel, insert
  std::optional<std::size_t> position;  ///< insert: where (0: first; none: the end)
  std::vector<int> floors;              ///< set: the new queue, first served first
};

/// Everything `status` reports, filled by the backend. The drive-neutral fields every drive kind
/// fills alike; what only one kind has goes into `details`, reported under the kind's name.
struct StatusSnapshot {
  drive::Kind drive_kind = drive::Kind::Dcp;         ///< drive.kind
  drive::State drive_state = drive::State::Offline;  ///< drive.state
  LinkState link = LinkState::Down;                  ///< link.state
  SharedJson details;                                ///< status.<drive.kind>, e.g. status.dcp
  std::optional<std::int64_t> position_mm;           ///< car.position_mm; nullopt if unknown
  std::optional<int> floor;                          ///< car.floor (0 = lowest); nullopt between
  std::optional<int> next_possible_stop;  ///< car.next_possible_stop: nearest floor it can stop at
  bool brake_open = false;                ///< car.brake_open: brake output (follows S6)
  bool contactors_on = false;             ///< car.contactors_on: motor contactor output
  /// car.doors from the machine inputs: "locked", "closed", "open", "reopening"; null: no inputs
  std::optional<std::string> doors;
  /// service.reason: why the car takes no call now ("stopping", "fault", "inspection", "recall",
  /// "learning", "not_ready"); empty: in service
  /// car.motion: standing, starting, accelerating, at_speed, decelerating, levelling.
  std::string motion = "standing";
  std::string out_of_service;
  std::string travel_state = "idle";                ///< travel.state, snake_case
  std::optional<std::string> travel_direction;      ///< travel.direction: "up", "down" or null
  std::optional<int> target_floor;                  ///< travel.target_floor or null
  std::vector<int> calls;                           ///< travel.calls: queued destinations, in order
  std::optional<std::int64_t> last_travel_slip_mm;  ///< travel.last_slip_mm (I9 extended reply)
  std::vector<FaultInfo> faults;                    ///< active faults, oldest first
  RtInfo rt{};                                      ///< rt
  /// record: whether the lift's record is kept ({"state", "path", "reason"}); null: none
  SharedJson record;
  bool operator==(const StatusSnapshot&) const = default;
};

/// Counters and timing for `stats`. The drive-neutral fields mean the same on every drive kind;
/// every counter of one kind's own link or thread goes into `details`, reported under the kind's
/// name (stats.dcp, stats.sch001, stats.uss).
struct StatsSnapshot {
  drive::Kind drive_kind = drive::Kind::Dcp;  ///< names the object of `details`
  std::uint64_t frames_sent = 0;              ///< link.frames_sent: frames to the drive
  std::uint64_t cycles = 0;                   ///< cycle.cycles: passes of the drive loop
  std::uint64_t dropped_events = 0;           ///< cycle.dropped_events: queue full
  /// cycle.dropped_travel_samples: travel curve samples the io thread did not take in time
  std::uint64_t dropped_travel_samples = 0;
  nlohmann::json details = nlohmann::json::object();  ///< stats.<drive.kind>, e.g. stats.dcp
};

/// One exchange of the frame trace (DCP: one cycle).
struct TraceEntry {
  MonoTime at{};                                ///< when our frame was sent (monotonic)
  std::vector<std::uint8_t> tx;                 ///< our frame
  std::optional<std::vector<std::uint8_t>> rx;  ///< the drive's answer; nullopt if none in time
};

/// Inputs from the machine (safety chain, doors, switches, DCP3 shaft signals, position).
struct Inputs {
  bool safety_chain = false;                ///< safety chain closed
  bool doors_closed = false;                ///< all doors closed
  bool doors_locked = false;                ///< all doors locked
  bool door_reversal = false;               ///< doors reopening (light curtain, door-open button)
  bool inspection = false;                  ///< inspection switch on
  bool recall = false;                      ///< recall (test control) switch on
  bool button_up = false;                   ///< inspection/recall up button pressed
  bool button_down = false;                 ///< inspection/recall down button pressed
  bool zone_level = false;                  ///< car inside the stopping zone of a level
  bool zone_door = false;                   ///< car inside the door (unlocking) zone
  bool relevel_up = false;                  ///< car below the level beyond tolerance (relevel up)
  bool relevel_down = false;                ///< car above the level beyond tolerance (relevel down)
  bool end_zone_top = false;                ///< car in the top end zone
  bool end_zone_bottom = false;             ///< car in the bottom end zone
  bool decel_v4_up = false;                 ///< DCP3 deceleration point for V4, travelling up
  bool decel_v4_down = false;               ///< DCP3 deceleration point for V4, travelling down
  bool decel_v3_up = false;                 ///< DCP3 deceleration point for V3, travelling up
  bool decel_v3_down = false;               ///< DCP3 deceleration point for V3, travelling down
  bool decel_v2_up = false;                 ///< DCP3 deceleration point for V2, travelling up
  bool decel_v2_down = false;               ///< DCP3 deceleration point for V2, travelling down
  bool decel_v1_up = false;                 ///< DCP3 deceleration point for V1, travelling up
  bool decel_v1_down = false;               ///< DCP3 deceleration point for V1, travelling down
  bool decel_v7_up = false;                 ///< DCP3 deceleration point for V7, travelling up
  bool decel_v7_down = false;               ///< DCP3 deceleration point for V7, travelling down
  bool decel_v6_up = false;                 ///< DCP3 deceleration point for V6, travelling up
  bool decel_v6_down = false;               ///< DCP3 deceleration point for V6, travelling down
  bool decel_v5_up = false;                 ///< DCP3 deceleration point for V5, travelling up
  bool decel_v5_down = false;               ///< DCP3 deceleration point for V5, travelling down
  std::optional<std::int64_t> position_mm;  ///< absolute car position; nullopt = unknown
};

/// A partial update of Inputs: fields left empty keep their value.
struct InputUpdate {
  std::array<std::optional<bool>, 28> flags{};  ///< indexed like kInputFlags
  std::optional<std::int64_t> position_mm;      ///< new position, if given
  /// Writes the given fields into `inputs`.
  void apply_to(Inputs& inputs) const;
};

/// Name and member of one boolean input, in the order of InputUpdate::flags.
struct InputFlag {
  std::string_view name;         ///< field name in the API
  bool Inputs::*member;          ///< where it lives in Inputs
  std::string_view description;  ///< one line for docs and help
};
/// Every boolean input, in wire-name order of the docs.
extern const std::array<InputFlag, 28> kInputFlags;

/// Arguments of `travel` and `fast_start` "arm".
struct TravelArgs {
  int floor = 0;                     ///< floor index, 0 = lowest
  std::optional<std::string> speed;  ///< "V4", "V3", ... (nullopt: the fastest allowed)
  std::optional<int> load_percent;   ///< car load for I8
};

/// The position range we accept (every drive kind): DCP I9 carries a sign and 6 digits of
/// millimetres (DCP 5.12.9), the narrowest of the position paths.
inline constexpr std::int64_t kMaxPositionMm = 999'999;

/// The daemon's side of the API for the commands in lib/api. A drive kind's backend also
/// implements its kind's own interface (lib/<kind>/host/commands.hpp) for its own commands.
/// Every method is called on the io_context's thread; every Responder must be called exactly
/// once on that thread.
class Backend {
 public:
  virtual ~Backend() = default;
  /// The drive kind behind this backend; the dispatcher refuses the commands of capabilities
  /// the kind lacks (`not_offered`) before they reach the backend.
  virtual drive::Kind drive_kind() const = 0;
  /// Current state for `status` and the `state` event.
  virtual StatusSnapshot status() = 0;
  /// Link and cycle counters for `stats`.
  virtual StatsSnapshot stats() = 0;
  /// The newest `max_entries` trace entries, oldest first.
  virtual std::vector<TraceEntry> trace(std::size_t max_entries) = 0;
  /// Writes the whole flight recorder, decoded, to a file; the result names it ({"file": path,
  /// "records": n}). A backend without a recorder refuses.
  virtual Result save_trace();
  /// The newest `last` travels with their curves, oldest first (`travels`). A backend that
  /// records none refuses.
  virtual Result travels(std::size_t last);
  /// The effective configuration (as loaded and defaulted) for `config`.
  virtual nlohmann::json config() = 0;
  /// Asks the drive for a fault reset (I2 'R', DCP 5.12.4).
  virtual void drive_reset(Responder done) = 0;
  /// Applies an input update from the I/O board; the result is to_json() of all inputs after it.
  virtual void update_inputs(const InputUpdate& update, Responder done) = 0;

  // ---- travel (DCP chapters 9 to 13); a backend without travel support refuses them ----
  /// Travel to `floor` (or extend a running DCP4 travel). `speed` "V4", "V3", ... or empty.
  virtual void travel(const TravelArgs& args, Responder done);
  /// Controlled stop of the running travel; clears the calls queue.
  virtual void stop(Responder done);
  /// Relevel to the nearest floor.
  virtual void relevel(Responder done);
  /// Software inspection on/off with a held direction ("up", "down", "none").
  virtual void inspection(bool on, const std::string& direction, Responder done);
  /// Calls queue: list, add, cancel, insert or set (CallsArgs).
  virtual void calls(const CallsArgs& args, Responder done);
  /// The learning travel: answered when it ends, with the learned levels beside the configured
  /// ones (docs/api.md "learn"). Every lift's backend offers it (DCP, SCH001 and USS); the
  /// default, for a backend without travels, refuses: `not_offered`.
  virtual void learn(Responder done);

  // ---- the lift's record (lib/record); a backend without one refuses: `not_offered` ----
  /// Lifetime counters and the stopping error per floor (`counters`).
  virtual Result counters();
  /// Sets the counters `names` back to zero (`counters_reset`) and records who did it.
  virtual Result reset_counters(const std::vector<std::string>& names, const std::string& who);
  /// The travels of the record that match `args`, newest first (`history`).
  virtual Result history(const HistoryArgs& args);
  /// Floor-to-floor time and stopping error per floor and day (`trend`).
  virtual Result trend(const TrendArgs& args);

  // ---- for a group dispatcher ----
  /// When the car could stand at each floor's level, and what adding `args.floor` would cost the
  /// queued stops (`eta`, docs/api.md "Arrival times"). The default: `not_offered`.
  virtual Result eta(const EtaArgs& args);

  // ---- the simulated lift (liftd --simulate only) ----
  /// Fault injection and door/safety-chain handling on the simulated lift. The result is the
  /// simulated lift's state after it. The default refuses: `not_ready` "only with liftd
  /// --simulate".
  virtual void sim(const SimRequest& request, Responder done);
};

/// JSON of a status snapshot, as in the `status` result and `state` event.
nlohmann::json to_json(const StatusSnapshot& status);
/// JSON of the backend's stats (the server adds "api").
nlohmann::json to_json(const StatsSnapshot& stats);
/// JSON of one trace entry: {"t_us":..,"tx":"hex bytes","rx":"hex bytes"|null}.
nlohmann::json to_json(const TraceEntry& entry);
/// JSON of the inputs: every flag by name plus position_mm (null if unknown).
nlohmann::json to_json(const Inputs& inputs);
/// "2026-11-22T03:00:00.123Z"
std::string format_utc(std::chrono::system_clock::time_point time);
/// Milliseconds since the Unix epoch of a UTC time as a request gives it: "2026-11-22" (its
/// midnight), "2026-11-22T03:00:00Z" or "2026-11-22T03:00:00.123Z"; nullopt for anything else.
std::optional<std::int64_t> parse_utc_ms(std::string_view text);

}  // namespace liftd::api
