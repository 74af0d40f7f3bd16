// The DCP controller: what runs inside the 15 ms cycle for a DCP drive. It joins the master link
// (lib/dcp), the travel sequencers (lib/travel) and the lift model (lib/lift) into one
// rt::CycleEngine, and talks to the non-real-time side only through lock-free structures:
// commands in (SPSC queue), replies and events out (SPSC queues), state out (triple buffer).
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

#include "common/mono_time.hpp"
#include "config/defaults.hpp"
#include "dcp/master_link.hpp"
#include "dcp/travel/controller.hpp"
#include "lift/faults.hpp"
#include "lift/inputs.hpp"
#include "lift/lift_model.hpp"
#include "lift/position_source.hpp"
#include "lift/rules.hpp"
#include "rt/cycle_runner.hpp"
#include "rt/snapshot.hpp"
#include "rt/spsc_queue.hpp"

namespace liftd::control {

/// The position source of every drive kind (lib/lift/position_source.hpp).
using lift::PositionFeed;
using lift::PositionSource;

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
};

// ---- commands (non-RT -> cycle) ----

/// Go to a floor; extends a running DCP4 travel where the spec allows.
struct TravelCommand {
  std::size_t floor = 0;
  std::optional<dcp::Speed> speed;  ///< nullopt: fastest the installation allows
  std::optional<std::uint8_t> load_percent;
  bool fast_start = false;  ///< DCP 12: arm fast start, go when the doors are locked
};
/// Stop at the next possible floor (DCP4: remaining distance retargeted; DCP3: crawl from that
/// floor's deceleration point); other travels end with the controlled stop.
struct StopCommand {};
/// The service is stopping: no new travel, the running one stops as StopCommand does; `force`
/// (deadline passed) withdraws the drive enable at once.
struct ShutdownCommand {
  bool force = false;
};
/// DCP 13 fast stop.
struct FastStopCommand {};
/// Relevel to the floor the car is at (DCP4 VN', DCP3 relevelling without distance).
struct RelevelCommand {};
/// Software inspection: switch on/off and hold a direction (must be repeated).
struct InspectionCommand {
  bool on = false;
  lift::Direction direction = lift::Direction::None;
};
/// Fast start: the go signal (checks the doors) or abort (controlled stop).
struct FastStartCommand {
  enum class Action : std::uint8_t { Go, Abort };
  Action action = Action::Go;
};
/// Queue a destination / cancel one.
struct CallCommand {
  bool add = true;
  std::size_t floor = 0;
};
/// The machine's inputs, complete (the provider merges partial updates).
struct InputsCommand {
  lift::Inputs inputs;
};
/// An I-message for the drive (I2, I6, I8, I9, keypad).
struct LinkCommand {
  dcp::Request request;
};
/// Wall-clock time for I3 (sent every second by the non-RT side).
struct ClockCommand {
  dcp::CivilTime time;
};

using CommandBody = std::variant<TravelCommand, StopCommand, FastStopCommand, RelevelCommand,
                                 InspectionCommand, FastStartCommand, CallCommand, InputsCommand,
                                 LinkCommand, ClockCommand, ShutdownCommand>;

/// A command with the caller's tag (echoed in the reply; 0 = no reply wanted).
struct Command {
  std::uint32_t tag = 0;
  CommandBody body;
};

// ---- replies and events (cycle -> non-RT) ----

/// How a command ended. Mirrors the API's error codes.
enum class ReplyCode : std::uint8_t {
  Ok,
  NotReady,    ///< a condition forbids it now (detail names it)
  Busy,        ///< something else is running
  BadRequest,  ///< the request cannot apply to this lift (detail says why)
  Fault,       ///< the drive or link is in fault
  Timeout,     ///< the drive did not answer
};

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
/// One line of explanation for a technician.
std::string_view fault_text(FaultCode code) noexcept;

/// Something that happened, drained by the non-RT side for the journal and the watch stream.
struct ControllerEvent {
  enum class Kind : std::uint8_t {
    Link,          ///< `link` is set
    Travel,        ///< `travel` is set
    DriveError,    ///< `drive_error` is set (DCP 5.11)
    FaultRaised,   ///< `fault`
    FaultCleared,  ///< `fault`
    CallServed,    ///< `floor` was reached and left the calls queue
  };
  Kind kind = Kind::Link;
  MonoTime at{};
  dcp::LinkEvent link{};
  travel::Event travel{};
  dcp::DriveErrorText drive_error{};
  FaultCode fault = FaultCode::LinkFault;
  std::size_t floor = 0;
};

