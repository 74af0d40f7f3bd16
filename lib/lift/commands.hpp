// The commands every lift takes (io thread -> real-time thread), their replies, the queues'
// sizes, the refusals every kind words alike and a kind's own table of them, and the types a
// kind's controller names once (CoreTypes). What ControllerCore (lift/controller_core.hpp)
// handles and answers.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>
#include <variant>

#include "lift/calls.hpp"
#include "lift/cause.hpp"
#include "lift/inputs.hpp"
#include "lift/rules.hpp"

namespace liftd::lift {

// ---- commands (io thread -> real-time thread) ----

/// Travel to `floor` at `speed` (the drive's speed names; V4 unless the client asks otherwise).
template <typename Speed>
struct BasicTravelCommand {
  std::size_t floor = 0;
  Speed speed = Speed::V4;
};
struct StopCommand {};
struct RelevelCommand {};
/// The learning travel (lift/learning_travel.hpp on the hydraulic and USS lifts; DCP's crawls
/// through the level zones as DCP 10.3 allows): answered when it ends, with the record in the
/// controller's learn_record().
struct LearnCommand {};
struct InspectionCommand {
  bool on = false;
  Direction direction = Direction::None;
};
struct InputsCommand {
  Inputs inputs;
};
/// The service is stopping: no new travel, the running one lands as `stop` does; `force` ends
/// it at once (the drive's hardest stop: SCH001 drops every signal, USS coasts by OFF2).
struct ShutdownCommand {
  bool force = false;
};
/// A command with the caller's tag.
template <typename Body>
struct TaggedCommand {
  std::uint32_t tag = 0;  ///< echoed in the reply; 0 = no reply wanted
  Body body;
};

/// The commands every lift takes besides its travel. A kind's controller header names them with
/// `using namespace lift::shared_commands;` in its namespace and puts them in its command variant
/// with CommandBodyOf.
namespace shared_commands {
using lift::CallCommand;
using lift::InputsCommand;
using lift::InspectionCommand;
using lift::LearnCommand;
using lift::RelevelCommand;
using lift::ShutdownCommand;
using lift::StopCommand;
}  // namespace shared_commands

/// A kind's command variant: its travel command, the commands every lift takes, then its own.
template <typename TravelCommand, typename... Own>
using CommandBodyOf =
    std::variant<TravelCommand, StopCommand, RelevelCommand, InspectionCommand, CallCommand,
                 InputsCommand, ShutdownCommand, LearnCommand, Own...>;

// ---- replies (real-time thread -> io thread) ----
struct CommandReply {
  std::uint32_t tag = 0;
  ReplyCode code = ReplyCode::Ok;
  std::string_view detail;           ///< a static string
  std::optional<std::size_t> floor;  ///< stop / relevel: where the car will stop
};

/// Why a command is refused: the reply's code and text.
struct Refusal {
  ReplyCode code = ReplyCode::NotReady;
  std::string_view detail;  ///< a static string
};

inline constexpr std::size_t kCommandQueueSize = 64;
inline constexpr std::size_t kReplyQueueSize = 64;
inline constexpr std::size_t kEventQueueSize = 256;
/// Travel samples between two io-thread polls: the io thread wakes after every step, so 512
/// holds 7.6 s of 15 ms DCP cycles should it stall.
inline constexpr std::size_t kTravelSampleQueueSize = 512;

/// The types a kind's controller works on, named once per kind: its command variant, reply,
/// event and snapshot, its travel sequencer with that sequencer's event, kind and command, and
/// the input of one step.
template <typename CommandT, typename ReplyT, typename EventT, typename SnapshotT, typename TravelT,
          typename TravelEventT, typename TravelKindT, typename TravelCommandT, typename InputT>
struct CoreTypes {
  using Command = CommandT;
  using Reply = ReplyT;
  using Event = EventT;
  using Snapshot = SnapshotT;
  using Travel = TravelT;
  using TravelEvent = TravelEventT;
  using TravelKind = TravelKindT;
  using TravelCommand = TravelCommandT;
  using Input = InputT;
};

/// The reply code of a refusal for a cause both drives' travels know; NotReady for the others.
constexpr ReplyCode shared_cause_code(Cause cause) noexcept {
  switch (cause) {
    case Cause::SafetyChainOpen:
    case Cause::InputsLost:
    case Cause::PositionLost:
      return ReplyCode::Fault;
    default:
      return ReplyCode::NotReady;
  }
}

/// The reply text of a refusal for a cause both drives' travels know.
constexpr std::string_view shared_cause_text(Cause cause) noexcept {
  switch (cause) {
    case Cause::SafetyChainOpen:
      return "safety chain open";
    case Cause::DoorsNotLocked:
      return "doors not locked";
    case Cause::InputsLost:
      return "machine inputs missing or stale";
    case Cause::PositionLost:
      return "no valid car position";
    default:
      return "not possible now";
  }
}

/// A drive kind's own answer to a refusal for a cause its travels report: the reply code and
/// text (a kind's table of them, refusal_for()).
struct CauseRefusal {
  Cause cause = Cause::None;
  ReplyCode code = ReplyCode::NotReady;
  std::string_view text;  ///< a static string
};

/// The refusal for `cause` by a kind's own table, else the one every kind gives.
constexpr Refusal refusal_for(std::span<const CauseRefusal> own, Cause cause) noexcept {
  for (const CauseRefusal& r : own) {
    if (r.cause == cause) return Refusal{r.code, r.text};
  }
  return Refusal{shared_cause_code(cause), shared_cause_text(cause)};
}

/// The refusal of a normal travel, a learning travel or a relevelling while the inspection or
/// recall switch is on (DCP 9.1.1), on every drive kind.
inline constexpr std::string_view kButtonModeText = "inspection or recall is switched on";

/// The relevel command's refusal without a position and without a single relevelling signal.
inline constexpr std::string_view kNoRelevelReference =
    "no position and no single relevelling signal (relevel_up / relevel_down)";

}  // namespace liftd::lift
