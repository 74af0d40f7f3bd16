// What the kernel says about a CAN interface (rtnetlink): whether it exists, whether it is up,
// and its bitrate where the driver reports one. Bitrate and state are the system's business
// (systemd-networkd [CAN] BitRate=); liftd only warns at start when they look wrong.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

namespace liftd::can {

struct InterfaceInfo {
  bool found = false;                    ///< the interface exists
  bool up = false;                       ///< IFF_UP
  std::optional<std::uint32_t> bitrate;  ///< bit/s, where readable (IFLA_CAN_BITTIMING)
  std::string error;                     ///< why nothing could be read (netlink refused, ...)
};

/// Asks the kernel about interface `name` over rtnetlink (never blocks for long: one request,
/// one reply, 1 s receive timeout).
InterfaceInfo query_interface(const std::string& name);

}  // namespace liftd::can
