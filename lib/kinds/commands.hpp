// The registry's API part: each drive kind's own API commands (lib/<kind>/host/commands.*) and
// the `sim` actions its simulator takes (lib/<kind>/host/sim_actions.*). A library of its own
// (kind_commands), so that the API tests, the fuzz targets and the benchmarks serve every kind's
// commands as the daemon does without linking any kind's lift.
#pragma once

#include "api/backend.hpp"
#include "api/dispatcher.hpp"
#include "api/sim.hpp"
#include "drive/drive.hpp"

namespace liftd::kinds {

/// Adds every drive kind's own API commands to `dispatcher`: those of backend.drive_kind()
/// served by `backend`, the others' only known, so that the dispatcher answers them
/// `not_offered` as on every lift (it is told what the kind offers); and `sim` with every
/// kind's simulator actions.
void add_drive_kind_commands(api::Dispatcher& dispatcher, api::Backend& backend);

/// The `sim` actions the simulator of `kind` takes (lib/<kind>/host/sim_actions.*).
const api::KindSimActions& sim_actions_of(drive::Kind kind) noexcept;

}  // namespace liftd::kinds
