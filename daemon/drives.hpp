// One factory turns drive.kind into the daemon's lift: the DCP lift (lift_app.*), the
// hydraulic SCH001 lift (hydraulic_lift.*) or the USS lift (uss_lift.*). Each builds its
// controller, its runner, its API backend and, with --simulate, its simulated drive, and registers
// them with the daemon.
#pragma once

#include <memory>
#include <string>

#include "config/config.hpp"
#include "host/host.hpp"

namespace liftd::daemon {

/// The lift for config.drive.kind. Throws std::invalid_argument / std::runtime_error with a
/// clear message on a configuration the parts refuse or a kind this build cannot run.
std::unique_ptr<LiftRunner> make_lift(Host& host, const config::Config& config, bool simulate);

}  // namespace liftd::daemon
