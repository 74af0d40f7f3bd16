// The DCP controller: what runs inside the 15 ms cycle for a DCP drive. It joins the master link
// (lib/dcp), the travel sequencers (lib/dcp/travel) and the lift (lib/lift) into one
// rt::CycleEngine. The command plumbing, the rules and the fault table every lift has are
// lift::ControllerCore's, as on the SCH001 and USS lifts: commands in, replies and events out
// (lock-free queues), state out (triple buffer), inputs, inspection, calls, the first travel gates.
//
// Threads: the cycle thread calls the rt::CycleEngine methods; ONE other thread (the daemon's
// io thread) calls post(), poll_reply(), poll_event() and snapshot().
#pragma once

#include <array>
#include <atomic>
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
#include "common/snapshot_box.hpp"
#include "dcp/master_link.hpp"
#include "dcp/travel/controller.hpp"
#include "lift/controller_core.hpp"
#include "lift/faults.hpp"
#include "lift/inputs.hpp"
#include "lift/level_learner.hpp"
#include "lift/lift_model.hpp"
#include "rt/cycle_runner.hpp"

namespace liftd::control {

/// The position source of every drive kind (lib/common/position_source.hpp).
using liftd::PositionFeed;
using liftd::PositionSource;

/// Everything the controller needs, fixed at construction.
struct ControllerConfig {
  dcp::MasterLinkConfig link;
  travel::TravelConfig travel;
  lift::LiftConfig lift;
  std::vector<std::int64_t> floors_mm;  ///< strictly increasing levels (config `floors`)
  /// Inputs older than this count as lost: a fault for any travel (config inputs.timeout_ms).
  MonoTime inputs_timeout = std::chrono::milliseconds(defaults::kInputsTimeoutMs);
  /// An API inspection direction must be repeated within this (config travel.inspection_hold_ms).
  MonoTime inspection_hold = std::chrono::milliseconds(defaults::kInspectionHoldMs);
  /// The simulated shaft's level zone, read at the cycle's instant beside the machine inputs'
  /// level zone by the learning travel (liftd --simulate; nullptr otherwise).
  const LevelZoneSource* level_zone_source = nullptr;
};

// ---- commands (non-RT -> cycle); the ones every lift takes are lift::ControllerCore's ----

/// Go to a floor; extends a running DCP4 travel where the spec allows.
struct TravelCommand {
  std::size_t floor = 0;
  std::optional<dcp::Speed> speed;  ///< nullopt: fastest the installation allows
  std::optional<std::uint8_t> load_percent;
  bool fast_start = false;  ///< DCP 12: arm fast start, go when the doors are locked
};
/// Stop at the next possible floor (DCP4: remaining distance retargeted; DCP3: crawl from that
/// floor's deceleration point); other travels end with the controlled stop.
using lift::StopCommand;
/// The service is stopping: no new travel, the running one stops as StopCommand does; `force`
/// (deadline passed) withdraws the drive enable at once.
using lift::ShutdownCommand;
/// DCP 13 fast stop.
struct FastStopCommand {};
/// Relevel to the floor the car is at (DCP4 VN', DCP3 relevelling without distance).
using lift::RelevelCommand;
/// Software inspection: switch on/off and hold a direction (must be repeated).
using lift::InspectionCommand;
/// Fast start: the go signal (checks the doors) or abort (controlled stop).
struct FastStartCommand {
  enum class Action : std::uint8_t { Go, Abort };
  Action action = Action::Go;
};
/// Queue a destination / cancel one.
using lift::CallCommand;
/// The machine's inputs, complete (the provider merges partial updates).
using lift::InputsCommand;
/// An I-message for the drive (I2, I6, I8, I9, keypad).
struct LinkCommand {
  dcp::Request request;
};
/// Wall-clock time for I3 (sent every second by the non-RT side).
struct ClockCommand {
  dcp::CivilTime time;
};
using lift::LearnCommand;

using CommandBody = std::variant<TravelCommand, StopCommand, FastStopCommand, RelevelCommand,
                                 InspectionCommand, FastStartCommand, CallCommand, InputsCommand,
                                 LinkCommand, ClockCommand, ShutdownCommand, LearnCommand>;

/// What a learning travel found (lift/learning_travel.hpp).
using lift::LearnRecord;
/// The learning travel's approach and run-out (lift/learning_travel.hpp).
using lift::kLearnApproachMm;
using lift::kLearnRunOutMm;
/// A learning leg's crawl limit: the configured crawl time plus this many ms per mm of the leg.
inline constexpr std::uint32_t kLearnCrawlMsPerMm = lift::kLearnMsPerMm;

/// A command with the caller's tag (echoed in the reply; 0 = no reply wanted).
using Command = lift::TaggedCommand<CommandBody>;

// ---- replies and events (cycle -> non-RT) ----

/// How a command ended, as on every lift (the API's error codes).
using lift::ReplyCode;

/// The answer to one tagged command. `detail` points to a static string.
struct CommandReply {
  std::uint32_t tag = 0;
  ReplyCode code = ReplyCode::Ok;
  std::string_view detail;
  std::optional<dcp::DriveMessage> drive_reply;  ///< for link commands
  bool extended = false;                         ///< travel command extended a running travel
  std::optional<std::size_t> floor;              ///< stop: the floor the car will stop at
};

/// Faults the controller tracks; each is reported once when it starts and once when it ends.
using lift::fault_code_name;
using lift::FaultCode;
/// The technician's texts of the drive's faults.
inline constexpr lift::DriveFaultTexts kFaultTexts{
    .link_fault =
        "DCP link fault: replies missing or corrupt (DCP 7.3) or serial port lost; "
        "drive enable is off",
    .drive_fault = "drive reports a general fault (S3); drive enable is off until it clears",
    .advance_warning = "drive advance warning (S2): no new travel until it clears (DCP 9.1.5)",
    .position_lost = "absolute car position invalid or stale; no DCP4 travel possible",
};

/// Something that happened, drained by the non-RT side for the journal and the watch stream.
struct ControllerEvent {
  enum class Kind : std::uint8_t {
    Link,          ///< `link` is set
    Travel,        ///< `travel` is set
    DriveError,    ///< `drive_error` is set (DCP 5.11)
    FaultRaised,   ///< `fault`
    FaultCleared,  ///< `fault`
    CallServed,    ///< `floor` was reached and left the calls queue
    CallsDropped,  ///< liftd emptied the calls queue: `dropped`, for `cause`
  };
  Kind kind = Kind::Link;
  MonoTime at{};
  dcp::LinkEvent link{};
  travel::Event travel{};
  dcp::DriveErrorText drive_error{};
  FaultCode fault = FaultCode::LinkFault;
  std::size_t floor = 0;
  lift::DroppedCalls dropped{};
  lift::Cause cause = lift::Cause::None;
};

/// Bound on queued calls shown in the snapshot.
using lift::kMaxSnapshotCalls;

/// The state published after every cycle: the lift's (lift::CarSnapshot; quiesced: shutting
/// down and at rest, no travel, S1 = 0, and at least one DCP 7.3 supervision window of frames
/// without B0/B1/B2 gone out; drive_allows_travel: travel::CommandGate::drive_forbidding() of
/// the link and status as published) and the drive's.
struct ControllerSnapshot : lift::CarSnapshot {
  std::uint64_t cycle = 0;
  dcp::LinkState link = dcp::LinkState::Down;
  std::optional<dcp::Protocol> protocol;
  std::optional<dcp::InitReply> drive_info;
  std::optional<std::uint8_t> status_byte;
  std::optional<dcp::ExtendedStatus> extended;
  std::optional<std::uint32_t> decel_distance_mm;
  dcp::PowerReply power_mode{};
  travel::TravelKind travel_kind = travel::TravelKind::None;
  bool fast_start_armed = false;
  bool brake_open = false;     ///< mechanical brake output, follows S6 (DCP 9.1.7)
  bool contactors_on = false;  ///< motor contactors output
  std::uint8_t command = 0;    ///< B0..B6 of the last frame's process data
  std::uint16_t data_word = 0;
  std::array<std::array<std::uint8_t, dcp::kDisplayColumns>, dcp::kDisplayRows> display{};
  std::uint32_t display_version = 0;
  dcp::LinkCounters link_counters{};
  std::optional<std::int64_t> last_travel_measured_mm;  ///< I9 extended reply (rope slip)
  std::optional<std::int64_t> last_travel_slip_mm;      ///< measured minus commanded distance
  /// Why the handshake has not completed (empty when it has, DCP 5.12.2).
  std::string_view handshake_problem;
};

/// The types lift::ControllerCore works on for a DCP lift.
using DcpCoreTypes = lift::CoreTypes<Command, CommandReply, ControllerEvent, ControllerSnapshot,
                                     travel::TravelController, travel::Event, travel::TravelKind,
                                     TravelCommand, travel::CycleInput>;

/// The DCP side of one lift, run by an rt::CycleRunner.
class DcpController final : public rt::CycleEngine, public lift::ControllerCore<DcpCoreTypes> {
 public:
  /// Throws std::invalid_argument on a bad link/travel config or floor table (at start-up).
  DcpController(const ControllerConfig& config, const PositionSource& position);

