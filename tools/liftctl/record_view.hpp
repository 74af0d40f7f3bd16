// liftctl's views of the lift's record (docs/api.md "The lift's record"): `counters`,
// `history` and `plot --trend`, from the words on the command line to the request, and from the
// result to a table or an SVG chart.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace liftctl {

/// `counters` or `counters reset NAME...` (words[0] is "counters"); nullopt with `error` set.
std::optional<nlohmann::json> counters_request(const std::vector<std::string>& words,
                                               std::string& error);
/// `history [--from T] [--to T] [--floor N] [--outcome arrived|aborted] [--cause C]
/// [--limit N]`; nullopt with `error` set.
std::optional<nlohmann::json> history_request(const std::vector<std::string>& words,
                                              std::string& error);

/// `plot --trend [--from T] [--to T] [--floor N] [--svg FILE]` (words[0] is "plot").
struct TrendOptions {
  nlohmann::json request;               ///< the `trend` request
  std::optional<std::string> svg_path;  ///< write an SVG file there instead of the table
};
/// Whether the plot words ask for the trend (carry "--trend").
bool wants_trend(const std::vector<std::string>& words);
std::optional<TrendOptions> trend_request(const std::vector<std::string>& words,
                                          std::string& error);

/// The counters, one per line, then a table of the floors' arrivals and stopping errors.
std::string format_counters(const nlohmann::json& result);
/// One line per travel, newest first.
std::string format_history(const nlohmann::json& result);
/// One line per floor and day: arrivals, stopping error, travel time.
std::string format_trend(const nlohmann::json& result);
/// A self-contained SVG: the mean stopping error and the mean floor-to-floor time per day, one
/// line per floor.
std::string render_trend_svg(const nlohmann::json& result);

}  // namespace liftctl
