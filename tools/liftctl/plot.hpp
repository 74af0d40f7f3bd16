// `liftctl plot`: the curves of the last travels (the API's `travels` result), as a chart in an
// 80-column terminal or as a self-contained SVG file.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace liftctl {

/// The widest line the terminal chart prints.
inline constexpr std::size_t kPlotColumns = 80;

struct PlotOptions {
  int last = 5;                         ///< the API's `last`: 1..16
  std::optional<std::string> svg_path;  ///< write an SVG file there instead of the chart
};

/// `plot [--last N] [--svg FILE]` (words[0] is "plot"); nullopt with `error` set on bad usage.
std::optional<PlotOptions> parse_plot_args(const std::vector<std::string>& words,
                                           std::string& error);

/// The terminal chart of every travel in a `travels` result: position and speed against time,
/// a marker row where a bit switched and the switches listed; no line longer than kPlotColumns.
std::string format_plot(const nlohmann::json& travels_result);

/// A self-contained SVG document of a `travels` result: one panel each for position, speed,
/// remaining distance and the drive's bits, with time and value axes, units and a legend.
std::string render_svg(const nlohmann::json& travels_result);

}  // namespace liftctl
