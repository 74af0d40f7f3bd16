#include "record_view.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <set>

namespace liftctl {
namespace {

using nlohmann::json;

std::optional<long> whole_number(const std::string& text) {
  char* end = nullptr;
  const long n = std::strtol(text.c_str(), &end, 10);
  if (text.empty() || *end != '\0') return std::nullopt;
  return n;
}

/// A number, or "-" for null or absent.
std::string shown(const json& object, const char* key, int decimals = 0) {
  const auto it = object.find(key);
  if (it == object.end() || !it->is_number()) return "-";
  char buf[48];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, it->get<double>());
  return buf;
}

/// `value` times `scale` with `decimals`, or "-".
std::string fixed(std::optional<double> value, int decimals, double scale) {
  if (!value) return "-";
  char buf[48];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, *value * scale);
  return buf;
}

std::string text_of(const json& object, const char* key) {
  const auto it = object.find(key);
  if (it == object.end() || it->is_null()) return "-";
  return it->is_string() ? it->get<std::string>() : it->dump();
}

/// The options every record view shares (--from, --to, --floor), and those `extra` names.
/// Returns false with `error` set on a bad word.
bool read_options(const std::vector<std::string>& words, std::size_t first,
                  const std::set<std::string>& extra, const std::string& usage, json& request,
                  std::optional<std::string>* svg, std::string& error) {
  for (std::size_t i = first; i < words.size(); ++i) {
    const std::string& word = words[i];
    if (word == "--trend") continue;
    const bool known = word == "--from" || word == "--to" || word == "--floor" ||
                       extra.count(word) != 0 || (svg != nullptr && word == "--svg");
    if (!known) {
      error = "unknown word \"" + word + "\"; usage: " + usage;
      return false;
    }
    if (i + 1 >= words.size()) {
      error = word + " needs a value; usage: " + usage;
      return false;
    }
    const std::string& value = words[++i];
    const std::string key = word.substr(2);
    if (key == "svg") {
      *svg = value;
    } else if (key == "floor" || key == "limit") {
      const auto n = whole_number(value);
      if (!n || *n < 0) {
        error = word + " must be a whole number, not \"" + value + "\"";
        return false;
      }
      request[key] = *n;
    } else {
      request[key] = value;  // the daemon checks times, outcomes and causes and says why
    }
  }
  return true;
}

/// Days of a trend result as a map floor -> (day -> row).
std::map<long, std::map<std::string, json>> by_floor(const json& result) {
  std::map<long, std::map<std::string, json>> out;
  for (const json& row : result.value("days", json::array())) {
    if (!row.contains("floor") || !row["floor"].is_number()) continue;
    out[row["floor"].get<long>()][row.value("day", std::string("?"))] = row;
  }
  return out;
}

std::optional<double> nested_number(const json& row, const char* object, const char* key) {
  const auto it = row.find(object);
  if (it == row.end() || !it->is_object()) return std::nullopt;
  const auto v = it->find(key);
  if (v == it->end() || !v->is_number()) return std::nullopt;
  return v->get<double>();
}

}  // namespace

std::optional<json> counters_request(const std::vector<std::string>& words, std::string& error) {
  if (words.size() == 1) return json{{"cmd", "counters"}};
  if (words[1] != "reset" || words.size() < 3) {
    error = "usage: counters [reset NAME...]";
    return std::nullopt;
  }
  return json{{"cmd", "counters_reset"},
              {"names", std::vector<std::string>(words.begin() + 2, words.end())}};
}

std::optional<json> history_request(const std::vector<std::string>& words, std::string& error) {
  json request = {{"cmd", "history"}};
  const std::string usage =
      "history [--from T] [--to T] [--floor N] [--outcome arrived|aborted] [--cause C] "
      "[--limit N]";
  if (!read_options(words, 1, {"--outcome", "--cause", "--limit"}, usage, request, nullptr,
                    error)) {
    return std::nullopt;
  }
  return request;
}

bool wants_trend(const std::vector<std::string>& words) {
  return std::find(words.begin(), words.end(), "--trend") != words.end();
}

std::optional<TrendOptions> trend_request(const std::vector<std::string>& words,
                                          std::string& error) {
  TrendOptions options;
  options.request = {{"cmd", "trend"}};
  if (!read_options(words, 1, {}, "plot --trend [--from T] [--to T] [--floor N] [--svg FILE]",
                    options.request, &options.svg_path, error)) {
    return std::nullopt;
  }
  return options;
}

