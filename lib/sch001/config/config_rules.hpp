// The SCH001 card's part of the configuration: the sch001.* section (the card's parameters and
// the hydraulic unit behind it) and what a SCH001 lift needs across the shared keys.
#pragma once

#include "config/schema.hpp"

namespace liftd::sch001 {

/// The sch001.* keys, the checks a SCH001 lift needs (the floor count its frames carry) and the
/// summary of a SCH001 card. The CAN endpoint (can.*) is shared: the CAN encoder uses it too.
config::KindRules config_rules();

}  // namespace liftd::sch001
