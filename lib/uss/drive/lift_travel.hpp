// Travel sequencing of a lift whose drive speaks USS, sans-I/O: what the drive gets in its
// control word STW and main setpoint HSW (USS C 5.2.1, C 5.2.2), and what the brake and the
// motor contactors do, at each moment of a travel, a relevelling or an inspection run, given
// the drive's status word ZSW and main actual value HIW, the car position and the machine's
// inputs. Called after every USS exchange by the USS controller; no allocation, lock or system
// call.
//
// Like a DCP3 travel (DCP 10.1): a speed setpoint per DCP speed name (V0 crawl, VN relevel, VI
// inspection, V1..V7 travel speeds) from config in percent of the drive's full scale; the
// drive's own ramp generator accelerates and decelerates (STW bits 4..6 set, C 5.2.1 table
// 5.3); at the speed's deceleration point the setpoint drops to crawl V0, at the level to 0.
//
// Brake and contactor mapping (the USS drive has no brake or contactor output of its own that
// the profile defines, so the lift controller drives both from what ZSW says):
// - Motor contactors close when a run begins, contactor_ms before STW bit 0 (ON) goes out, and
//   open when the drive reports ZSW bit 2 = 0 ("Betrieb gesperrt": pulses off) after the stop;
//   at once with a coast (OFF2: the drive's pulses are off and the safety chain that feeds the
//   contactors is usually what opened).
// - The brake opens only while ZSW bit 2 = 1 ("Betrieb freigegeben": the motor is fed) with ZSW
//   bits 3, 4, 5 saying no fault, no OFF2, no OFF3; the setpoint stays 0 for brake_release_ms
//   while it lifts. It closes when the drive reports standstill (|HIW| <= standstill_percent
//   with setpoint 0) at the end of a travel, brake_apply_ms before OFF1 takes the torque away;
//   during an OFF3 quick stop (ZSW bit 5 = 0) it stays open while the drive brakes the car and
//   closes at standstill; at once when ZSW bit 2 drops, with a coast (OFF2), a drive fault or
//   without current replies.
// - Abort wishes: OFF2 for the safety chain, unlocked doors, link fault, drive fault, a drive
//   that drops out or does not stop, the run-time limiter and a forced shutdown; OFF3 for lost
//   inputs, lost position, a crawl that finds no level and inspection switched on mid-travel;
//   OFF1 for a stop before the car moves (abort_wish()). After an OFF2 the idle word stays OFF2
//   until a reply shows ZSW bit 2 = 0, and while the safety chain is open or unknown.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string_view>

#include "common/defaults.hpp"
#include "common/mono_time.hpp"
#include "lift/cause.hpp"
#include "lift/floors.hpp"
#include "lift/inputs.hpp"
#include "lift/travel_event.hpp"
#include "uss/defaults.hpp"
#include "uss/drive/drive_profile.hpp"

