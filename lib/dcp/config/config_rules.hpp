// The DCP drive's part of the configuration: the dcp.* section with the DCP facts behind it (the
// I0 maker-code table, the language code), and what a floor may be where a DCP display shows its
// name and I9 reports its level.
#pragma once

#include "config/schema.hpp"

namespace liftd::dcp {

/// The dcp.* keys and the summary of a DCP drive (no cross-check: each dcp.* key stands alone).
config::KindRules config_rules();

/// Floor names in the display character set (DCP appendix A), the same name where the display
/// shows two alike, and levels within I9's six digits of mm (DCP 5.12.9).
config::FloorRules floor_rules();

}  // namespace liftd::dcp
