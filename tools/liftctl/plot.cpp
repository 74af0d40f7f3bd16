#include "plot.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>
#include <string_view>

namespace liftctl {
namespace {

using nlohmann::json;

// ---- the curves of a `travels` result ----

struct Curve {
  std::string id;
  std::string title;  ///< "travel 12: dcp4_distance to floor 2 (6000 mm), arrived, 3.42 s"
  std::vector<double> t_s;
  std::vector<std::optional<double>> position;
  std::vector<std::optional<double>> speed;
  std::vector<std::optional<double>> remaining;
  /// The bits on, per sample, by key: "c:" and the name of a command bit, "s:" of a status bit
  /// (a USS drive names bits of both words alike).
  std::vector<std::set<std::string>> bits;
  std::vector<std::string> command_names;  ///< in bit order
  std::vector<std::string> status_names;   ///< in bit order
  double duration_s = 0;
};

std::optional<double> number_at(const json& sample, const char* key) {
  const auto it = sample.find(key);
  if (it == sample.end() || !it->is_number()) return std::nullopt;
  return it->get<double>();
}

std::string fixed(double value, int decimals) {
  char buf[48];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, value);
  return buf;
}

std::string title_of(const json& t) {
  std::string title =
      "travel " + std::to_string(t.value("id", 0)) + ": " + t.value("kind", std::string("?"));
  if (t.contains("target_floor") && t["target_floor"].is_number()) {
    title += " to floor " + std::to_string(t["target_floor"].get<long>());
    if (t.contains("target_mm") && t["target_mm"].is_number()) {
      title += " (" + std::to_string(t["target_mm"].get<long>()) + " mm)";
    }
  }
  const json cause = t.value("cause", json());
  title += ", " + (cause.is_string()
                       ? cause.get<std::string>()
                       : std::string(t.value("end", json()).is_null() ? "running" : "ended"));
  title += ", " + fixed(t.value("duration_ms", 0.0) / 1000.0, 2) + " s";
  return title;
}

std::vector<Curve> curves_of(const json& result) {
  std::vector<Curve> out;
  for (const json& t : result.value("travels", json::array())) {
    Curve c;
    c.id = std::to_string(t.value("id", 0));
    c.title = title_of(t);
    for (const json& name : t.value("command_bits", json::array())) {
      if (name.is_string()) c.command_names.push_back(name.get<std::string>());
    }
    for (const json& name : t.value("status_bits", json::array())) {
      if (name.is_string()) c.status_names.push_back(name.get<std::string>());
    }
    for (const json& s : t.value("samples", json::array())) {
      c.t_s.push_back(s.value("t_ms", 0.0) / 1000.0);
      c.position.push_back(number_at(s, "position_mm"));
      c.speed.push_back(number_at(s, "speed_mm_s"));
      c.remaining.push_back(number_at(s, "remaining_mm"));
      std::set<std::string> on;
      for (const char* group : {"command", "status"}) {
        for (const json& name : s.value(group, json::array())) {
          if (name.is_string()) on.insert(std::string(1, group[0]) + ":" + name.get<std::string>());
        }
      }
      c.bits.push_back(std::move(on));
    }
    c.duration_s = c.t_s.empty() ? 0 : c.t_s.back();
    out.push_back(std::move(c));
  }
  return out;
}

struct Range {
  double lo = 0;
  double hi = 0;
  bool any = false;
  void add(double v) {
    lo = any ? std::min(lo, v) : v;
    hi = any ? std::max(hi, v) : v;
    any = true;
  }
};

Range range_of(const std::vector<std::optional<double>>& values) {
  Range r;
  for (const auto& v : values) {
    if (v) r.add(*v);
  }
  return r;
}

/// A round step for about `wanted` intervals over `span` (1, 2 or 5 times a power of ten).
double nice_step(double span, int wanted) {
  if (span <= 0) return 1;
  const double raw = span / wanted;
  const double power = std::pow(10.0, std::floor(std::log10(raw)));
  for (const double m : {1.0, 2.0, 5.0, 10.0}) {
    if (raw <= m * power) return m * power;
  }
  return 10 * power;
}

/// "+name" for each bit of `names` (keys `prefix` + name) that came on between `before` and
/// `now`, "-name" for each that went off.
std::string changes_of(const std::set<std::string>& before, const std::set<std::string>& now,
                       const std::vector<std::string>& names, const std::string& prefix) {
  std::string changes;
  for (const std::string& name : names) {
    const bool was = before.count(prefix + name) != 0;
    const bool is = now.count(prefix + name) != 0;
    if (was != is) changes += std::string(changes.empty() ? "" : " ") + (is ? "+" : "-") + name;
  }
  return changes;
}

/// Each switch of a bit: the command bits' changes, then after " | " the status bits' (the first
/// sample lists the bits on at the start).
std::vector<std::pair<double, std::string>> switches_of(const Curve& c) {
  std::vector<std::pair<double, std::string>> out;
  std::set<std::string> before;
  for (std::size_t i = 0; i < c.bits.size(); ++i) {
    const std::string command = changes_of(before, c.bits[i], c.command_names, "c:");
    const std::string status = changes_of(before, c.bits[i], c.status_names, "s:");
    if (!command.empty() || !status.empty()) {
      out.emplace_back(c.t_s[i],
                       command + (status.empty() ? "" : (command.empty() ? "| " : " | ") + status));
    }
    before = c.bits[i];
  }
  return out;
}

// ---- the terminal chart ----

constexpr std::size_t kLabelWidth = 9;  // "  12345 |"
constexpr std::size_t kChartWidth = kPlotColumns - kLabelWidth;

/// The column of time `t` on a chart from 0 to `duration`.
std::size_t column_of(double t, double duration) {
  if (duration <= 0) return 0;
  const double x = t / duration * static_cast<double>(kChartWidth - 1);
  return std::min(kChartWidth - 1, static_cast<std::size_t>(std::lround(std::max(0.0, x))));
}

std::string label(const std::string& text) {
  std::string out = text.size() > kLabelWidth - 2 ? text.substr(0, kLabelWidth - 2) : text;
  return std::string(kLabelWidth - 2 - out.size(), ' ') + out + " |";
}

/// A chart of `rows` rows of one quantity against time.
std::string chart(const Curve& c, const std::vector<std::optional<double>>& values,
                  const std::string& name, std::size_t rows) {
  Range r = range_of(values);
  std::string out = name + "\n";
  if (!r.any) return out + label("") + " (none)\n";
  if (r.hi == r.lo) {
    r.hi += 1;
    r.lo -= 1;
  }
  std::vector<std::string> grid(rows, std::string(kChartWidth, ' '));
  std::vector<double> sum(kChartWidth, 0);
  std::vector<int> count(kChartWidth, 0);
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (!values[i]) continue;
    const std::size_t col = column_of(c.t_s[i], c.duration_s);
    sum[col] += *values[i];
    ++count[col];
  }
  std::optional<std::size_t> previous;
  for (std::size_t col = 0; col < kChartWidth; ++col) {
    if (count[col] == 0) continue;
    const double v = sum[col] / count[col];
    const auto row = static_cast<std::size_t>(
        std::lround((v - r.lo) / (r.hi - r.lo) * static_cast<double>(rows - 1)));
    if (previous) {
      for (std::size_t k = std::min(*previous, row) + 1; k < std::max(*previous, row); ++k) {
        grid[rows - 1 - k][col] = '.';
      }
    }
    grid[rows - 1 - row][col] = '*';
    previous = row;
  }
  for (std::size_t i = 0; i < rows; ++i) {
    std::string y;
    if (i == 0) y = fixed(r.hi, 0);
    if (i == rows - 1) y = fixed(r.lo, 0);
    if (i == rows / 2 && rows > 2) y = fixed((r.hi + r.lo) / 2, 0);
    std::string line = label(y) + grid[i];
    while (!line.empty() && line.back() == ' ') line.pop_back();
    out += line + "\n";
  }
  return out;
}