namespace liftd::uss {

/// The speed names a USS lift has a setpoint for (the DCP names, drive/drive.hpp).
enum class SpeedName : std::uint8_t { V0, VN, VI, V1, V2, V3, V4, V5, V6, V7 };
inline constexpr std::size_t kSpeedCount = 10;
/// "V0", "VN", "VI", "V1" .. "V7".
std::string_view to_string(SpeedName speed) noexcept;
/// The speed of a name ("V4"), nullopt for any other.
std::optional<SpeedName> parse_speed(std::string_view name) noexcept;
/// n for the travel speeds V1..V7 (the shaft's deceleration point of Vn, lift::Inputs), 0 for
/// V0, VN and VI.
int speed_number(SpeedName speed) noexcept;
/// Index into the per-speed config arrays.
constexpr std::size_t speed_index(SpeedName speed) noexcept {
  return static_cast<std::size_t>(speed);
}

/// Where a travel learns its deceleration point and level (as a DCP3 travel, DCP 10.1).
enum class Reference : std::uint8_t {
  Position,      ///< absolute position against the target, per-speed slowdown distance
  ShaftSignals,  ///< Inputs::decel_point(n, direction) of the travel's speed, Inputs::level_zone
};

/// Defaults of the `uss.*` travel settings: lib/common/defaults.hpp (one set for the
/// configuration file and this library).
namespace uss_defaults {
inline constexpr double kSpeedV0Percent = defaults::kUssSpeedV0Percent;
inline constexpr double kSpeedVnPercent = defaults::kUssSpeedVnPercent;
inline constexpr double kSpeedViPercent = defaults::kUssSpeedViPercent;
inline constexpr double kSpeedV3Percent = defaults::kUssSpeedV3Percent;
inline constexpr double kSpeedV4Percent = defaults::kUssSpeedV4Percent;
inline constexpr int kContactorMs = defaults::kUssContactorMs;
inline constexpr int kBrakeReleaseMs = defaults::kUssBrakeReleaseMs;
inline constexpr int kBrakeApplyMs = defaults::kUssBrakeApplyMs;
inline constexpr double kStandstillPercent = defaults::kUssStandstillPercent;
inline constexpr int kStandstillTimeoutMs = defaults::kUssStandstillTimeoutMs;
inline constexpr int kCrawlTimeoutMs = defaults::kUssCrawlTimeoutMs;
inline constexpr int kStopLeadMm = defaults::kDcp3StopLeadMm;
inline constexpr int kLinkFaultReplies = defaults::kUssTelegramFailures;
}  // namespace uss_defaults

/// The travel settings (config `uss.*`; distances in mm, times in ms, speeds in percent of the
/// drive's normalised full scale, C 5.2.2).
struct LiftTravelConfig {
  ProfileConfig profile;
  /// Setpoint per speed name in percent of full scale (index speed_index); 0 = the installation
  /// has no such speed. V0 and a travel speed are required.
  std::array<double, kSpeedCount> speed_percent{uss_defaults::kSpeedV0Percent,
                                                uss_defaults::kSpeedVnPercent,
                                                uss_defaults::kSpeedViPercent,
                                                0.0,
                                                0.0,
                                                uss_defaults::kSpeedV3Percent,
                                                uss_defaults::kSpeedV4Percent,
                                                0.0,
                                                0.0,
                                                0.0};
  /// Position reference: the setpoint drops to V0 this far before the level, per travel speed
  /// (index speed_index; SV3 and SV4 as the DCP3 defaults, DCP 8.1).
  std::array<std::uint32_t, kSpeedCount> slowdown_mm{
      0, 0, 0, 0, 0, defaults::kDcp3DecelV3Mm, defaults::kDcp3DecelV4Mm, 0, 0, 0};
  Reference reference = Reference::Position;
  /// Position reference: the crawl's setpoint goes to 0 this far before the level (the drive's
  /// ramp from V0 to 0 covers it).
  std::uint32_t stop_lead_mm = uss_defaults::kStopLeadMm;
  /// Relevelling by position ends within this of the level.
  std::uint32_t level_tolerance_mm = defaults::kLevelToleranceMm;
  std::uint32_t contactor_ms = uss_defaults::kContactorMs;
  std::uint32_t brake_release_ms = uss_defaults::kBrakeReleaseMs;
  std::uint32_t brake_apply_ms = uss_defaults::kBrakeApplyMs;
  /// |HIW| (the speed actual value, percent) at or below this with setpoint 0 is standstill.
  double standstill_percent = uss_defaults::kStandstillPercent;
  std::uint32_t standstill_timeout_ms = uss_defaults::kStandstillTimeoutMs;
  /// Longest crawl at V0 after the deceleration point, and longest relevelling run at VN.
  std::uint32_t crawl_timeout_ms = uss_defaults::kCrawlTimeoutMs;
  /// Motor run-time limiter: a travel or relevelling longer than this ends with a coast (not
  /// inspection runs).
  std::uint32_t max_travel_ms = defaults::kMaxTravelMs;
  bool relevel_doors_open = true;  ///< relevel with the doors open (door zone bridged)
  /// ZSW bit 7 "Warnung" refuses new travels (a running one goes on, "Antrieb weiter in
  /// Betrieb").
  bool warning_blocks_start = true;
};

/// The name of the first unusable LiftTravelConfig field, or nullopt.
std::optional<std::string_view> validate(const LiftTravelConfig& config) noexcept;

/// What runs.
using lift::TravelKind;

/// Where a run is.
enum class Phase : std::uint8_t {
  Idle,
  Contactors,    ///< motor contactors closing, STW still OFF1
  SwitchOn,      ///< STW run: waiting for ZSW "operation enabled"
  BrakeRelease,  ///< operation enabled, brake lifting, setpoint 0
  Run,           ///< at the travel's speed (the drive's ramp accelerates)
  Crawl,         ///< V0 after the deceleration point
  Stopping,      ///< setpoint 0 at the level, waiting for standstill
  BrakeApply,    ///< standstill: brake falling, drive still holds the car
  SwitchOff,     ///< OFF1: waiting for ZSW bit 2 = 0
  Halt,          ///< ended early: OFF1/OFF3 tail until the drive is off
};
/// "idle", "contactors", "switch_on", "brake_release", "run", "crawl", "stopping",
/// "brake_apply", "switch_off", "halt".
std::string_view to_string(Phase phase) noexcept;

/// The wish an abort for `cause` leaves the drive with: OFF2, OFF3 or OFF1 as the abort wishes
/// in the comment at the top of this file say.
ProfileWish abort_wish(lift::Cause cause) noexcept;

/// The facts of one step (after one USS exchange).
struct DriveInput {
  MonoTime now{};
  std::optional<std::int64_t> position_mm;  ///< nullopt: unknown
  lift::Inputs inputs{};
  /// The port is up, the drive was heard and fewer than link_fault_replies replies in a row
  /// failed: `zsw` and `actual_percent` are current.
  bool link_ok = false;
  std::uint16_t zsw = 0;        ///< the drive's last status word (PZD1)
  double actual_percent = 0.0;  ///< the drive's last main actual value HIW (PZD2), normalised
  std::uint64_t replies = 0;    ///< good replies from the drive so far
};

/// What goes out after a step.
struct DriveOutput {
  std::uint16_t stw = control::kStop;  ///< PZD1 of the next telegram to the drive
  double setpoint_percent = 0.0;       ///< PZD2 (HSW) before normalisation, signed by direction
  ProfileWish wish = ProfileWish::Stop;
  bool brake_open = false;     ///< mechanical brake released
  bool contactors_on = false;  ///< motor contactors closed
};

/// Something that happened, drained by the controller.
using TravelEvent = lift::BasicTravelEvent<TravelKind>;

/// The sequencer. The car's current floor is the one it last stopped at.
class LiftTravel : public lift::RunState<Phase> {
 public:
  explicit LiftTravel(const LiftTravelConfig& config) noexcept
      : config_(config), profile_(config.profile) {}

