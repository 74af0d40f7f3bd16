// The `sim` actions only the simulated DCP drive takes (channel_fault, refuse_target), with the
// `channel` argument, and the shared actions its simulator takes (every one).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "api/sim.hpp"

namespace liftd::daemon {

/// The simulated DCP drive's own `sim` actions.
enum class DcpSimAction : std::uint8_t {
  ChannelFault,  ///< a fault on the drive's communication channel only (DCP 5)
  RefuseTarget,  ///< the drive refuses the next target change with S5 (DCP 4.1)
};
/// Wire names of DcpSimAction, in enum order.
inline constexpr std::array<std::string_view, 2> kDcpSimActions = {"channel_fault",
                                                                   "refuse_target"};

/// A fault on the simulated drive's communication channel (DCP 5), the real-time bytes intact.
enum class SimChannelFault : std::uint8_t {
  Partial,  ///< STX and the start of a message, never an ETX (the master resets after 1 s)
  Garbage,  ///< a frame with an undefined mode byte and stray control characters
  Silence,  ///< 1.5 s of idle channel bytes, the master's channel bytes unheard
};
/// Wire names of SimChannelFault, in enum order.
inline constexpr std::array<std::string_view, 3> kSimChannelFaults = {"partial", "garbage",
                                                                      "silence"};

/// One of the DCP drive's own actions, with its argument.
struct DcpSimRequest {
  DcpSimAction action = DcpSimAction::ChannelFault;
  SimChannelFault channel = SimChannelFault::Partial;  ///< ChannelFault: which fault
};
/// The DCP action of `request` (one the DCP kind declared: !request.shared, owner Dcp).
DcpSimRequest dcp_sim_request(const api::SimRequest& request);

/// The DCP kind's part of `sim`, for the registry of drive kinds.
extern const api::KindSimActions kDcpSimActionTable;

}  // namespace liftd::daemon