/// The switches, wrapped at kPlotColumns: "  1.230 s  +B0_enable -S1_travel_active".
std::string switch_lines(const Curve& c) {
  std::string out;
  for (const auto& [t, changes] : switches_of(c)) {
    std::string time = fixed(t, 3);
    time.insert(0, time.size() < 6 ? 6 - time.size() : 0, ' ');
    std::string line = "  " + time + " s ";
    const std::size_t indent = line.size();
    std::size_t start = 0;
    while (start < changes.size()) {
      std::size_t end = changes.find(' ', start);
      if (end == std::string::npos) end = changes.size();
      const std::string word = changes.substr(start, end - start);
      if (line.size() + 1 + word.size() > kPlotColumns && line.size() > indent) {
        out += line + "\n";
        line = std::string(indent, ' ');
      }
      line += " " + word.substr(0, kPlotColumns - indent - 1);
      start = end + 1;
    }
    out += line + "\n";
  }
  return out;
}

std::string terminal_chart(const Curve& c) {
  std::string out = c.title.substr(0, kPlotColumns) + "\n";
  out += chart(c, c.position, "position [mm]", 8);
  out += chart(c, c.speed, "speed [mm/s]", 6);
  std::string markers(kChartWidth, ' ');
  for (const auto& [t, changes] : switches_of(c)) markers[column_of(t, c.duration_s)] = '^';
  std::string marker_line = label("bits") + markers;
  while (marker_line.back() == ' ') marker_line.pop_back();
  out += marker_line + "\n";
  out += std::string(kLabelWidth - 1, ' ') + "+" + std::string(kChartWidth, '-') + "\n";
  const std::string end = fixed(c.duration_s, 2) + " s";
  std::string axis = std::string(kLabelWidth, ' ') + "0 s";
  axis += std::string(kPlotColumns - axis.size() - end.size(), ' ') + end;
  out += axis + "\n";
  out += "bits switched (+ on, - off; command | status):\n" + switch_lines(c);
  return out;
}

