// The USS drive's part of the configuration: the uss.* section with the USS limits behind it
// (rates, addresses, PKW and PZD lengths) and the checks across its keys for a USS lift.
#pragma once

#include "config/schema.hpp"

namespace liftd::uss {

/// The uss.* keys, the checks a USS lift needs across them (addresses, polling list, speeds,
/// the position source) and the summary of a USS drive.
config::KindRules config_rules();

}  // namespace liftd::uss