  // ---- io thread: post(), poll_reply(), poll_event(), snapshot(), dropped_events() ----
  /// Floor levels as configured.
  std::span<const std::int64_t> floors_mm() const noexcept { return config_.floors_mm; }

  // ---- rt::CycleEngine (cycle thread) ----
  std::span<const std::uint8_t> frame_to_send(MonoTime now) noexcept override;
  std::size_t reply_size() const noexcept override { return dcp::kFrameSize; }
  bool on_reply(std::span<const std::uint8_t> reply, MonoTime now) noexcept override;
  void on_no_reply(MonoTime now) noexcept override { link_.on_no_reply(now); }
  void on_bad_reply(MonoTime now) noexcept override { link_.on_bad_reply(now); }
  void on_port_lost(MonoTime now) noexcept override { link_.on_port_lost(now); }
  void after_cycle(MonoTime now) noexcept override;

  /// Direct access for in-process tests and benchmarks driven on one thread (and travel()).
  const dcp::MasterLink& link() const noexcept { return link_; }

 private:
  struct Internal {  // a channel request the travel made; its reply goes back to the travel
    bool active = false;
    travel::ChannelRequest::Kind kind = travel::ChannelRequest::Kind::StartParameters;
  };
  static constexpr dcp::RequestTag kTravelTag = 0xFFFF'FFFFU;
  static constexpr std::uint32_t kInternalTag = 0xFFFF'FFFEU;  ///< a change without a caller

