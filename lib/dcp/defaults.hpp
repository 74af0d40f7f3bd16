// The DCP lift's defaults: the defaults of its configuration section and of the library structs
// that carry the same settings (the rule of lib/common/defaults.hpp, which holds the shared ones),
// so a test that builds the controller directly runs the lift a default configuration gives the
// daemon.
#pragma once

namespace liftd::defaults {

// dcp.* (the DCP link)
inline constexpr bool kExtendedPosition = true;  ///< ask for the extended I9 (DCP 5.12.3)
inline constexpr int kLinkFaultFrames = 10;      ///< DCP 7.3: bad replies that make a link fault
inline constexpr int kLinkRecoverFrames = 10;    ///< DCP 7.3: good replies that end it
inline constexpr int kRequestTimeoutMs = 2000;   ///< wait for an I-message reply

}  // namespace liftd::defaults
