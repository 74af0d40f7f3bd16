// The SCH001 side of one hydraulic lift: the card link (card_link.hpp), the hydraulic travel
// sequencing (hydraulic_travel.hpp) and the drive-neutral lift model (lib/lift) joined into one
// engine that the CAN runner (lib/rt/can_runner.hpp) feeds with frames, bus errors and ticks.
// Talks to the non-real-time side only through lock-free structures: commands in, replies and
// events out (SPSC queues), state out (triple buffer).
//
// Threads: the CAN runner's thread calls the rt::CanEngine methods; ONE other thread (the
// daemon's io thread) calls post(), poll_reply(), poll_event() and snapshot().
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

#include "can/socket.hpp"
#include "common/defaults.hpp"
#include "common/level_zone_source.hpp"
#include "common/mono_time.hpp"
#include "common/position_source.hpp"
#include "lift/controller_core.hpp"
#include "lift/faults.hpp"
#include "lift/inputs.hpp"
#include "lift/lift_model.hpp"
#include "rt/can_runner.hpp"
#include "sch001/card_link.hpp"
#include "sch001/defaults.hpp"
#include "sch001/hydraulic_travel.hpp"

namespace liftd::sch001 {

/// Everything the controller needs, fixed at construction.
struct ControllerConfig {
  CardLinkConfig link;
  HydraulicConfig hydraulic;
  lift::LiftConfig lift;                ///< level tolerance: status car.floor
  std::vector<std::int64_t> floors_mm;  ///< strictly increasing levels (config `floors`)
  MonoTime inputs_timeout = std::chrono::milliseconds(defaults::kInputsTimeoutMs);  ///< inputs.*
  /// travel.inspection_hold_ms
  MonoTime inspection_hold = std::chrono::milliseconds(defaults::kInspectionHoldMs);
  /// Relevel by itself when the car at rest leaves the level zone.
  bool auto_relevel = defaults::kHydraulicAutoRelevel;
  /// The simulated shaft's level zone, read beside the machine inputs' by the learning travel
  /// (liftd --simulate; nullptr otherwise).
  const LevelZoneSource* level_zone_source = nullptr;
};

// ---- commands (io thread -> CAN thread): the shared ones in lib/lift/commands.hpp ----
/// The card's speeds: the fastest the unit has unless the client limits it.
using TravelCommand = lift::BasicTravelCommand<Speed>;
using namespace lift::shared_commands;
using CommandBody = lift::CommandBodyOf<TravelCommand>;
/// A command with the caller's tag (the frame's command bits are `Command` in protocol.hpp).
using ControllerCommand = lift::TaggedCommand<CommandBody>;

// ---- replies and events (CAN thread -> io thread) ----
using lift::CommandReply;
using lift::ReplyCode;

/// Faults; each reported once when it starts and once when it ends. The API names are those of
/// the DCP lift where the meaning is the same.
using lift::fault_code_name;
using lift::FaultCode;
/// The technician's texts of the drive's faults, in the card's terms.
inline constexpr lift::DriveFaultTexts kFaultTexts{
    .link_fault =
        "SCH001 link fault: no frame from the card for 10 s (card document 3f), the CAN "
        "bus or socket failed and the card is not heard again, our answers cannot be sent, "
        "or another node sends on liftd's identifier (card document 1.6); no travel "
        "command goes out",
    .drive_fault = "the SCH001 card reports ERR: no travel command may go out (card document 3d)",
    .advance_warning = {},  // the card has no warning signal
    .position_lost = {},
};

/// What the io thread must hear of, one event each. What can come at the bus's rate (the card's
/// status changes, error frames, frames on our identifier) is counted in the snapshot instead:
/// a flood of those must never push a travel or fault event out of the queue.
struct ControllerEvent {
  enum class Kind : std::uint8_t {
    Link,          ///< `link`: first heard, silent, recovered
    Travel,        ///< `travel`
    Endpoint,      ///< `endpoint_up`: the CAN endpoint opened or failed
    FaultRaised,   ///< `fault`
    FaultCleared,  ///< `fault`
    CallServed,    ///< `floor`
    CallsDropped,  ///< liftd emptied the calls queue: `dropped`, for `cause`
  };
  Kind kind = Kind::Link;
  MonoTime at{};
  LinkChange link = LinkChange::None;
  TravelEvent travel{};
  bool endpoint_up = false;
  FaultCode fault = FaultCode::LinkFault;
  std::size_t floor = 0;
  lift::DroppedCalls dropped{};
  lift::Cause cause = lift::Cause::None;
};

/// Card document 3c: the card sends its status every 100 ms and each one is answered; this many
/// answers in a row that could not be sent (nobody takes our frames) are a link fault.
inline constexpr std::uint32_t kSendFailuresForFault = 3;

using lift::kMaxSnapshotCalls;

/// The state published after every step: the lift's (lift::CarSnapshot; quiesced: shutting
/// down, no travel, no signal in the last answer) and the card's.
struct ControllerSnapshot : lift::SequencedSnapshot<TravelKind, Phase> {
  bool endpoint_up = false;     ///< the CAN endpoint is open and working
  bool heard = false;           ///< the card was heard on the current endpoint
  bool ever_heard = false;      ///< the card was heard since start
  bool endpoint_lost = false;   ///< the endpoint failed; the card is not heard on a new one yet
  bool silent = false;          ///< the card timed out (3f)
  bool send_failing = false;    ///< kSendFailuresForFault answers in a row could not be sent
  bool foreign_sender = false;  ///< another node sent on our identifier in the last 10 s (1.6)
  std::uint64_t status_changes = 0;  ///< the card's status byte changed (journal: card_status)
  bool timeout_enabled = true;
  std::optional<CardStatus> card;
  bool single_unit = true;
  CardLinkCounters counters{};
  std::uint64_t bus_errors = 0;
  can::ErrorReport last_bus_error{};
  CommandBits bits_sent{};  ///< the command byte of the last answer that went out
  std::uint8_t current_floor_sent = 0;
  std::uint8_t destination_floor_sent = 0;
  bool motor_on = false;
};

/// The types the shared command handling works on.
using Sch001CoreTypes =
    lift::CoreTypes<ControllerCommand, CommandReply, ControllerEvent, ControllerSnapshot,
                    HydraulicTravel, TravelEvent, TravelKind, TravelCommand, TickInput>;

class Sch001Controller final : public rt::CanEngine, public lift::ControllerCore<Sch001CoreTypes> {
 public:
  /// Throws std::invalid_argument on a bad floor table.
  Sch001Controller(const ControllerConfig& config, const PositionSource& position, MonoTime start);

