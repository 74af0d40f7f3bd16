// The `sim` command's actions (liftd --simulate only). lib/api holds the actions the simulators
// of several drive kinds take and the form of a kind's own list; each kind declares which shared
// actions its simulator takes and adds its own actions, with their arguments, from its folder
// (lib/<kind>/host/sim_actions.*), named in the registry of drive kinds (lib/kinds/lifts.cpp).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>

#include <nlohmann/json.hpp>

#include "api/result.hpp"
#include "api/schema.hpp"
#include "drive/drive.hpp"

namespace liftd::api {

/// The `sim` actions the simulators of more than one drive kind take.
enum class SimAction : std::uint8_t {
  GeneralFault,      ///< the drive's general fault on/off (DCP S3, SCH001 ERR, USS fault)
  AdvanceWarning,    ///< the drive's advance warning on/off (DCP S2, USS warning)
  NotReady,          ///< the drive not ready on/off (DCP S0 = 0, SCH001 RDY = 0, USS local)
  ReplyFault,        ///< the drive's next `frames` replies carry `fault` (DCP, USS)
  ClearReplyFaults,  ///< ends every injected reply fault (DCP, USS)
  Drift,             ///< moves the stationary car by `drift_mm`
  SafetyChainOpen,   ///< safety chain open (on) or closed (off)
  DoorReversal,      ///< a door reversal (light curtain): closing doors reopen
  OpenDoors,         ///< starts opening the doors (on arrival while the car moves)
  CloseDoors,        ///< starts closing the doors
  ObstructDoors,     ///< holds the doors open (on) or releases them (off)
};
/// Wire names of SimAction, in enum order: the first choices of `sim` `action`.
inline constexpr std::array<std::string_view, 11> kSimActions = {
    "general_fault",      "advance_warning", "not_ready",         "reply_fault",
    "clear_reply_faults", "drift",           "safety_chain_open", "door_reversal",
    "open_doors",         "close_doors",     "obstruct_doors"};

/// A fault on the simulated drive's replies.
enum class SimReplyFault : std::uint8_t {
  NoReply,      ///< no reply at all
  BadChecksum,  ///< reply with a wrong checksum
  S7,           ///< reply with S7 (the drive claims our frame was corrupt)
  Late,         ///< reply outside the DCP 7.2 window
  Garbage,      ///< a few random bytes instead of a frame
};
/// Wire names of SimReplyFault, in enum order.
inline constexpr std::array<std::string_view, 5> kSimReplyFaults = {"no_reply", "bad_checksum",
                                                                    "s7", "late", "garbage"};

/// A set of shared actions, one bit per SimAction.
using SimActionSet = std::uint32_t;
/// The set holding `action`.
constexpr SimActionSet sim_action_bit(SimAction action) {
  return SimActionSet{1} << static_cast<unsigned>(action);
}
/// Every shared action.
inline constexpr SimActionSet kEverySimAction = (SimActionSet{1} << kSimActions.size()) - 1;

/// Arguments of `sim`, validated by the command table.
struct SimRequest {
  std::string_view name = kSimActions[0];  ///< the action's wire name (a table's, static)
  /// A shared action; nullopt: the own action `own` of the drive kind `owner`.
  std::optional<SimAction> shared = SimAction::GeneralFault;
  drive::Kind owner = drive::Kind::Dcp;          ///< !shared: the kind that declared it
  std::size_t own = 0;                           ///< !shared: its index in the kind's list
  bool on = true;                                ///< switches: on (default) or off
  SimReplyFault fault = SimReplyFault::NoReply;  ///< ReplyFault: which fault
  std::uint32_t frames = 1;                      ///< ReplyFault: how many replies
  std::int32_t drift_mm = 0;                     ///< Drift: + up, - down
  nlohmann::json request;  ///< the validated request: a kind's own action reads its arguments
};

/// One drive kind's part of `sim` (lib/<kind>/host/sim_actions.*).
struct KindSimActions {
  drive::Kind kind;
  std::string_view lift_name;  ///< how a refused action names this lift ("DCP", "USS", ...)
  SimActionSet shared;         ///< the shared actions its simulator takes
  std::span<const std::string_view> own;  ///< wire names of its own actions, in its enum order
  /// The arguments only its own actions take (`sim` lists them after `fault`, before the counts
  /// `frames` and `drift_mm`); nullptr: none.
  ArgSchema (*own_args)();
  /// A refusal of a request for its own action `own` that lacks an argument (checked on every
  /// lift, before the backend); nullptr: none needed.
  std::optional<Result> (*check)(std::size_t own, const nlohmann::json& request);

  /// Whether this kind's simulator takes `request`'s action.
  bool takes(const SimRequest& request) const noexcept {
    if (request.shared) return (shared & sim_action_bit(*request.shared)) != 0;
    return request.owner == kind;
  }
};

/// `sim` with an action this lift's simulator does not take: bad_request, naming the action and
/// the lift.
Result sim_action_refused(const SimRequest& request, std::string_view this_lift);

}  // namespace liftd::api