  /// What a run of `kind` is called (status travel.state, travel events): a travel to a floor is
  /// "speed" (lift::travel_kind_name).
  static constexpr std::string_view kind_name(TravelKind kind) noexcept {
    return lift::travel_kind_name(kind, "speed");
  }

  /// Starts a travel to `floor` at `speed` (one of V1..V7 with a setpoint; else
  /// SpeedNotConfigured). lift::Cause::None when it started; else why not (conditions of `in`). The
  /// caller checks busy().
  lift::Cause start_travel(const lift::FloorTable& floors, std::size_t floor, SpeedName speed,
                           const DriveInput& in) noexcept;
  /// Starts relevelling to `floor` at VN. By position the direction is the level's; without a
  /// position `direction` (from the shaft's relevel signals) is used.
  lift::Cause start_relevel(const lift::FloorTable& floors, std::size_t floor,
                            lift::Direction direction, const DriveInput& in) noexcept;
  /// Starts a leg of the learning travel to `target_mm` going `direction`, ended by position
  /// whatever the reference (no floor of the table, no level-zone stop). Up at the crawl setpoint
  /// V0 all the way; down at `approach` (a travel speed with a setpoint; else V0) until its
  /// slowdown distance before the target, then V0. The crawl and run-time limits allow a crawl
  /// through the leg (lift::learn_leg_limit_ms). Every gate of a travel applies.
  lift::Cause start_learning(std::int64_t target_mm, lift::Direction direction, SpeedName approach,
                             const DriveInput& in) noexcept;
  /// A learning leg going up ends at `target_mm` instead (the run-out after the last zone);
  /// false when no such leg runs.
  bool end_learning_at(std::int64_t target_mm) noexcept;
  /// Inspection: hold-to-run `direction` (None: stop). A change of direction stops first; no
  /// run starts towards a terminal level the car is at.
  lift::Cause inspect(const lift::FloorTable& floors, lift::Direction direction,
                      const DriveInput& in) noexcept;
  /// Stop at the next floor ahead the car can still reach at its speed's slowdown distance (by
  /// position; by shaft signals the target stays); a car already crawling keeps its floor; a car
  /// not yet moving, or with no floor reachable, stops at once by OFF1 (the drive's ramp).
  /// Inspection and a learning leg: the normal stop sequence. Returns the floor the car will
  /// stop at.
  std::optional<std::size_t> stop(const lift::FloorTable& floors, const DriveInput& in) noexcept;
  /// The next possible stop of a travel between floors that moves: the first floor ahead beyond
  /// its speed's slowdown distance (by position), else its target; nullopt while no such travel
  /// moves (not yet started, other kinds).
  std::optional<std::size_t> landing_floor(const lift::FloorTable& floors,
                                           const DriveInput& in) const noexcept;
  /// Ends whatever runs at once with `cause` (reported once), leaving abort_wish(cause).
  void abort(lift::Cause cause, MonoTime now) noexcept;
  /// Arms a fault acknowledge (DriveProfile::acknowledge).
  void acknowledge() noexcept { profile_.acknowledge(); }

