// Which journal catalog entry (log::Catalogued, systemd/liftd.catalog) a lift's typed facts get:
// a fault raised or cleared (lift::FaultCode) and an aborted travel (lift::Cause). Every drive
// kind reports these through report_fault and report_travel (lift_core.hpp), so DCP, SCH001 and
// USS records of the same fact carry the same MESSAGE_ID.
#pragma once

#include <optional>

#include "lift/cause.hpp"
#include "lift/faults.hpp"
#include "log/catalog.hpp"

namespace liftd::daemon {

/// The catalog key of a fault's journal record: every fault when raised (link_fault ->
/// LinkLost, drive_fault, advance_warning, safety_chain_open, position_lost, inputs_lost), only
/// link_fault when cleared (LinkRestored); nullopt for the rest.
std::optional<log::Catalogued> fault_catalog_key(lift::FaultCode code, bool raised) noexcept;

/// The catalog key of an aborted travel's journal record: SafetyChainOpenedMidTravel when the
/// safety chain opened, TravelAborted for every other cause.
log::Catalogued abort_catalog_key(lift::Cause cause) noexcept;

}  // namespace liftd::daemon