  void handle(const Command& command, travel::CycleInput& in) noexcept;
  void handle_travel(std::uint32_t tag, const TravelCommand& cmd) noexcept;
  void handle_relevel(std::uint32_t tag) noexcept;
  /// What a running travel is doing, for a stop: moving under a DCP4 distance or a DCP3 speed
  /// travel, and (DCP3) still before its deceleration point.
  struct MovingTravel {
    bool dcp4 = false;
    bool dcp3 = false;
    bool before_decel_point = false;
  };
  MovingTravel moving_travel() const noexcept;
  /// Ends the running travel as `stop` does; the floor it will stop at (nullopt: ended at once).
  std::optional<std::size_t> stop_travel() noexcept;
  /// `calls cancel` of the floor the running travel heads for.
  void cancel_target(std::uint32_t tag, std::size_t floor) noexcept;
  void handle_stop(std::uint32_t tag) noexcept;
  void handle_learn(std::uint32_t tag) noexcept;
  /// The drive's refusal of a learning leg (not ready, general fault), as a travel's start has.
  std::optional<lift::Answer> drive_refuses_learning() const noexcept;
  /// Starts a learning leg to `target_mm`: up at crawl by position, down as a travel would go.
  bool start_learn_leg(std::int64_t target_mm, lift::Direction direction) noexcept;
  /// After a learning leg ended: the next leg, or the learning's end (ControllerCore).
  void step_learn() noexcept;
  std::optional<std::size_t> next_stop_floor() const noexcept;
  void settle_extension(const travel::Event& event) noexcept;
  void owe_position(MonoTime now) noexcept;
  /// The travel command moved the running travel's target (reply `extended`).
  void reply_extended(std::uint32_t tag) noexcept;
  travel::CycleInput build_input(MonoTime now) noexcept;
  /// The link's and the drive's part of a cycle input as the link knows them now: link and
  /// handshake, protocol, status, deceleration distance, extended status.
  void read_drive(travel::CycleInput& in) const noexcept;
  void submit_channel(const travel::ChannelRequest& request) noexcept;
  void drain_link(MonoTime now) noexcept;
  void drain_travel(MonoTime now) noexcept;
  void serve_calls() noexcept;
  void update_faults(const travel::CycleInput& in, MonoTime now) noexcept;
  void publish(MonoTime now) noexcept;
  /// The command and status bytes of this cycle and the remaining distance sent, for the travel
  /// curve (lift::TravelSample).
  lift::DriveBits drive_bits() const noexcept;
  std::optional<std::string_view> not_ready_reason(bool fast_start) const noexcept;
  dcp::Speed choose_dcp3_speed(std::int64_t distance_mm) const noexcept;

  ControllerConfig config_;
  const PositionSource& position_;
  dcp::MasterLink link_;

  std::array<Command, lift::kCommandQueueSize> deferred_{};  ///< this cycle's commands after inputs

  // Cycle-thread state.
  dcp::FrameBytes frame_{};
  travel::CycleInput last_input_{};
  travel::CycleOutput last_output_{};
  Internal internal_;
  std::optional<travel::ChannelReply> pending_reply_;
  std::optional<std::size_t> target_floor_;
  std::uint32_t travel_tag_ = 0;  ///< tag of the command that started the running travel
  std::uint32_t extend_tag_ = 0;  ///< a travel command whose target change waits for S5
  std::size_t extend_floor_ = 0;
  bool position_owed_ = false;  ///< DCP 5.12.9: I9 after every stop, not sent yet
  std::optional<std::int64_t> previous_position_mm_;  ///< last cycle's position
  travel::TravelKind last_kind_ = travel::TravelKind::None;
  std::uint32_t frames_at_rest_ = 0;  ///< frames in a row without B0/B1/B2
  std::optional<std::int64_t> travel_start_mm_;
  std::optional<std::int64_t> pending_i9_travel_mm_;  ///< commanded distance, for slip
  std::optional<std::int64_t> measured_mm_;
  std::optional<std::int64_t> slip_mm_;
  bool fast_start_armed_ = false;
  std::uint64_t cycle_ = 0;
};

}  // namespace liftd::control
