// liftctl plot: the SVG document is well-formed XML with a panel per quantity, a series per
// travel, a lane per bit and a legend; the terminal chart never passes 80 columns; and liftctl
// asks `travels` with the --last given and writes --svg FILE.
#include <sys/wait.h>

#include <cctype>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <map>
#include <sstream>

#include "api/test_support.hpp"
#include "plot.hpp"

namespace liftd::api::testing {
namespace {

// ---- a small XML reader: enough to tell a well-formed SVG document from a broken one ----

struct Element {
  std::string name;
  std::map<std::string, std::string> attributes;
  std::vector<Element> children;
  std::string text;
};

class XmlReader {
 public:
  explicit XmlReader(std::string text) : s_(std::move(text)) {}

  /// The root element; nullopt with error() set when the text is not well-formed XML.
  std::optional<Element> read() {
    skip_misc();
    Element root;
    if (!element(root)) return std::nullopt;
    skip_misc();
    if (pos_ != s_.size()) {
      fail("content after the root element");
      return std::nullopt;
    }
    return root;
  }
  const std::string& error() const { return error_; }

 private:
  /// Records the first problem; false.
  bool fail(const std::string& why) {
    if (error_.empty()) error_ = why + " at offset " + std::to_string(pos_);
    return false;
  }
  bool starts(std::string_view prefix) const {
    return s_.compare(pos_, prefix.size(), prefix) == 0;
  }
  void skip_space() {
    while (pos_ < s_.size() && std::isspace(static_cast<unsigned char>(s_[pos_]))) ++pos_;
  }
  /// Whitespace, the XML declaration and comments.
  void skip_misc() {
    for (;;) {
      skip_space();
      if (starts("<?")) {
        pos_ = s_.find("?>", pos_);
        pos_ = pos_ == std::string::npos ? s_.size() : pos_ + 2;
      } else if (starts("<!--")) {
        pos_ = s_.find("-->", pos_);
        pos_ = pos_ == std::string::npos ? s_.size() : pos_ + 3;
      } else {
        return;
      }
    }
  }
  std::string name() {
    const std::size_t start = pos_;
    while (pos_ < s_.size() &&
           (std::isalnum(static_cast<unsigned char>(s_[pos_])) || s_[pos_] == '-' ||
            s_[pos_] == '_' || s_[pos_] == ':' || s_[pos_] == '.')) {
      ++pos_;
    }
    return s_.substr(start, pos_ - start);
  }
  /// Character data up to `end`, with its entity references checked.
  bool chars(char end, std::string& out) {
    while (pos_ < s_.size() && s_[pos_] != end) {
      if (s_[pos_] == '<') return fail("'<' in character data");
      if (s_[pos_] == '&') {
        const std::size_t semi = s_.find(';', pos_);
        if (semi == std::string::npos) return fail("unterminated entity");
        const std::string entity = s_.substr(pos_ + 1, semi - pos_ - 1);
        const bool known = entity == "amp" || entity == "lt" || entity == "gt" ||
                           entity == "quot" || entity == "apos" ||
                           (!entity.empty() && entity[0] == '#');
        if (!known) return fail("unknown entity &" + entity + ";");
        out += '&';
        pos_ = semi + 1;
        continue;
      }
      out += s_[pos_++];
    }
    return true;
  }
  bool element(Element& e) {
    if (!starts("<")) return fail("expected an element");
    ++pos_;
    e.name = name();
    if (e.name.empty()) return fail("element without a name");
    for (;;) {
      skip_space();
      if (starts("/>")) {
        pos_ += 2;
        return true;
      }
      if (starts(">")) {
        ++pos_;
        break;
      }
      const std::string attribute = name();
      if (attribute.empty()) return fail("bad attribute in <" + e.name + ">");
      skip_space();
      if (!starts("=")) return fail("attribute " + attribute + " without a value");
      ++pos_;
      skip_space();
      if (pos_ >= s_.size() || (s_[pos_] != '"' && s_[pos_] != '\'')) {
        return fail("attribute " + attribute + " not quoted");
      }
      const char quote = s_[pos_++];
      std::string value;
      if (!chars(quote, value)) return false;
      if (pos_ >= s_.size()) return fail("unterminated attribute");
      ++pos_;
      if (!e.attributes.emplace(attribute, value).second) {
        return fail("attribute " + attribute + " twice");
      }
    }
    for (;;) {
      if (!chars('<', e.text)) return false;
      if (pos_ >= s_.size()) return fail("<" + e.name + "> not closed");
      if (starts("<!--")) {
        skip_misc();
        continue;
      }
      if (starts("</")) {
        pos_ += 2;
        if (name() != e.name) return fail("</...> does not close <" + e.name + ">");
        skip_space();
        if (!starts(">")) return fail("bad end tag");
        ++pos_;
        return true;
      }
      Element child;
      if (!element(child)) return false;
      e.children.push_back(std::move(child));
    }
  }