// ---- the SVG document ----

constexpr double kSvgWidth = 960;
constexpr double kLeft = 170;
constexpr double kRight = 30;
constexpr double kPanelHeight = 170;
constexpr double kPanelGap = 60;
constexpr double kLaneHeight = 18;
constexpr std::string_view kColours[] = {"#1f77b4", "#d62728", "#2ca02c", "#9467bd",
                                         "#ff7f0e", "#8c564b", "#e377c2", "#17becf"};

std::string escape(const std::string& text) {
  std::string out;
  for (const char ch : text) {
    switch (ch) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += ch;
    }
  }
  return out;
}

std::string num(double v) {
  return fixed(v, 1);
}

std::string colour(std::size_t i) {
  return std::string(kColours[i % std::size(kColours)]);
}

struct Frame {
  double top = 0;
  double height = 0;
  double x_max = 1;
  double y_lo = 0;
  double y_hi = 1;
  double x(double t) const { return kLeft + t / x_max * (kSvgWidth - kLeft - kRight); }
  double y(double v) const { return top + height - (v - y_lo) / (y_hi - y_lo) * height; }
};

/// The time axis under a panel, in seconds.
std::string time_axis(const Frame& f) {
  std::string out;
  const double step = nice_step(f.x_max, 8);
  for (double t = 0; t <= f.x_max + step / 1000; t += step) {
    out += "<line x1=\"" + num(f.x(t)) + "\" y1=\"" + num(f.top) + "\" x2=\"" + num(f.x(t)) +
           "\" y2=\"" + num(f.top + f.height) + "\" class=\"grid\"/>\n";
    out += "<text x=\"" + num(f.x(t)) + "\" y=\"" + num(f.top + f.height + 14) +
           "\" text-anchor=\"middle\">" + fixed(t, step < 1 ? 1 : 0) + "</text>\n";
  }
  out += "<text x=\"" + num(kSvgWidth - kRight) + "\" y=\"" + num(f.top + f.height + 30) +
         "\" text-anchor=\"end\">time [s]</text>\n";
  return out;
}