std::string format_counters(const json& result) {
  std::string out;
  out += "since: " + text_of(result, "since") + "\n";
  const json counters = result.value("counters", json::object());
  std::size_t width = 0;
  for (const auto& [name, value] : counters.items()) width = std::max(width, name.size());
  for (const auto& [name, value] : counters.items()) {
    char line[256];
    std::snprintf(line, sizeof line, "  %-*s %s\n", static_cast<int>(width), name.c_str(),
                  value.dump().c_str());
    out += line;
  }
  const json floors = result.value("floors", json::array());
  if (!floors.empty()) {
    out += "floor  arrivals  stop error mm: mean    p95  worst\n";
    for (const json& f : floors) {
      const json error = f.value("stop_error_mm", json::object());
      char line[160];
      std::snprintf(line, sizeof line, "%5s  %8s  %20s %6s %6s\n", shown(f, "floor").c_str(),
                    shown(f, "arrivals").c_str(), shown(error, "mean", 1).c_str(),
                    shown(error, "p95", 1).c_str(), shown(error, "worst").c_str());
      out += line;
    }
  }
  for (const json& r : result.value("resets", json::array())) {
    out += "reset " + text_of(r, "at") + " by " + text_of(r, "who") + ": " +
           r.value("names", json::array()).dump() + "\n";
  }
  return out;
}

std::string format_history(const json& result) {
  const json travels = result.value("travels", json::array());
  if (travels.empty()) return "no travel in the record matches\n";
  std::string out =
      "start                     kind          from to   end  outcome  cause            "
      "ms      top mm/s  error mm\n";
  for (const json& t : travels) {
    char line[320];
    std::snprintf(line, sizeof line, "%-25s %-13s %4s %4s %4s %-8s %-16s %7s %9s %9s%s\n",
                  text_of(t, "start").c_str(), text_of(t, "kind").c_str(),
                  shown(t, "from_floor").c_str(), shown(t, "to_floor").c_str(),
                  shown(t, "end_floor").c_str(), text_of(t, "outcome").c_str(),
                  text_of(t, "cause").c_str(), shown(t, "duration_ms").c_str(),
                  shown(t, "top_speed_mm_s").c_str(), shown(t, "stop_error_mm").c_str(),
                  t.value("relevel_followed", false) ? "  relevelled" : "");
    out += line;
  }
  if (result.value("truncated", false)) out += "(more travels match: --limit)\n";
  return out;
}

std::string format_trend(const json& result) {
  const auto floors = by_floor(result);
  if (floors.empty()) return "no travel in the record for these days\n";
  std::string out = "day         floor  arrivals  stop error mm: mean  worst  travel s: mean\n";
  for (const auto& [floor, days] : floors) {
    for (const auto& [day, row] : days) {
      const auto mean_error = nested_number(row, "stop_error_mm", "mean");
      const auto worst = nested_number(row, "stop_error_mm", "worst");
      const auto travel_ms = nested_number(row, "travel_ms", "mean");
      char line[200];
      std::snprintf(line, sizeof line, "%-10s  %5ld  %8s  %19s  %5s  %14s\n", day.c_str(), floor,
                    shown(row, "arrivals").c_str(), fixed(mean_error, 1, 1.0).c_str(),
                    fixed(worst, 0, 1.0).c_str(), fixed(travel_ms, 2, 0.001).c_str());
      out += line;
    }
  }
  return out;
}