/// Bound on queued calls shown in the snapshot.
inline constexpr std::size_t kMaxSnapshotCalls = 64;

/// The state published after every cycle.
struct ControllerSnapshot {
  std::uint64_t cycle = 0;
  MonoTime at{};
  dcp::LinkState link = dcp::LinkState::Down;
  std::optional<dcp::Protocol> protocol;
  std::optional<dcp::InitReply> drive_info;
  std::optional<std::uint8_t> status_byte;
  std::optional<dcp::ExtendedStatus> extended;
  std::optional<std::uint32_t> decel_distance_mm;
  dcp::PowerReply power_mode{};
  std::optional<std::int64_t> position_mm;
  std::optional<std::size_t> floor;
  std::optional<std::size_t> next_possible_stop;
  travel::TravelKind travel_kind = travel::TravelKind::None;
  lift::Direction direction = lift::Direction::None;
  std::optional<std::size_t> target_floor;
  bool fast_start_armed = false;
  bool brake_open = false;     ///< mechanical brake output, follows S6 (DCP 9.1.7)
  bool contactors_on = false;  ///< motor contactors output
  std::uint8_t command = 0;    ///< B0..B6 of the last frame's process data
  std::uint16_t data_word = 0;
  lift::Inputs inputs{};  ///< effective inputs (provider + API inspection)
  std::array<std::uint8_t, kMaxSnapshotCalls> calls{};
  std::size_t call_count = 0;
  std::array<std::array<std::uint8_t, dcp::kDisplayColumns>, dcp::kDisplayRows> display{};
  std::uint32_t display_version = 0;
  dcp::LinkCounters link_counters{};
  std::array<bool, static_cast<std::size_t>(FaultCode::kCount)> faults{};
  std::array<MonoTime, static_cast<std::size_t>(FaultCode::kCount)> fault_since{};
  std::optional<std::int64_t> last_travel_measured_mm;  ///< I9 extended reply (rope slip)
  std::optional<std::int64_t> last_travel_slip_mm;      ///< measured minus commanded distance
  /// Why the handshake has not completed (empty when it has, DCP 5.12.2).
  std::string_view handshake_problem;
  bool shutting_down = false;  ///< ShutdownCommand received
  /// Shutting down and at rest: no travel, S1 = 0, and at least one DCP 7.3 supervision window
  /// of frames without B0/B1/B2 has gone out.
  bool quiesced = false;
  /// The drive lets a travel start now: travel::CommandGate::drive_forbidding() of the link and
  /// status as published, the check a travel command passes (status `drive.state`).
  bool drive_allows_travel = false;
};

inline constexpr std::size_t kCommandQueueSize = 64;
inline constexpr std::size_t kReplyQueueSize = 64;
inline constexpr std::size_t kEventQueueSize = 256;

/// The DCP side of one lift, run by an rt::CycleRunner.
class DcpController final : public rt::CycleEngine {
 public:
  /// Throws std::invalid_argument on a bad link/travel config or floor table (at start-up).
  DcpController(const ControllerConfig& config, const PositionSource& position);

  // ---- non-real-time side (one thread) ----
  /// Queues a command for the next cycle; false when the queue is full.
  bool post(const Command& command) noexcept { return commands_.try_push(command); }
  /// The next reply to a tagged command.
  bool poll_reply(CommandReply& out) noexcept { return replies_.try_pop(out); }
  /// The next event.
  bool poll_event(ControllerEvent& out) noexcept { return events_.try_pop(out); }
  /// The latest published state.
  ControllerSnapshot snapshot() noexcept { return snapshot_.read(); }
  /// Events lost because a queue was full: ours to the io thread or the travel controller's own
  /// (read on any thread; stats cycle.dropped_events).
  std::uint64_t dropped_events() const noexcept {
    return dropped_events_.load(std::memory_order_relaxed) +
           travel_dropped_.load(std::memory_order_relaxed);
  }
  /// Floor levels as configured.
  std::span<const std::int64_t> floors_mm() const noexcept { return floors_mm_; }

  // ---- rt::CycleEngine (cycle thread) ----
  std::span<const std::uint8_t> frame_to_send(MonoTime now) noexcept override;
  std::size_t reply_size() const noexcept override { return dcp::kFrameSize; }
  bool on_reply(std::span<const std::uint8_t> reply, MonoTime now) noexcept override;
  void on_no_reply(MonoTime now) noexcept override { link_.on_no_reply(now); }
  void on_port_lost(MonoTime now) noexcept override { link_.on_port_lost(now); }
  void after_cycle(MonoTime now) noexcept override;

