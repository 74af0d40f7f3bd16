// Human-readable rendering of liftd API results for liftctl.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

namespace liftctl {

/// Multi-line summary of a `status` result.
std::string format_status(const nlohmann::json& status);
/// One line summarising a `state` event (or status result) for plain watch output.
std::string format_state_line(const nlohmann::json& status);
/// One line for any other event: "<name> key=value ...".
std::string format_event_line(const std::string& name, const nlohmann::json& data);
/// Multi-line `stats`.
std::string format_stats(const nlohmann::json& stats);
/// One line per trace frame.
std::string format_trace(const nlohmann::json& trace);
/// The display as a framed box.
std::string format_display(const nlohmann::json& display);
/// The result of a travel command (`travel`, `stop`, `fast_stop`, `relevel`, `inspection`,
/// `fast_start`, `calls`) to `request`: what the daemon did, in a line.
std::string format_travel_result(const nlohmann::json& request, const nlohmann::json& result);
/// Any other result: "key: value" lines (nested keys joined with '.').
std::string format_generic(const nlohmann::json& result);

}  // namespace liftctl