  /// One step: checks the conditions, moves through the phases, returns what goes out.
  DriveOutput tick(const lift::FloorTable& floors, const DriveInput& in) noexcept;

  /// The condition of `in` that forbids starting a run of `kind` now, or None: the drive's
  /// (drive_forbidding()), then what would end a run.
  lift::Cause forbidding(TravelKind kind, const DriveInput& in) const noexcept;
  /// The drive's side of forbidding(): the link, a fault or a latched supervision, local control
  /// (ZSW bit 9 = 0), not ready to switch on, a warning where it blocks a start (C 5.2.1).
  /// Status `drive.state` is `ready` only when it is None.
  lift::Cause drive_forbidding(const DriveInput& in) const noexcept;
  /// The condition of `in` that ends a running run of `kind`, or None.
  lift::Cause ending(TravelKind kind, const DriveInput& in) const noexcept;
  /// The speed has a setpoint.
  bool speed_available(SpeedName speed) const noexcept {
    return config_.speed_percent[speed_index(speed)] > 0.0;
  }

  SpeedName speed() const noexcept { return speed_; }
  /// A run (or its halt tail) is in progress: no new one may start.
  bool busy() const noexcept { return phase_ != Phase::Idle; }
  const DriveProfile& profile() const noexcept { return profile_; }
  const LiftTravelConfig& config() const noexcept { return config_; }
  /// The output of the last tick.
  const DriveOutput& output() const noexcept { return out_; }

 private:
  /// The nearest floor ahead at least this speed's slowdown distance away (by position).
  std::optional<std::size_t> first_floor_beyond_slowdown(const lift::FloorTable& floors,
                                                         std::int64_t position_mm) const noexcept;
  /// Whether `floor` comes before the target in the travel's direction.
  bool earlier_than_target(std::size_t floor) const noexcept;
  lift::Cause begin(TravelKind kind, std::size_t floor, SpeedName speed, lift::Direction direction,
                    const DriveInput& in) noexcept;
  void enter(Phase phase, MonoTime now) noexcept;
  void finish(MonoTime now) noexcept;
  void push(TravelEvent::Type type, lift::Cause cause, MonoTime now) noexcept;
  void normal_stop(MonoTime now) noexcept;
  bool decel_point(const DriveInput& in) const noexcept;
  bool at_level(const DriveInput& in) const noexcept;
  double run_setpoint(const DriveInput& in) const noexcept;
  void sequence(const lift::FloorTable& floors, const DriveInput& in) noexcept;

  LiftTravelConfig config_;
  DriveProfile profile_;
  SpeedName speed_ = SpeedName::V4;
  std::uint32_t run_limit_ms_ = 0;    ///< the run-time limiter of this run
  std::uint32_t crawl_limit_ms_ = 0;  ///< the longest crawl of this run
  MonoTime entered_at_{};
  ProfileWish halt_wish_ = ProfileWish::Stop;
  bool halt_brake_ = false;    ///< the brake may stay open during the halt (OFF1/OFF3 ramp)
  bool inspect_stop_ = false;  ///< inspection: released, stopping
  bool coast_hold_ = false;    ///< OFF2 held until a reply shows ZSW bit 2 = 0
  DriveOutput out_{};
};

}  // namespace liftd::uss
