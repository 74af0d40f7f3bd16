// The registry's lifts: drive.kind -> the daemon's lift, each in its kind's folder (the DCP lift
// lib/dcp/host/dcp_lift.*, the hydraulic SCH001 lift lib/sch001/host/hydraulic_lift.*, the USS
// lift lib/uss/host/uss_lift.*), made by its registry entry (registry.hpp). Each builds its
// controller, its runner, its API backend and, with --simulate, its simulated drive, and
// registers them with the daemon (lib/host/host.hpp). daemon/ includes no kind's header.
#pragma once

#include <memory>
#include <string>

#include "config/config.hpp"
#include "host/host.hpp"

namespace liftd::kinds {

using daemon::Host;
using daemon::LiftRunner;

/// The lift for config.drive.kind. Throws std::invalid_argument / std::runtime_error with a
/// clear message on a configuration the parts refuse or a kind this build cannot run.
std::unique_ptr<LiftRunner> make_lift(Host& host, const config::Config& config, bool simulate);

}  // namespace liftd::kinds