/// A panel of one quantity: its frame, value axis with `unit`, and one series per travel.
std::string value_panel(const std::vector<Curve>& curves,
                        std::vector<std::optional<double>> Curve::*member, const std::string& id,
                        const std::string& title, const std::string& unit, double top, double x_max,
                        const std::string& none_text) {
  Range r;
  for (const Curve& c : curves) {
    const Range cr = range_of(c.*member);
    if (cr.any) {
      r.add(cr.lo);
      r.add(cr.hi);
    }
  }
  Frame f{top, kPanelHeight, x_max, r.lo, r.hi};
  const double step = nice_step(r.hi - r.lo, 5);
  if (r.any) {
    f.y_lo = std::floor(r.lo / step) * step;
    f.y_hi = std::ceil(r.hi / step) * step;
    if (f.y_hi <= f.y_lo) f.y_hi = f.y_lo + step;
  }
  std::string out = "<g id=\"panel-" + id + "\" class=\"panel\">\n";
  out += "<text x=\"" + num(kLeft) + "\" y=\"" + num(top - 8) + "\" class=\"title\">" +
         escape(title) + " [" + escape(unit) + "]</text>\n";
  out += "<rect x=\"" + num(kLeft) + "\" y=\"" + num(top) + "\" width=\"" +
         num(kSvgWidth - kLeft - kRight) + "\" height=\"" + num(kPanelHeight) +
         "\" class=\"frame\"/>\n";
  out += time_axis(f);
  if (!r.any) {
    out += "<text x=\"" + num(kSvgWidth / 2) + "\" y=\"" + num(top + kPanelHeight / 2) +
           "\" text-anchor=\"middle\" class=\"note\">" + escape(none_text) + "</text>\n";
    return out + "</g>\n";
  }
  for (double v = f.y_lo; v <= f.y_hi + step / 1000; v += step) {
    out += "<line x1=\"" + num(kLeft) + "\" y1=\"" + num(f.y(v)) + "\" x2=\"" +
           num(kSvgWidth - kRight) + "\" y2=\"" + num(f.y(v)) + "\" class=\"grid\"/>\n";
    out += "<text x=\"" + num(kLeft - 6) + "\" y=\"" + num(f.y(v) + 4) + "\" text-anchor=\"end\">" +
           fixed(v, 0) + "</text>\n";
  }
  out += "<text transform=\"translate(" + num(kLeft - 55) + "," + num(top + kPanelHeight / 2) +
         ") rotate(-90)\" text-anchor=\"middle\">" + escape(id) + " [" + escape(unit) +
         "]</text>\n";
  for (std::size_t i = 0; i < curves.size(); ++i) {
    const Curve& c = curves[i];
    std::string points;
    for (std::size_t k = 0; k < c.t_s.size(); ++k) {
      const auto& v = (c.*member)[k];
      if (!v) continue;
      points += (points.empty() ? "" : " ") + num(f.x(c.t_s[k])) + "," + num(f.y(*v));
    }
    if (points.empty()) continue;
    out += "<polyline class=\"series\" data-travel=\"" + c.id + "\" fill=\"none\" stroke=\"" +
           colour(i) + "\" stroke-width=\"1.5\" points=\"" + points + "\"/>\n";
  }
  return out + "</g>\n";
}