std::string render_trend_svg(const json& result) {
  const auto floors = by_floor(result);
  std::set<std::string> day_set;
  for (const auto& [floor, days] : floors) {
    for (const auto& [day, row] : days) day_set.insert(day);
  }
  const std::vector<std::string> days(day_set.begin(), day_set.end());
  constexpr double kTrendWidth = 900;
  constexpr double kTrendPanel = 260;
  constexpr double kTrendLeft = 70;
  constexpr double kTrendRight = 150;
  constexpr double kTrendTop = 40;
  static const char* const kTrendColours[] = {"#1f77b4", "#d62728", "#2ca02c", "#9467bd",
                                              "#ff7f0e", "#17becf", "#8c564b", "#e377c2"};
  std::string svg = "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"900\" height=\"" +
                    std::to_string(static_cast<int>(2 * kTrendPanel + 3 * kTrendTop)) + "\">\n";
  svg += "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
  const auto x_of = [&](std::size_t i) {
    const double span = kTrendWidth - kTrendLeft - kTrendRight;
    return kTrendLeft + (days.size() > 1
                             ? span * static_cast<double>(i) / static_cast<double>(days.size() - 1)
                             : span / 2);
  };
  struct Panel {
    const char* object;
    const char* title;
    double scale;  // value -> shown unit
  };
  const Panel panels[] = {{"stop_error_mm", "mean stopping error per day (mm)", 1.0},
                          {"travel_ms", "mean floor-to-floor time per day (s)", 0.001}};
  for (std::size_t p = 0; p < 2; ++p) {
    const double top = kTrendTop + static_cast<double>(p) * (kTrendPanel + kTrendTop);
    double lo = 0;
    double hi = 0;
    bool any = false;
    for (const auto& [floor, rows] : floors) {
      for (const auto& [day, row] : rows) {
        if (const auto v = nested_number(row, panels[p].object, "mean")) {
          const double shown_value = *v * panels[p].scale;
          lo = any ? std::min(lo, shown_value) : std::min(0.0, shown_value);
          hi = any ? std::max(hi, shown_value) : std::max(0.0, shown_value);
          any = true;
        }
      }
    }
    if (hi - lo < 1e-9) hi = lo + 1;
    const auto y_of = [&](double v) {
      return top + kTrendPanel - (v - lo) / (hi - lo) * kTrendPanel;
    };
    char buf[400];
    std::snprintf(
        buf, sizeof buf,
        "<text x=\"%.0f\" y=\"%.0f\" font-family=\"sans-serif\" font-size=\"14\">%s</text>\n"
        "<line x1=\"%.0f\" y1=\"%.0f\" x2=\"%.0f\" y2=\"%.0f\" stroke=\"black\"/>\n"
        "<line x1=\"%.0f\" y1=\"%.0f\" x2=\"%.0f\" y2=\"%.0f\" stroke=\"black\"/>\n",
        kTrendLeft, top - 10, panels[p].title, kTrendLeft, top, kTrendLeft, top + kTrendPanel,
        kTrendLeft, top + kTrendPanel, kTrendWidth - kTrendRight, top + kTrendPanel);
    svg += buf;
    for (const double v : {lo, (lo + hi) / 2, hi}) {
      std::snprintf(buf, sizeof buf,
                    "<text x=\"%.0f\" y=\"%.1f\" font-family=\"sans-serif\" font-size=\"11\" "
                    "text-anchor=\"end\">%.1f</text>\n",
                    kTrendLeft - 6, y_of(v) + 4, v);
      svg += buf;
    }
    if (!days.empty()) {
      for (const std::size_t i : {std::size_t{0}, days.size() - 1}) {
        std::snprintf(buf, sizeof buf,
                      "<text x=\"%.1f\" y=\"%.0f\" font-family=\"sans-serif\" font-size=\"11\" "
                      "text-anchor=\"middle\">%s</text>\n",
                      x_of(i), top + kTrendPanel + 16, days[i].c_str());
        svg += buf;
      }
    }
    std::size_t colour = 0;
    for (const auto& [floor, rows] : floors) {
      std::string points;
      for (std::size_t i = 0; i < days.size(); ++i) {
        const auto it = rows.find(days[i]);
        if (it == rows.end()) continue;
        const auto v = nested_number(it->second, panels[p].object, "mean");
        if (!v) continue;
        std::snprintf(buf, sizeof buf, "%.1f,%.1f ", x_of(i), y_of(*v * panels[p].scale));
        points += buf;
      }
      const char* c = kTrendColours[colour++ % std::size(kTrendColours)];
      svg += "<polyline fill=\"none\" stroke-width=\"2\" stroke=\"" + std::string(c) +
             "\" points=\"" + points + "\"/>\n";
      std::snprintf(buf, sizeof buf,
                    "<text x=\"%.0f\" y=\"%.0f\" font-family=\"sans-serif\" font-size=\"12\" "
                    "fill=\"%s\">floor %ld</text>\n",
                    kTrendWidth - kTrendRight + 10, top + 16 + 16 * static_cast<double>(colour - 1),
                    c, floor);
      svg += buf;
    }
  }
  svg += "</svg>\n";
  return svg;
}

}  // namespace liftctl