  /// Direct access for in-process tests and benchmarks driven on one thread.
  const dcp::MasterLink& link() const noexcept { return link_; }
  const travel::TravelController& travel() const noexcept { return travel_; }

 private:
  struct Internal {  // a channel request the travel made; its reply goes back to the travel
    bool active = false;
    travel::ChannelRequest::Kind kind = travel::ChannelRequest::Kind::StartParameters;
  };
  static constexpr dcp::RequestTag kTravelTag = 0xFFFF'FFFFU;
  static constexpr std::uint32_t kInternalTag = 0xFFFF'FFFEU;  ///< a change without a caller

  void handle(const Command& command, MonoTime now) noexcept;
  void handle_travel(std::uint32_t tag, const TravelCommand& cmd) noexcept;
  void handle_relevel(std::uint32_t tag) noexcept;
  void handle_stop(std::uint32_t tag) noexcept;
  std::optional<std::size_t> next_stop_floor() const noexcept;
  void settle_extension(const travel::Event& event) noexcept;
  void owe_position(MonoTime now) noexcept;
  void reply(std::uint32_t tag, ReplyCode code, std::string_view detail = {},
             bool extended = false) noexcept;
  void push_event(const ControllerEvent& event) noexcept;
  travel::CycleInput build_input(MonoTime now) noexcept;
  /// The link's and the drive's part of a cycle input as the link knows them now: link and
  /// handshake, protocol, status, deceleration distance, extended status.
  void read_drive(travel::CycleInput& in) const noexcept;
  lift::Inputs effective_inputs(MonoTime now) const noexcept;
  void submit_channel(const travel::ChannelRequest& request) noexcept;
  void drain_link(MonoTime now) noexcept;
  void drain_travel(MonoTime now) noexcept;
  void serve_calls() noexcept;
  void update_faults(const travel::CycleInput& in, MonoTime now) noexcept;
  void set_fault(FaultCode code, bool active, MonoTime now) noexcept;
  void publish(MonoTime now) noexcept;
  std::optional<std::string_view> not_ready_reason(bool fast_start) const noexcept;
  dcp::Speed choose_dcp3_speed(std::int64_t distance_mm) const noexcept;

  ControllerConfig config_;
  std::vector<std::int64_t> floors_mm_;
  const PositionSource& position_;
  dcp::MasterLink link_;
  travel::TravelController travel_;
  lift::LiftModel lift_;

  rt::SpscQueue<Command, kCommandQueueSize> commands_;
  std::array<Command, kCommandQueueSize> deferred_{};  ///< this cycle's commands after inputs
  rt::SpscQueue<CommandReply, kReplyQueueSize> replies_;
  rt::SpscQueue<ControllerEvent, kEventQueueSize> events_;
  rt::Snapshot<ControllerSnapshot> snapshot_;
  std::atomic<std::uint64_t> dropped_events_{0};
  std::atomic<std::uint64_t> travel_dropped_{0};  ///< the travel's own count, copied each cycle

  // Cycle-thread state.
  dcp::FrameBytes frame_{};
  travel::CycleInput last_input_{};
  travel::CycleOutput last_output_{};
  lift::LiftRules rules_;  ///< inputs, inspection, start grace and calls, as every lift has them
  Internal internal_;
  std::optional<travel::ChannelReply> pending_reply_;
  std::optional<std::size_t> target_floor_;
  std::uint32_t travel_tag_ = 0;  ///< tag of the command that started the running travel
  std::uint32_t extend_tag_ = 0;  ///< a travel command whose target change waits for S5
  std::size_t extend_floor_ = 0;
  bool position_owed_ = false;  ///< DCP 5.12.9: I9 after every stop, not sent yet
  std::optional<std::int64_t> previous_position_mm_;  ///< last cycle's position
  travel::TravelKind last_kind_ = travel::TravelKind::None;
  bool shutting_down_ = false;
  std::uint32_t frames_at_rest_ = 0;  ///< frames in a row without B0/B1/B2
  std::optional<std::int64_t> travel_start_mm_;
  std::optional<std::int64_t> pending_i9_travel_mm_;  ///< commanded distance, for slip
  std::optional<std::int64_t> measured_mm_;
  std::optional<std::int64_t> slip_mm_;
  bool fast_start_armed_ = false;
  lift::FaultTable faults_;  ///< each raise and clear told once, never lost to a full queue
  std::uint64_t cycle_ = 0;
};

}  // namespace liftd::control
