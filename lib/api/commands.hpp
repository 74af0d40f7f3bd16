// The commands every drive kind has or several share (status, watch, stats, trace, drive_reset,
// config, version, inputs, the travel commands, sim), each one table entry on a Dispatcher, and
// the argument helpers a drive kind's own commands (lib/<kind>/host/commands) share with them.
#pragma once

#include <functional>
#include <span>

#include <nlohmann/json.hpp>

#include "api/backend.hpp"
#include "api/dispatcher.hpp"
#include "api/sim.hpp"

namespace liftd::api {

/// Most trace entries one `trace` request returns.
inline constexpr std::int64_t kMaxTraceEntries = 1000;
/// The travels `travels` returns at most: all a lift keeps (host/travel_log.hpp).
inline constexpr std::int64_t kMaxTravels = 16;

/// Highest floor index a request may name (the configuration allows at most 64 floors).
inline constexpr std::int64_t kMaxFloorIndex = 63;
/// Most destinations the calls queue holds (lift::CallQueue: one per floor of the largest table).
inline constexpr std::int64_t kMaxCallsQueued = 128;

/// The `floor` argument of the travel commands (0..kMaxFloorIndex).
ArgSpec floor_arg(bool required);
/// The `speed` argument of the travel commands (drive::kTravelSpeedNames).
ArgSpec speed_arg();
/// TravelArgs from a validated request with `floor`, `speed` and `load_percent`.
TravelArgs travel_args(const nlohmann::json& request);

/// Adds the travel commands every drive kind offers (travel, stop, relevel, inspection, calls).
/// add_builtin_commands() calls it.
void add_travel_commands(Dispatcher& dispatcher, Backend& backend);
/// `learn`: the learning travel (added by add_travel_commands).
void add_learn_command(Dispatcher& dispatcher, Backend& backend);

/// Adds the lift's record commands (counters, counters_reset, history, trend);
/// add_builtin_commands() calls it.
void add_record_commands(Dispatcher& dispatcher, Backend& backend);

/// Most replies one `sim` reply_fault request affects (about 2.5 minutes of 15 ms cycles).
inline constexpr std::int64_t kMaxSimFaultFrames = 10000;
/// Largest car drift one `sim` drift request applies, either way.
inline constexpr std::int64_t kMaxSimDriftMm = 1000;

/// Adds `sim`, the simulated lift's fault injection (a backend without one refuses it): the
/// shared actions, then each of `kinds`' own actions in the order of `kinds` (the registry of
/// drive kinds, lib/kinds/lifts.cpp, adds it with every kind's list).
void add_sim_command(Dispatcher& dispatcher, Backend& backend,
                     std::span<const KindSimActions* const> kinds);

/// Adds every built-in command to `dispatcher`, served by `backend`. A drive kind's own
/// commands, `sim` with every kind's simulator actions and what the backend's kind offers
/// (Dispatcher::set_drive_kind) come from the registry of drive kinds (lib/kinds). `api_stats`
/// supplies the server's own counters for `stats` ("api" object); it may be empty.
void add_builtin_commands(Dispatcher& dispatcher, Backend& backend,
                          std::function<nlohmann::json()> api_stats = {});

}  // namespace liftd::api