/// The bits panel of the newest travel: one lane per bit that was on at some time, the command
/// bits above a line, the drive's status bits below it; a bar while the bit is on.
std::string bits_panel(const Curve& c, double top, double x_max, std::size_t& lanes_out) {
  std::vector<std::pair<std::string, std::string>> lanes;  // key, name
  std::size_t command_lanes = 0;
  for (const auto& [names, prefix] :
       {std::pair{&c.command_names, "c:"}, std::pair{&c.status_names, "s:"}}) {
    for (const std::string& name : *names) {
      const std::string key = prefix + name;
      const bool ever = std::any_of(c.bits.begin(), c.bits.end(),
                                    [&](const std::set<std::string>& on) { return on.count(key); });
      if (ever) lanes.emplace_back(key, name);
    }
    if (names == &c.command_names) command_lanes = lanes.size();
  }
  lanes_out = lanes.size();
  const double height = std::max<double>(1, static_cast<double>(lanes.size())) * kLaneHeight;
  Frame f{top, height, x_max, 0, 1};
  std::string out = "<g id=\"panel-bits\" class=\"panel\">\n";
  out += "<text x=\"" + num(kLeft) + "\" y=\"" + num(top - 8) +
         "\" class=\"title\">bits of travel " + escape(c.id) +
         ": the command above the line, the drive's status below; a bar while on</text>\n";
  out += "<rect x=\"" + num(kLeft) + "\" y=\"" + num(top) + "\" width=\"" +
         num(kSvgWidth - kLeft - kRight) + "\" height=\"" + num(height) + "\" class=\"frame\"/>\n";
  out += time_axis(f);
  if (command_lanes > 0 && command_lanes < lanes.size()) {
    const double y = top + static_cast<double>(command_lanes) * kLaneHeight;
    out += "<line x1=\"" + num(kLeft) + "\" y1=\"" + num(y) + "\" x2=\"" + num(kSvgWidth - kRight) +
           "\" y2=\"" + num(y) + "\" stroke=\"#444\"/>\n";
  }
  for (std::size_t lane = 0; lane < lanes.size(); ++lane) {
    const auto& [key, name] = lanes[lane];
    const double base = top + (static_cast<double>(lane) + 1) * kLaneHeight - 3;
    const double high = base - kLaneHeight + 7;
    out += "<text x=\"" + num(kLeft - 6) + "\" y=\"" + num(base) + "\" text-anchor=\"end\">" +
           escape(name) + "</text>\n";
    std::string points;
    std::optional<double> last_y;
    double on_since = -1;  // x where the bit came on; -1 while it is off
    const auto bar = [&](double from, double to) {
      out += "<rect x=\"" + num(from) + "\" y=\"" + num(high) + "\" width=\"" +
             num(std::max(0.5, to - from)) + "\" height=\"" + num(base - high) + "\" fill=\"" +
             colour(lane) + "\" fill-opacity=\"0.35\"/>\n";
    };
    for (std::size_t k = 0; k < c.t_s.size(); ++k) {
      const bool on = c.bits[k].count(key) != 0;
      const double y = on ? high : base;
      const double x = f.x(c.t_s[k]);
      if (on && on_since < 0) on_since = x;
      if (!on && on_since >= 0) {
        bar(on_since, x);
        on_since = -1;
      }
      if (last_y && *last_y != y) points += " " + num(x) + "," + num(*last_y);
      points += (points.empty() ? "" : " ") + num(x) + "," + num(y);
      last_y = y;
    }
    if (on_since >= 0) bar(on_since, f.x(c.duration_s));
    out += "<polyline class=\"bit\" data-bit=\"" + escape(name) + "\" fill=\"none\" stroke=\"" +
           colour(lane) + "\" stroke-width=\"1.5\" points=\"" + points + "\"/>\n";
  }
  return out + "</g>\n";
}

}  // namespace

