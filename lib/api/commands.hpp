// The built-in commands (status, watch, stats, trace, display, key, drive_reset, power, load,
// config, version, inputs, the travel commands, sim, the USS parameter commands), each one table
// entry on a Dispatcher.
#pragma once

#include <functional>

#include <nlohmann/json.hpp>

#include "api/backend.hpp"
#include "api/dispatcher.hpp"

namespace liftd::api {

/// Most trace entries one `trace` request returns.
inline constexpr std::int64_t kMaxTraceEntries = 1000;

/// Highest floor index a request may name (the configuration allows at most 64 floors).
inline constexpr std::int64_t kMaxFloorIndex = 63;

/// Adds the travel commands (travel, stop, fast_stop, relevel, inspection, fast_start, calls).
/// add_builtin_commands() calls it.
void add_travel_commands(Dispatcher& dispatcher, Backend& backend);

/// Most replies one `sim` reply_fault request affects (about 2.5 minutes of 15 ms cycles).
inline constexpr std::int64_t kMaxSimFaultFrames = 10000;
/// Largest car drift one `sim` drift request applies, either way.
inline constexpr std::int64_t kMaxSimDriftMm = 1000;

/// Adds `sim`, the simulated lift's fault injection (a backend without one refuses it).
/// add_builtin_commands() calls it.
void add_sim_command(Dispatcher& dispatcher, Backend& backend);

/// Adds `uss_read`, `uss_write` and `uss_mirror` (offered by drive kinds with
/// Capability::Parameters). add_builtin_commands() calls it.
void add_parameter_commands(Dispatcher& dispatcher, Backend& backend);

/// Adds every built-in command to `dispatcher`, served by `backend`. `api_stats` supplies the
/// server's own counters for `stats` ("api" object); it may be empty.
void add_builtin_commands(Dispatcher& dispatcher, Backend& backend,
                          std::function<nlohmann::json()> api_stats = {});

}  // namespace liftd::api
