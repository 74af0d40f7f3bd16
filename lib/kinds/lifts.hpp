// The registry of drive kinds: drive.kind -> the daemon's lift, each in its kind's folder (the DCP
// lift lib/dcp/host/dcp_lift.*, the hydraulic SCH001 lift lib/sch001/host/hydraulic_lift.*, the
// USS lift lib/uss/host/uss_lift.*). Each builds its controller, its runner, its API backend and,
// with --simulate, its simulated drive, and registers them with the daemon (lib/host/host.hpp).
// A kind with API commands of its own adds them from its folder (lib/<kind>/host/commands.*), and
// each kind names the `sim` actions its simulator takes (lib/<kind>/host/sim_actions.*).
// With config_schema.cpp (each kind's configuration section) this folder is the one registry of
// drive kinds: daemon/ includes no kind's header.
#pragma once

#include <memory>
#include <string>

#include "api/backend.hpp"
#include "api/dispatcher.hpp"
#include "config/config.hpp"
#include "host/host.hpp"

namespace liftd::kinds {

using daemon::Host;
using daemon::LiftRunner;

/// The lift for config.drive.kind. Throws std::invalid_argument / std::runtime_error with a
/// clear message on a configuration the parts refuse or a kind this build cannot run.
std::unique_ptr<LiftRunner> make_lift(Host& host, const config::Config& config, bool simulate);

/// Adds every drive kind's own API commands to `dispatcher`: those of backend.drive_kind()
/// served by `backend`, the others' only known, so that the dispatcher answers them
/// `not_offered` as on every lift; and `sim` with every kind's simulator actions.
void add_drive_kind_commands(api::Dispatcher& dispatcher, api::Backend& backend);

}  // namespace liftd::kinds
