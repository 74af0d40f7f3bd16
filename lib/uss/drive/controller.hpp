// The USS side of one lift: the user side of the USS master (lib/uss/master) for the lift's
// drive and any other slave on the bus, the travel sequencing (lift_travel.hpp) with the drive
// profile (drive_profile.hpp), and the drive-neutral lift model (lib/lift), joined into one
// engine that the USS runner (lib/rt/uss_runner.hpp) calls after every exchange. Talks to the
// non-real-time side only through lock-free structures: commands in, replies and events out
// (SPSC queues), state out (triple buffer).
//
// Threads: the USS runner's thread calls the uss::UssHooks methods (and so every uss::Master
// user-side call); ONE other thread (the daemon's io thread) calls post(), poll_reply(),
// poll_event() and snapshot().
#pragma once

#include <array>
#include <atomic>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>
#include <variant>
#include <vector>

#include "common/defaults.hpp"
#include "common/level_zone_source.hpp"
#include "common/mono_time.hpp"
#include "common/position_source.hpp"
#include "lift/controller_core.hpp"
#include "lift/faults.hpp"
#include "lift/floors.hpp"
#include "lift/inputs.hpp"
#include "lift/lift_model.hpp"
#include "uss/drive/drive_profile.hpp"
#include "uss/drive/lift_travel.hpp"
#include "uss/master/master.hpp"
#include "uss/pkw.hpp"
#include "uss/pzd.hpp"
#include "uss/receiver.hpp"
#include "uss/runner/uss_runner.hpp"