  std::string s_;
  std::size_t pos_ = 0;
  std::string error_;
};

void collect(const Element& e, const std::function<bool(const Element&)>& match,
             std::vector<const Element*>& out) {
  if (match(e)) out.push_back(&e);
  for (const Element& child : e.children) collect(child, match, out);
}

std::vector<const Element*> find_all(const Element& root,
                                     const std::function<bool(const Element&)>& match) {
  std::vector<const Element*> out;
  collect(root, match, out);
  return out;
}

const Element* by_id(const Element& root, const std::string& id) {
  const auto found = find_all(root, [&](const Element& e) {
    const auto it = e.attributes.find("id");
    return it != e.attributes.end() && it->second == id;
  });
  return found.empty() ? nullptr : found.front();
}

/// All text below `e`, joined.
std::string all_text(const Element& e) {
  std::string out = e.text;
  for (const Element& child : e.children) out += " " + all_text(child);
  return out;
}

// ---- `travels` results to draw ----

/// A travel of `seconds` from 0 to `level_mm` sampled every 15 ms, the DCP bits switching as a
/// DCP4 travel switches them; `remaining` false for a drive link without remaining distance.
nlohmann::json travel(int id, double seconds, int level_mm, bool remaining) {
  nlohmann::json samples = nlohmann::json::array();
  const int steps = static_cast<int>(seconds / 0.015);
  for (int i = 0; i <= steps; ++i) {
    const double u = static_cast<double>(i) / steps;
    const double position = level_mm * (3 * u * u - 2 * u * u * u);
    const double speed = level_mm * (6 * u - 6 * u * u) / seconds;
    nlohmann::json command = nlohmann::json::array();
    nlohmann::json status = {"S0_ready"};
    if (i > 0 && i < steps) command = {"B0_enable", "B2_stop"};
    if (i > 2 && i < steps - 1) status.push_back("S1_travel_active");
    if (i > 10 && i < steps - 5) status.push_back("S6_brake_open");
    samples.push_back({{"t_ms", i * 15},
                       {"position_mm", std::lround(position)},
                       {"speed_mm_s", std::lround(speed)},
                       {"remaining_mm", remaining ? nlohmann::json(std::lround(level_mm - position))
                                                  : nlohmann::json(nullptr)},
                       {"command", command},
                       {"status", status}});
  }
  return {{"id", id},
          {"kind", "distance"},
          {"start", "2026-11-27T10:00:00.000Z"},
          {"end", "2026-11-27T10:00:07.000Z"},
          {"duration_ms", steps * 15},
          {"cause", "arrived"},
          {"target_floor", 2},
          {"target_mm", level_mm},
          {"stride", 1},
          {"command_bits",
           {"B0_enable", "B1_travel", "B2_stop", "B3_speed", "B4_down", "B5_change", "B6_desired",
            "B7_reply_error"}},
          {"status_bits",
           {"S0_ready", "S1_travel_active", "S2_advance_warning", "S3_general_fault",
            "S4_below_levelling", "S5_accepted", "S6_brake_open", "S7_message_error"}},
          {"samples", samples}};
}

nlohmann::json two_travels() {
  return {{"travels", {travel(7, 6.0, 6000, true), travel(8, 4.0, 3000, true)}},
          {"dropped_samples", 0}};
}

void expect_fits_80_columns(const std::string& text) {
  std::istringstream lines(text);
  std::string line;
  int count = 0;
  while (std::getline(lines, line)) {
    ++count;
    EXPECT_LE(line.size(), liftctl::kPlotColumns) << "line " << count << ": " << line;
  }
  EXPECT_GT(count, 0);
}

TEST(LiftctlPlotXml, TheReaderRefusesWhatIsNotWellFormed) {
  for (const char* broken :
       {"<svg><g></svg>", "<svg a=1/>", "<svg>&nbsp;</svg>", "<svg><text>a < b</text></svg>",
        "<svg/><svg/>", "<svg a='1' a='2'/>"}) {
    XmlReader reader(broken);
    EXPECT_FALSE(reader.read()) << broken;
  }
  XmlReader good("<?xml version=\"1.0\"?>\n<svg a=\"&amp;\"><!-- c --><g/>x &lt; y</svg>");
  EXPECT_TRUE(good.read()) << good.error();
}

TEST(LiftctlPlot, TheSvgIsWellFormedWithAPanelPerQuantityASeriesPerTravelAndALegend) {
  XmlReader reader(liftctl::render_svg(two_travels()));
  const auto root = reader.read();
  ASSERT_TRUE(root) << reader.error();
  EXPECT_EQ(root->name, "svg");
  EXPECT_EQ(root->attributes.at("xmlns"), "http://www.w3.org/2000/svg");
  for (const auto& [panel, unit] : {std::pair{"panel-position", "[mm]"},
                                    {"panel-speed", "[mm/s]"},
                                    {"panel-remaining", "[mm]"}}) {
    const Element* g = by_id(*root, panel);
    ASSERT_NE(g, nullptr) << panel;
    const std::string text = all_text(*g);
    EXPECT_NE(text.find(unit), std::string::npos) << panel << ": " << text;
    EXPECT_NE(text.find("time [s]"), std::string::npos) << panel;
    const auto series = find_all(*g, [](const Element& e) {
      return e.name == "polyline" && e.attributes.count("class") &&
             e.attributes.at("class") == "series";
    });
    ASSERT_EQ(series.size(), 2U) << panel << ": one series per travel";
    EXPECT_EQ(series[0]->attributes.at("data-travel"), "7");
    EXPECT_EQ(series[1]->attributes.at("data-travel"), "8");
    EXPECT_NE(series[0]->attributes.at("stroke"), series[1]->attributes.at("stroke"));
    // Every sample of the travel is a point of its line.
    std::istringstream points(series[0]->attributes.at("points"));
    std::string point;
    std::size_t n = 0;
    while (points >> point) ++n;
    EXPECT_EQ(n, two_travels()["travels"][0]["samples"].size()) << panel;
  }
  const Element* bits = by_id(*root, "panel-bits");
  ASSERT_NE(bits, nullptr);
  const auto lanes =
      find_all(*bits, [](const Element& e) { return e.attributes.count("data-bit"); });
  std::vector<std::string> names;
  for (const Element* lane : lanes) names.push_back(lane->attributes.at("data-bit"));
  EXPECT_EQ(names, (std::vector<std::string>{"B0_enable", "B2_stop", "S0_ready", "S1_travel_active",
                                             "S6_brake_open"}));
  const Element* legend = by_id(*root, "legend");
  ASSERT_NE(legend, nullptr);
  const std::string legend_text = all_text(*legend);
  EXPECT_NE(legend_text.find("travel 7: distance to floor 2 (6000 mm), arrived"), std::string::npos)
      << legend_text;
  EXPECT_NE(legend_text.find("travel 8"), std::string::npos) << legend_text;
}

TEST(LiftctlPlot, ADriveLinkWithoutRemainingDistanceSaysSoInItsPanel) {
  const nlohmann::json result = {{"travels", {travel(1, 3.0, 1200, false)}}};
  XmlReader reader(liftctl::render_svg(result));
  const auto root = reader.read();
  ASSERT_TRUE(root) << reader.error();
  const Element* remaining = by_id(*root, "panel-remaining");
  ASSERT_NE(remaining, nullptr);
  EXPECT_NE(all_text(*remaining).find("no remaining distance"), std::string::npos);
  EXPECT_TRUE(find_all(*remaining, [](const Element& e) { return e.name == "polyline"; }).empty());
}

TEST(LiftctlPlot, TheTerminalChartFitsEightyColumnsAndMarksTheSwitches) {
  const std::string chart = liftctl::format_plot(two_travels());
  expect_fits_80_columns(chart);
  EXPECT_NE(chart.find("travel 7: distance to floor 2 (6000 mm), arrived, 6.00 s"),
            std::string::npos)
      << chart;
  EXPECT_NE(chart.find("position [mm]"), std::string::npos) << chart;
  EXPECT_NE(chart.find("speed [mm/s]"), std::string::npos) << chart;
  EXPECT_NE(chart.find("   bits |^"), std::string::npos) << chart;
  EXPECT_NE(chart.find("0.015 s  +B0_enable +B2_stop"), std::string::npos) << chart;
  EXPECT_NE(chart.find("   6000 |"), std::string::npos) << chart;
}

TEST(LiftctlPlot, LongBitNamesWrapWithinEightyColumns) {
  nlohmann::json t = travel(3, 2.0, 1200, false);
  const std::vector<std::string> uss = {"on",
                                        "no_off2",
                                        "no_off3",
                                        "enable_operation",
                                        "ramp_generator_enable",
                                        "ramp_start",
                                        "setpoint_enable",
                                        "fault_acknowledge",
                                        "jog1",
                                        "jog2",
                                        "control_requested"};
  t["command_bits"] = uss;
  t["samples"][1]["command"] = uss;
  const std::string chart = liftctl::format_plot({{"travels", {t}}});
  expect_fits_80_columns(chart);
  EXPECT_NE(chart.find("+control_requested"), std::string::npos) << chart;
}

TEST(LiftctlPlot, NoTravelYet) {
  EXPECT_EQ(liftctl::format_plot({{"travels", nlohmann::json::array()}}),
            "no travel recorded yet\n");
  XmlReader reader(liftctl::render_svg({{"travels", nlohmann::json::array()}}));
  EXPECT_TRUE(reader.read()) << reader.error();
}

// ---- liftctl plot against the in-process server ----

class LiftctlPlotCommand : public LiftctlFixture {};

TEST_F(LiftctlPlotCommand, AsksForTheLastTravelsAndDrawsThemInEightyColumns) {
  backend_.travels_result = two_travels();
  start_server();
  const RunResult r = run_command(liftctl("plot --last 3"));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(backend_.travels_asked, 3U);
  expect_fits_80_columns(r.output);
  EXPECT_NE(r.output.find("travel 8"), std::string::npos) << r.output;
}

TEST_F(LiftctlPlotCommand, WritesTheSvgFile) {
  backend_.travels_result = two_travels();
  start_server();
  const std::string file = socket_path() + ".svg";
  const RunResult r = run_command(liftctl("plot --svg " + file));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(backend_.travels_asked, 5U) << "the default --last";
  EXPECT_NE(r.output.find("2 travels written to " + file), std::string::npos) << r.output;
  std::ifstream in(file);
  std::stringstream svg;
  svg << in.rdbuf();
  XmlReader reader(svg.str());
  const auto root = reader.read();
  ASSERT_TRUE(root) << reader.error();
  EXPECT_NE(by_id(*root, "panel-bits"), nullptr);
}

TEST_F(LiftctlPlotCommand, RefusesABadLast) {
  start_server();
  for (const char* args :
       {"plot --last 0", "plot --last 17", "plot --last", "plot --svg", "plot extra"}) {
    const RunResult r = run_command(liftctl(args));
    EXPECT_EQ(r.exit_code, 2) << args << ": " << r.output;
  }
  EXPECT_EQ(backend_.travels_asked, 0U);
}

}  // namespace
}  // namespace liftd::api::testing
