// liftctl's views of the lift's record: the words of `counters`, `history` and `plot --trend`
// become the documented requests (docs/api.md "The lift's record") or a usage error, and the
// results print as tables and an SVG chart.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "record_view.hpp"

namespace {

using nlohmann::json;
using Words = std::vector<std::string>;

TEST(LiftctlRecord, WordsBecomeTheDocumentedRequests) {
  struct Case {
    Words words;
    json request;
  };
  const Case cases[] = {
      {{"counters"}, {{"cmd", "counters"}}},
      {{"counters", "reset", "faults.*", "link_losses"},
       {{"cmd", "counters_reset"}, {"names", {"faults.*", "link_losses"}}}},
      {{"history"}, {{"cmd", "history"}}},
      {{"history", "--floor", "3", "--from", "2026-10-15", "--limit", "20"},
       {{"cmd", "history"}, {"floor", 3}, {"from", "2026-10-15"}, {"limit", 20}}},
      {{"history", "--outcome", "aborted", "--cause", "link_down", "--to", "2026-11-01T08:00:00Z"},
       {{"cmd", "history"},
        {"outcome", "aborted"},
        {"cause", "link_down"},
        {"to", "2026-11-01T08:00:00Z"}}},
  };
  for (const Case& c : cases) {
    std::string error;
    const auto request = c.words[0] == "counters" ? liftctl::counters_request(c.words, error)
                                                  : liftctl::history_request(c.words, error);
    ASSERT_TRUE(request.has_value()) << c.words[0] << ": " << error;
    EXPECT_EQ(*request, c.request);
  }
  std::string error;
  const auto trend =
      liftctl::trend_request({"plot", "--trend", "--floor", "2", "--svg", "t.svg"}, error);
  ASSERT_TRUE(trend.has_value()) << error;
  EXPECT_EQ(trend->request, (json{{"cmd", "trend"}, {"floor", 2}}));
  EXPECT_EQ(trend->svg_path, "t.svg");
  EXPECT_TRUE(liftctl::wants_trend({"plot", "--trend"}));
  EXPECT_FALSE(liftctl::wants_trend({"plot", "--last", "3"}));
}

TEST(LiftctlRecord, BadWordsSayWhatIsAllowed) {
  struct Case {
    Words words;
    const char* says;
  };
  const Case cases[] = {
      {{"counters", "reset"}, "usage: counters [reset NAME...]"},
      {{"counters", "zero", "all"}, "usage: counters [reset NAME...]"},
      {{"history", "--floor"}, "--floor needs a value"},
      {{"history", "--floor", "two"}, "--floor must be a whole number, not \"two\""},
      {{"history", "--limit", "-5"}, "--limit must be a whole number"},
      {{"history", "--svg", "x.svg"}, "unknown word \"--svg\""},
      {{"history", "3"}, "unknown word \"3\"; usage: history"},
  };
  for (const Case& c : cases) {
    std::string error;
    const auto request = c.words[0] == "counters" ? liftctl::counters_request(c.words, error)
                                                  : liftctl::history_request(c.words, error);
    EXPECT_FALSE(request.has_value()) << c.words[1];
    EXPECT_NE(error.find(c.says), std::string::npos) << error;
  }
  std::string error;
  EXPECT_FALSE(liftctl::trend_request({"plot", "--trend", "--limit", "3"}, error).has_value());
  EXPECT_NE(error.find("usage: plot --trend"), std::string::npos) << error;
}

TEST(LiftctlRecord, CountersPrintOnePerLineThenTheFloors) {
  const json result = json::parse(R"({"record":"on","since":"2026-11-01T07:12:03.000Z",
    "counters":{"motor_starts":2,"travels":2},
    "floors":[{"floor":2,"arrivals":1,"stop_error_mm":{"count":1,"mean":1.5,"p95":2,"worst":-2}}],
    "resets":[{"at":"2026-11-28T10:02:44.310Z","who":"uid 0 pid 7","names":["faults.*"]}]})");
  EXPECT_EQ(liftctl::format_counters(result),
            "since: 2026-11-01T07:12:03.000Z\n"
            "  motor_starts 2\n"
            "  travels      2\n"
            "floor  arrivals  stop error mm: mean    p95  worst\n"
            "    2         1                   1.5    2.0     -2\n"
            "reset 2026-11-28T10:02:44.310Z by uid 0 pid 7: [\"faults.*\"]\n");
}

TEST(LiftctlRecord, HistoryPrintsATravelALineAndSaysWhenMoreMatch) {
  const json result = json::parse(R"({"record":"on","count":1,"truncated":true,"travels":[{"id":2,
    "start":"2026-11-28T09:14:02.117Z","end":"2026-11-28T09:14:09.653Z","start_mono_ms":1,
    "end_mono_ms":2,"from_floor":0,"to_floor":2,"end_floor":2,"kind":"distance",
    "outcome":"arrived","cause":"arrived","duration_ms":7536,"top_speed_mm_s":1600,
    "stop_error_mm":1,"relevel_followed":true}]})");
  const std::string text = liftctl::format_history(result);
  EXPECT_NE(text.find("2026-11-28T09:14:02.117Z  distance         0    2    2 arrived  arrived   "
                      "          7536      1600         1  relevelled\n"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("(more travels match: --limit)"), std::string::npos) << text;
  EXPECT_EQ(liftctl::format_history(json::parse(R"({"travels":[],"count":0})")),
            "no travel in the record matches\n");
}

TEST(LiftctlRecord, TrendPrintsAFloorADayAndDrawsALinePerFloor) {
  const json result = json::parse(R"({"record":"on","days":[
    {"day":"2026-11-27","floor":1,"arrivals":4,"stop_error_mm":{"mean":1.25,"worst":3},
     "travel_ms":{"mean":6100.0,"count":3}},
    {"day":"2026-11-28","floor":1,"arrivals":2,"stop_error_mm":{"mean":-0.5,"worst":-2},
     "travel_ms":{"mean":null,"count":0}},
    {"day":"2026-11-28","floor":2,"arrivals":1,"stop_error_mm":{"mean":2.0,"worst":2},
     "travel_ms":{"mean":7536.0,"count":1}}],"pairs":[]})");
  EXPECT_EQ(liftctl::format_trend(result),
            "day         floor  arrivals  stop error mm: mean  worst  travel s: mean\n"
            "2026-11-27      1         4                  1.2      3            6.10\n"
            "2026-11-28      1         2                 -0.5     -2               -\n"
            "2026-11-28      2         1                  2.0      2            7.54\n");
  const std::string svg = liftctl::render_trend_svg(result);
  EXPECT_EQ(svg.rfind("<svg ", 0), 0U);
  EXPECT_NE(svg.find("</svg>\n"), std::string::npos);
  // Two panels (stopping error, travel time), one line per floor in each.
  std::size_t lines = 0;
  for (std::size_t at = svg.find("<polyline"); at != std::string::npos;
       at = svg.find("<polyline", at + 1)) {
    ++lines;
  }
  EXPECT_EQ(lines, 4U);
  EXPECT_NE(svg.find(">floor 1<"), std::string::npos);
  EXPECT_NE(svg.find(">floor 2<"), std::string::npos);
  EXPECT_NE(svg.find(">2026-11-27<"), std::string::npos);
}

}  // namespace