std::optional<PlotOptions> parse_plot_args(const std::vector<std::string>& words,
                                           std::string& error) {
  PlotOptions options;
  for (std::size_t i = 1; i < words.size(); ++i) {
    const std::string& word = words[i];
    if ((word == "--last" || word == "--svg") && i + 1 >= words.size()) {
      error = word + " needs a value; usage: plot [--last N] [--svg FILE]";
      return std::nullopt;
    }
    if (word == "--last") {
      const std::string& value = words[++i];
      char* end = nullptr;
      const long n = std::strtol(value.c_str(), &end, 10);
      if (value.empty() || *end != '\0' || n < 1 || n > 16) {
        error = "plot --last N: N must be 1..16";
        return std::nullopt;
      }
      options.last = static_cast<int>(n);
    } else if (word == "--svg") {
      options.svg_path = words[++i];
    } else {
      error = "usage: plot [--last N] [--svg FILE]";
      return std::nullopt;
    }
  }
  return options;
}

std::string format_plot(const nlohmann::json& travels_result) {
  const std::vector<Curve> curves = curves_of(travels_result);
  if (curves.empty()) return "no travel recorded yet\n";
  std::string out;
  for (const Curve& c : curves) {
    if (!out.empty()) out += "\n";
    out += terminal_chart(c);
  }
  return out;
}

std::string render_svg(const nlohmann::json& travels_result) {
  const std::vector<Curve> curves = curves_of(travels_result);
  double x_max = 0;
  for (const Curve& c : curves) x_max = std::max(x_max, c.duration_s);
  if (x_max <= 0) x_max = 1;
  const double legend_top = 50;
  const double first_panel = legend_top + 20 * static_cast<double>(curves.size()) + 40;
  std::string body;
  body += "<g id=\"legend\">\n";
  for (std::size_t i = 0; i < curves.size(); ++i) {
    const double y = legend_top + 20 * static_cast<double>(i);
    body += "<line x1=\"" + num(kLeft) + "\" y1=\"" + num(y - 4) + "\" x2=\"" + num(kLeft + 30) +
            "\" y2=\"" + num(y - 4) + "\" stroke=\"" + colour(i) + "\" stroke-width=\"3\"/>\n";
    body += "<text x=\"" + num(kLeft + 38) + "\" y=\"" + num(y) + "\">" + escape(curves[i].title) +
            "</text>\n";
  }
  body += "</g>\n";
  double top = first_panel;
  body += value_panel(curves, &Curve::position, "position", "car position", "mm", top, x_max,
                      "no position");
  top += kPanelHeight + kPanelGap;
  body += value_panel(curves, &Curve::speed, "speed", "speed (from the position)", "mm/s", top,
                      x_max, "no speed");
  top += kPanelHeight + kPanelGap;
  body += value_panel(curves, &Curve::remaining, "remaining", "remaining distance sent", "mm", top,
                      x_max, "this drive link carries no remaining distance (DCP4 only)");
  top += kPanelHeight + kPanelGap;
  std::size_t lanes = 0;
  if (!curves.empty()) body += bits_panel(curves.back(), top, x_max, lanes);
  top += std::max<double>(1, static_cast<double>(lanes)) * kLaneHeight + 50;
  const std::string title = curves.empty() ? "liftd: no travel recorded yet"
                            : curves.size() == 1
                                ? "liftd: travel " + curves.front().id
                                : "liftd: the last " + std::to_string(curves.size()) + " travels";
  std::string out = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
  out += "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" + num(kSvgWidth) + "\" height=\"" +
         num(top) + "\" viewBox=\"0 0 " + num(kSvgWidth) + " " + num(top) +
         "\" font-family=\"sans-serif\" font-size=\"12\">\n";
  out += "<title>" + escape(title) + "</title>\n";
  out +=
      "<style>.grid{stroke:#ddd;stroke-width:1}.frame{fill:none;stroke:#444;stroke-width:1}"
      ".title{font-weight:bold}.note{fill:#888}</style>\n";
  out += "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
  out += "<text x=\"" + num(kLeft) + "\" y=\"24\" font-size=\"16\" class=\"title\">" +
         escape(title) + "</text>\n";
  return out + body + "</svg>\n";
}

}  // namespace liftctl