namespace liftd::uss {

/// Everything the controller needs, fixed at construction.
struct UssControllerConfig {
  std::uint8_t drive_address = 0;  ///< uss.drive.address: the lift drive's slave address
  /// PZD words sent to the drive: PZD1 STW, PZD2 HSW, the rest 0 (the slave's PZD count).
  std::uint8_t drive_pzd_words = 2;
  Normalisation normalisation;  ///< HSW / HIW scaling (C 5.2.2), e.g. 4000 hex = 100 %
  LiftTravelConfig travel;
  /// Replies of the drive that fail in a row before its link counts as down and a travel ends
  /// (the master flags "sendet nicht" at the first, A 5.2.1.1).
  std::uint32_t link_fault_replies = uss_defaults::kLinkFaultReplies;
  lift::LiftConfig lift;                ///< level tolerance: status car.floor
  std::vector<std::int64_t> floors_mm;  ///< strictly increasing levels (config `floors`)
  MonoTime inputs_timeout = std::chrono::milliseconds(defaults::kInputsTimeoutMs);
  MonoTime inspection_hold = std::chrono::milliseconds(defaults::kInspectionHoldMs);
  /// Relevel by itself when the car at rest leaves the level (by position beyond
  /// relevel_threshold_mm up to relevel_zone_mm; without position by the shaft's relevel_up /
  /// relevel_down).
  bool auto_relevel = true;
  std::uint32_t relevel_threshold_mm = defaults::kRelevelThresholdMm;
  std::uint32_t relevel_zone_mm = lift::kRelevelZoneMm;
  /// The simulated shaft's level zone, read beside the machine inputs' by the learning travel
  /// (liftd --simulate; nullptr otherwise).
  const LevelZoneSource* level_zone_source = nullptr;
};

// ---- commands (io thread -> USS thread): the shared ones in lib/lift/commands.hpp ----
/// One of V1..V7 with a setpoint.
using TravelCommand = lift::BasicTravelCommand<SpeedName>;
/// The commands every lift takes (shutdown: the running travel lands as `stop` does, then OFF1;
/// `force`: OFF2 at once).
using namespace lift::shared_commands;
/// Acknowledge a drive fault: one rising edge of STW bit 7 (C 5.2.1 table 5.3); also clears a
/// latched drive-profile supervision. Refused while a run is in progress.
struct DriveResetCommand {};
/// A PKW request to any configured slave; the reply carries the uss::PkwResult.
struct ParameterCommand {
  std::uint8_t address = 0;
  Pkw request;
};
/// A mirror telegram (A 5.3) to a configured slave; the reply carries the MirrorResult.
struct MirrorCommand {
  std::uint8_t address = 0;
};
using CommandBody =
    lift::CommandBodyOf<TravelCommand, DriveResetCommand, ParameterCommand, MirrorCommand>;
using ControllerCommand = lift::TaggedCommand<CommandBody>;

// ---- replies and events (USS thread -> io thread) ----
using lift::ReplyCode;
/// The shared reply (tag, code, detail, floor) with the results of the USS requests.
struct CommandReply : lift::CommandReply {
  /// ParameterCommand: its one reply comes when the request ended (Ok with the result, whatever
  /// its outcome; Unanswered after the master's pkw_repeat_limit), or at once without a result
  /// when the master refused it.
  std::optional<PkwResult> pkw;
  /// MirrorCommand: likewise, Ok with the result once the mirror came back (or failed).
  std::optional<MirrorResult> mirror;
};

using lift::fault_code_name;
using lift::FaultCode;
/// The technician's texts of the drive's faults, in USS terms.
inline constexpr lift::DriveFaultTexts kFaultTexts{
    .link_fault =
        "USS link fault: the drive missed uss.link_fault_replies replies in a row (A 5.2.1.1 "
        "'Teilnehmer sendet nicht'), was never heard, or the serial port failed",
    .drive_fault =
        "the drive reports a fault (ZSW bit 3, C 5.2.1) or did not reach the state asked of "
        "it in time; drive_reset acknowledges it (STW bit 7)",
    .advance_warning =
        "the drive reports a warning (ZSW bit 7, C 5.2.1): no new travel until it clears",
    .position_lost = {},
};

struct ControllerEvent {
  enum class Kind : std::uint8_t {
    Link,          ///< a slave's "sendet nicht" flag changed (`link`)
    Port,          ///< the serial port opened or was lost (`port_up`)
    Spontaneous,   ///< a spontaneous report (C 4.2.1.2)
    Mirror,        ///< a mirror result without a command (the start test)
    DriveState,    ///< the drive-profile state read from ZSW, or its control (bit 9), changed
    Travel,        ///< `travel`
    FaultRaised,   ///< `fault`
    FaultCleared,  ///< `fault`
    CallServed,    ///< `floor`
    CallsDropped,  ///< liftd emptied the calls queue: `dropped`, for `cause`
  };
  Kind kind = Kind::Link;
  MonoTime at{};
  LinkChange link{};
  bool port_up = false;
  SpontaneousReport spontaneous{};
  MirrorResult mirror{};
  ProfileState drive_state = ProfileState::NotReadyToSwitchOn;
  bool plc_control = true;  ///< DriveState: the drive takes the master's control (ZSW bit 9)
  std::uint16_t zsw = 0;
  TravelEvent travel{};
  FaultCode fault = FaultCode::LinkFault;
  std::size_t floor = 0;
  lift::DroppedCalls dropped{};
  lift::Cause cause = lift::Cause::None;
};

/// One configured slave as the snapshot shows it.
struct SlaveSnapshot {
  std::uint8_t address = 0;
  bool heard = false;
  bool responding = false;  ///< false = "sendet nicht" (A 5.2.1.1) or not heard yet
  std::uint32_t consecutive_failures = 0;
  std::uint64_t good = 0;
  std::uint64_t failures = 0;
  std::array<std::uint16_t, kMaxPzdWords> pzd_in{};
  std::uint8_t pzd_in_count = 0;
  bool pkw_busy = false;
};

using lift::kMaxSnapshotCalls;
inline constexpr std::size_t kMaxSnapshotSlaves = kMaxSlaveAddress + 1;

/// The state published after every step: the lift's (lift::CarSnapshot; quiesced: shutting
/// down, no run, OFF1 (or OFF2) sent, brake and contactors off) and the drive's.
struct ControllerSnapshot : lift::SequencedSnapshot<TravelKind, Phase> {
  bool port_up = false;
  std::array<SlaveSnapshot, kMaxSnapshotSlaves> slaves{};  ///< configured ones, by address
  std::size_t slave_count = 0;
  std::uint8_t drive_address = 0;
  bool drive_heard = false;
  bool link_ok = false;        ///< the drive's replies are current (link_fault_replies)
  std::uint16_t stw_sent = 0;  ///< PZD1 set for the next telegram to the drive
  std::uint16_t zsw = 0;       ///< PZD1 of the drive's last good reply
  ProfileState drive_state = ProfileState::NotReadyToSwitchOn;
  ProfileWish wish = ProfileWish::Stop;
  Supervision supervision = Supervision::None;
  bool acknowledging = false;
  std::int16_t setpoint_raw = 0;  ///< HSW
  double setpoint_percent = 0.0;
  std::int16_t actual_raw = 0;  ///< HIW
  double actual_percent = 0.0;
  bool brake_open = false;
  bool contactors_on = false;
  RxCounters rx{};  ///< A 5.2.3 counters and error word
  std::uint64_t cycles = 0;
  std::chrono::nanoseconds expected_cycle_time{0};
  std::chrono::nanoseconds last_cycle_time{0};
  SpeedName speed = SpeedName::V4;
};

/// The types the shared command handling works on.
using UssCoreTypes =
    lift::CoreTypes<ControllerCommand, CommandReply, ControllerEvent, ControllerSnapshot,
                    LiftTravel, TravelEvent, TravelKind, TravelCommand, DriveInput>;

class UssController final : public uss::UssHooks, public lift::ControllerCore<UssCoreTypes> {
 public:
  /// Throws std::invalid_argument on a bad floor table, a bad travel config or a drive address
  /// the master does not poll.
  UssController(const UssControllerConfig& config, Master& master, const PositionSource& position,
                MonoTime start);