  // ---- io thread: post(), poll_reply(), poll_event(), snapshot(), dropped_events() ----
  std::span<const std::int64_t> floors_mm() const noexcept { return config_.floors_mm; }

  // ---- rt::CanEngine (CAN thread) ----
  /// Queues the answer to a card frame in `out` (card document 3c, 3f); the card is answered,
  /// never sent to unasked.
  void on_frame(const can::Frame& frame, MonoTime now, rt::CanOutbox& out) noexcept override;
  void on_bus_error(const can::ErrorReport& report, MonoTime now) noexcept override;
  void on_endpoint(bool up, MonoTime now) noexcept override;
  void on_tick(MonoTime now, rt::CanOutbox& out) noexcept override;
  void on_sent(const can::Frame& frame, bool delivered, MonoTime now) noexcept override;

  /// Direct access for single-threaded tests (and travel()).
  const CardLink& link() const noexcept { return link_; }

 private:
  void step(MonoTime now) noexcept;
  void handle(const ControllerCommand& command, TickInput& in) noexcept;
  TickInput build_input(MonoTime now) noexcept;
  void update_faults(const TickInput& in, MonoTime now) noexcept;
  // What only the hydraulic lift knows, for ControllerCore::step_lift.
  friend class lift::ControllerCore<Sch001CoreTypes>;
  static std::optional<lift::Refusal> drive_travel_refusal(const TravelCommand& command) noexcept;
  void inspect_run(lift::Direction direction, const TickInput& in) noexcept;
  void start_call_travel(std::size_t floor, const TickInput& in) noexcept;
  lift::Cause start_relevel_run(std::size_t floor, lift::Direction direction,
                                const TickInput& in) noexcept;
  void run_travel(const TickInput& in) noexcept;
  bool start_learn_leg(std::int64_t target_mm, lift::Direction direction,
                       const TickInput& in) noexcept;
  static std::optional<lift::Answer> drive_learn_refusal(const TickInput& in) noexcept;
  lift::RelevelPolicy relevel_policy() const noexcept;
  void publish(MonoTime now) noexcept;
  /// The answer to a refusal for `cause` (the card's own, else every kind's).
  static lift::Refusal refusal(lift::Cause cause) noexcept;

  ControllerConfig config_;
  const PositionSource& position_;
  CardLink link_;

  // CAN-thread state.
  bool endpoint_up_ = false;
  bool endpoint_lost_ = false;  ///< the endpoint failed; the card is not heard on a new one yet
  bool bus_fault_ = false;      ///< an error frame said bus-off, error passive, no ACK, ...
  std::uint32_t send_failures_ = 0;    ///< answers in a row that could not be sent
  std::optional<MonoTime> own_id_at_;  ///< the last frame another node sent on our identifier
  bool foreign_sender_ = false;        ///< within kCardTimeout of own_id_at_
  std::uint64_t status_changes_ = 0;
  std::optional<can::Frame> answer_;  ///< the last answer, until on_sent() says it went out
  CommandBits bits_sent_{};           ///< of the last answer that went out
  std::uint8_t current_sent_ = 0;
  std::uint8_t destination_sent_ = 0;
  TickOutput last_output_{};
  std::uint64_t bus_errors_ = 0;
  can::ErrorReport last_bus_error_{};
};

}  // namespace liftd::sch001