  // ---- io thread: post(), poll_reply(), poll_event(), snapshot(), dropped_events() ----
  std::span<const std::int64_t> floors_mm() const noexcept { return config_.floors_mm; }

  // ---- uss::UssHooks (USS thread) ----
  void after_exchange(MonoTime now) noexcept override;
  void on_port(bool up, MonoTime now) noexcept override;

 private:
  void step(MonoTime now) noexcept;
  void drain_master(MonoTime now) noexcept;
  void handle(const ControllerCommand& command, DriveInput& in) noexcept;
  DriveInput build_input(MonoTime now) const noexcept;
  void update_faults(const DriveInput& in, MonoTime now) noexcept;
  /// The fastest travel speed with a setpoint, in the order DCP 3.5.3.7 adds them (V4 if none).
  SpeedName fastest_speed() const noexcept;
  // What only the USS lift knows, for ControllerCore::step_lift.
  friend class lift::ControllerCore<UssCoreTypes>;
  std::optional<lift::Refusal> drive_travel_refusal(const TravelCommand& command) const noexcept;
  void inspect_run(lift::Direction direction, const DriveInput& in) noexcept;
  void start_call_travel(std::size_t floor, const DriveInput& in) noexcept;
  lift::Cause start_relevel_run(std::size_t floor, lift::Direction direction,
                                const DriveInput& in) noexcept;
  void run_travel(const DriveInput& in) noexcept;
  /// The learning travel needs the crawl V0's setpoint.
  std::optional<lift::Answer> drive_learn_refusal(const DriveInput& in) const noexcept;
  lift::RelevelPolicy relevel_policy() const noexcept;
  /// Starts a learning leg (LiftTravel::start_learning, the approach at the fastest speed).
  bool start_learn_leg(std::int64_t target_mm, lift::Direction direction,
                       const DriveInput& in) noexcept;
  void publish(MonoTime now) noexcept;
  /// The answer to a refusal for `cause` (the drive's own, else every kind's).
  static lift::Refusal refusal(lift::Cause cause) noexcept;

  UssControllerConfig config_;
  Master& master_;
  const PositionSource& position_;

  // USS-thread state.
  bool port_up_ = false;
  bool port_failed_ = false;  ///< the port was lost; the drive has not answered on a new one yet
  DriveOutput last_output_{};
  std::int16_t setpoint_raw_ = 0;
  /// The pass of the polling list the last travel sample was taken in: one sample per pass.
  std::uint64_t sampled_pass_ = ~std::uint64_t{0};
  ProfileState last_state_ = ProfileState::NotReadyToSwitchOn;
  bool last_plc_control_ = true;
  bool state_reported_ = false;
  // Scratch for the master's results (large; kept off the stack of the real-time thread).
  PkwResult pkw_result_{};
  SpontaneousReport report_{};
  CommandReply reply_scratch_{};
  ControllerEvent event_scratch_{};
  ControllerSnapshot snapshot_scratch_{};
};

}  // namespace liftd::uss
