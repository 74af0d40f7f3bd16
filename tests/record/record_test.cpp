// The lift's record on a real SQLite file in a temporary directory: what survives a restart,
// the history and trend answers, pruning, the relevel mark and resets (issue #42).
#include "record/lift_record.hpp"

#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "record_fixture.hpp"

namespace liftd::record {
namespace {

using nlohmann::json;
using testing::aborted_travel;
using testing::arrived_travel;
using testing::kDay0;
using testing::kMono0;
using testing::options_at;
using testing::Peek;
using testing::TempDir;

TEST(Record, starts_on_with_an_empty_record) {
  TempDir dir;
  LiftRecord record(options_at(dir.file("record.db")), kMono0, kDay0);
  ASSERT_TRUE(record.on()) << record.status_json().dump();
  EXPECT_EQ(record.status_json(), json::parse(R"({"state":"on","path":")" + dir.file("record.db") +
                                              R"(","reason":null,"travels":0})"));
  const json counters = record.counters_json();
  EXPECT_EQ(counters["since"], "2026-11-28T00:00:00.000Z");
  EXPECT_EQ(counters["record"], "on");
  EXPECT_EQ(counters["counters"]["travels"], 0);
  EXPECT_EQ(counters["floors"], json::array());
  EXPECT_EQ(counters["resets"], json::array());
  Peek peek(dir.file("record.db"));
  EXPECT_EQ(peek.text("PRAGMA journal_mode"), "wal");
  EXPECT_EQ(peek.number("PRAGMA user_version"), 1);
  EXPECT_EQ(peek.number("PRAGMA page_size"), 1024);
}

TEST(Record, counters_floors_and_resets_survive_a_restart) {
  TempDir dir;
  json before;
  {
    LiftRecord record(options_at(dir.file("record.db")), kMono0, kDay0);
    record.travel(arrived_travel(0, 2, 0, 4000, -3), kMono0 + 5000, kDay0 + 5000);
    record.travel(arrived_travel(2, 0, 10'000, 4100, 2), kMono0 + 15'000, kDay0 + 15'000);
    record.travel(aborted_travel(0, 1, 20'000, "link_down"), kMono0 + 22'000, kDay0 + 22'000);
    ASSERT_TRUE(record.reset({"motor_starts"}, "api:alice", kDay0 + 23'000).ok);
    // Counted after the last transaction, before the interval: the destructor writes them.
    record.fault_raised("drive_fault", kMono0 + 24'000);
    record.link_lost(kMono0 + 24'000);
    record.tick(kMono0 + 25'000, kDay0 + 25'000);
    before = record.counters_json();
  }
  EXPECT_EQ(before["counters"]["travels"], 3);
  EXPECT_EQ(before["counters"]["motor_starts"], 0);
  EXPECT_EQ(before["counters"]["faults.drive_fault"], 1);
  EXPECT_EQ(before["counters"]["operating_ms"], 25'000);
  EXPECT_EQ(before["floors"], json::parse(R"([
      {"floor":0,"arrivals":1,"stop_error_mm":{"count":1,"mean":2.0,"p95":2,"worst":2}},
      {"floor":2,"arrivals":1,"stop_error_mm":{"count":1,"mean":-3.0,"p95":3,"worst":-3}}])"));
  EXPECT_EQ(before["resets"], json::parse(R"([{"at":"2026-11-28T00:00:23.000Z","who":"api:alice",
                                                "names":["motor_starts"]}])"));

  // A later start: the same counters, the first start's "since", operating time counting on.
  LiftRecord again(options_at(dir.file("record.db")), 50, kDay0 + 86'400'000);
  ASSERT_TRUE(again.on()) << again.status_json().dump();
  EXPECT_EQ(again.counters_json(), before);
  EXPECT_EQ(again.status_json()["travels"], 3);
  again.tick(1050, kDay0 + 86'400'050);
  EXPECT_EQ(again.counters_json()["counters"]["operating_ms"], 26'000);
}

TEST(Record, counters_without_a_travel_are_written_once_the_interval_has_passed) {
  TempDir dir;
  Options options = options_at(dir.file("record.db"));
  options.counters_interval_ms = 60'000;
  LiftRecord record(options, kMono0, kDay0);
  Peek peek(dir.file("record.db"));
  const std::string faults = "SELECT value FROM counters WHERE name = 'faults.drive_fault'";
  record.fault_raised("drive_fault", kMono0 + 10);
  record.tick(kMono0 + 59'999, kDay0 + 59'999);
  EXPECT_EQ(peek.text(faults), "");
  record.tick(kMono0 + 60'000, kDay0 + 60'000);
  EXPECT_EQ(peek.text(faults), "1");
  EXPECT_EQ(peek.number("SELECT value FROM counters WHERE name = 'operating_ms'"), 60'000);
  // Nothing but time changed since: the next write waits a whole interval again.
  record.fault_raised("drive_fault", kMono0 + 60'010);
  record.tick(kMono0 + 119'999, kDay0 + 119'999);
  EXPECT_EQ(peek.text(faults), "1");
  // A travel's transaction writes every changed counter at once.
  record.travel(arrived_travel(0, 1, 120'000, 3000), kMono0 + 123'000, kDay0 + 123'000);
  EXPECT_EQ(peek.text(faults), "2");
  EXPECT_EQ(peek.number("SELECT value FROM counters WHERE name = 'travels'"), 1);
}

class RecordHistory : public ::testing::Test {
 protected:
  void SetUp() override {
    Options options = options_at(dir_.file("record.db"));
    record_ = std::make_unique<LiftRecord>(options, kMono0, kDay0);
    ASSERT_TRUE(record_->on());
    // ids 1..6, each a minute after the one before.
    write(arrived_travel(0, 3, 0, 6000, -2));
    write(aborted_travel(3, 1, 60'000, "link_down"));
    write(arrived_travel(3, 1, 120'000, 4000, 4));
    write(aborted_travel(1, 4, 180'000, "stop_requested"));
    write(arrived_travel(1, 0, 240'000, 3500, std::nullopt));
    write(aborted_travel(0, 2, 300'000, "link_down"));
  }
  void write(Travel t) { record_->travel(std::move(t), kMono0, kDay0); }
  std::vector<std::int64_t> ids(const HistoryQuery& query) {
    const json answer = record_->history_json(query);
    std::vector<std::int64_t> out;
    for (const json& t : answer["travels"]) out.push_back(t["id"].get<std::int64_t>());
    EXPECT_EQ(answer["count"], out.size());
    return out;
  }

  TempDir dir_;
  std::unique_ptr<LiftRecord> record_;
};

using Ids = std::vector<std::int64_t>;

TEST_F(RecordHistory, every_field_of_a_travel_comes_back) {
  HistoryQuery query;
  query.limit = 1;
  const json answer = record_->history_json(query);
  EXPECT_EQ(answer, json::parse(R"({"record":"on","count":1,"truncated":true,"travels":[
      {"id":6,"start":"2026-11-28T00:05:00.000Z","end":"2026-11-28T00:05:01.500Z",
       "start_mono_ms":305000,"end_mono_ms":306500,"from_floor":0,"to_floor":2,"end_floor":null,
       "kind":"travel","outcome":"aborted","cause":"link_down","duration_ms":1500,
       "top_speed_mm_s":400,"stop_error_mm":null,"relevel_followed":false}]})"));
}

TEST_F(RecordHistory, newest_first_with_each_filter) {
  EXPECT_EQ(ids({}), (Ids{6, 5, 4, 3, 2, 1}));
  EXPECT_EQ(ids({.from_unix_ms = kDay0 + 60'000, .to_unix_ms = kDay0 + 240'000}), (Ids{4, 3, 2}));
  EXPECT_EQ(ids({.from_unix_ms = kDay0 + 60'001}), (Ids{6, 5, 4, 3}));
  EXPECT_EQ(ids({.to_unix_ms = kDay0 + 60'000}), (Ids{1}));
  EXPECT_EQ(ids({.floor = 1}), (Ids{5, 4, 3, 2}));
  EXPECT_EQ(ids({.floor = 0}), (Ids{6, 5, 1}));
  EXPECT_EQ(ids({.floor = 9}), (Ids{}));
  EXPECT_EQ(ids({.outcome = "arrived"}), (Ids{5, 3, 1}));
  EXPECT_EQ(ids({.outcome = "aborted"}), (Ids{6, 4, 2}));
  EXPECT_EQ(ids({.cause = "link_down"}), (Ids{6, 2}));
  EXPECT_EQ(ids({.floor = 3, .outcome = "aborted", .cause = "link_down"}), (Ids{2}));
  EXPECT_EQ(ids({.limit = 2}), (Ids{6, 5}));
  EXPECT_EQ(record_->history_json({.limit = 2})["truncated"], true);
  EXPECT_EQ(record_->history_json({.limit = 6})["truncated"], false);
  EXPECT_EQ(ids({.limit = 0}), (Ids{}));
}

TEST_F(RecordHistory, a_bad_outcome_is_refused_with_what_is_allowed) {
  const json answer = record_->history_json({.outcome = "done"});
  EXPECT_EQ(answer["error"], "outcome must be \"arrived\" or \"aborted\", not \"done\"");
  EXPECT_EQ(answer["travels"], json::array());
}

TEST(Record, only_the_newest_travels_and_curves_are_kept) {
  TempDir dir;
  Options options = options_at(dir.file("record.db"));
  options.max_travels = 5;
  options.curves_kept = 2;
  LiftRecord record(options, kMono0, kDay0);
  for (int i = 0; i < 8; ++i) {
    Travel t = arrived_travel(i % 3, (i + 1) % 3, i * 60'000, 3000);
    t.curve_json = R"({"samples":[{"t_ms":0,"position_mm":)" + std::to_string(i) + "}]}";
    record.travel(std::move(t), kMono0, kDay0);
  }
  EXPECT_EQ(record.status_json()["travels"], 5);
  const json answer = record.history_json({.curves = true});
  ASSERT_EQ(answer["count"], 5);
  std::vector<std::int64_t> ids;
  for (const json& t : answer["travels"]) ids.push_back(t["id"].get<std::int64_t>());
  EXPECT_EQ(ids, (Ids{8, 7, 6, 5, 4}));
  EXPECT_EQ(answer["travels"][0]["curve"],
            json::parse(R"({"samples":[{"t_ms":0,"position_mm":7}]})"));
  EXPECT_EQ(answer["travels"][1]["curve"],
            json::parse(R"({"samples":[{"t_ms":0,"position_mm":6}]})"));
  EXPECT_FALSE(answer["travels"][2].contains("curve"));
  EXPECT_FALSE(record.history_json({})["travels"][0].contains("curve"));
  // The lifetime counters keep every travel, the table only the newest.
  EXPECT_EQ(record.counters_json()["counters"]["travels"], 8);
  Peek peek(dir.file("record.db"));
  EXPECT_EQ(peek.number("SELECT count(*) FROM travels"), 5);
  EXPECT_EQ(peek.number("SELECT count(*) FROM curves"), 2);
  EXPECT_EQ(peek.number("SELECT min(travel_id) FROM curves"), 7);
}

TEST(Record, a_kept_curve_that_is_no_json_is_named_as_such) {
  TempDir dir;
  LiftRecord record(options_at(dir.file("record.db")), kMono0, kDay0);
  Travel t = arrived_travel(0, 1, 0, 3000);
  t.curve_json = "{\"samples\":[";  // cut short
  record.travel(std::move(t), kMono0, kDay0);
  const json travel = record.history_json({.curves = true})["travels"][0];
  EXPECT_EQ(travel["curve"], nullptr);
  EXPECT_EQ(travel["curve_error"], "the kept curve is not valid JSON");
}

TEST(Record, a_relevel_at_the_same_floor_marks_the_travel_before_it) {
  TempDir dir;
  LiftRecord record(options_at(dir.file("record.db")), kMono0, kDay0);
  const auto relevel_at = [](int floor, std::int64_t start_ms) {
    Travel t = arrived_travel(floor, floor, start_ms, 700, 1);
    t.kind = "relevel";
    return t;
  };
  record.travel(arrived_travel(0, 3, 0, 5000, 9), kMono0, kDay0);       // id 1: relevel follows
  record.travel(relevel_at(3, 10'000), kMono0, kDay0);                  // id 2
  record.travel(arrived_travel(3, 1, 20'000, 5000, 9), kMono0, kDay0);  // id 3: none follows
  record.travel(relevel_at(2, 30'000), kMono0, kDay0);  // id 4: at another floor, marks nothing
  std::vector<bool> marks;
  const json history = record.history_json({});
  for (const json& t : history["travels"]) {
    marks.push_back(t["relevel_followed"].get<bool>());
  }
  EXPECT_EQ(marks, (std::vector<bool>{false, false, false, true}));
  // The mark is kept: a restart finds it, and the relevel after a restart still finds its travel.
  LiftRecord again(options_at(dir.file("record.db")), kMono0, kDay0);
  again.travel(relevel_at(2, 40'000), kMono0, kDay0);  // id 5, after id 4 at floor 2
  marks.clear();
  const json history_again = again.history_json({});
  for (const json& t : history_again["travels"]) {
    marks.push_back(t["relevel_followed"].get<bool>());
  }
  EXPECT_EQ(marks, (std::vector<bool>{false, true, false, false, true}));
  // A travel from a floor to itself is listed once for that floor.
  std::vector<std::int64_t> at_two;
  const json history_two = again.history_json({.floor = 2});
  for (const json& t : history_two["travels"]) at_two.push_back(t["id"].get<std::int64_t>());
  EXPECT_EQ(at_two, (std::vector<std::int64_t>{5, 4}));
}

TEST(Record, trend_aggregates_per_day_and_floor_and_per_pair) {
  TempDir dir;
  LiftRecord record(options_at(dir.file("record.db")), kMono0, kDay0);
  const std::int64_t day = 86'400'000;
  record.travel(arrived_travel(0, 2, 1000, 4000, -2), kMono0, kDay0);
  record.travel(arrived_travel(1, 2, 2000, 3000, 5), kMono0, kDay0);
  record.travel(arrived_travel(0, 2, 3000, 4200, 1), kMono0, kDay0);
  record.travel(aborted_travel(2, 0, 4000, "link_down"), kMono0, kDay0);  // no arrival
  Travel relevel = arrived_travel(2, 2, 5000, 600, -1);
  relevel.kind = "relevel";  // an arrival with its error, but no floor-to-floor time
  record.travel(relevel, kMono0, kDay0);
  record.travel(arrived_travel(2, 0, day + 1000, 4100, std::nullopt), kMono0, kDay0);
  record.travel(arrived_travel(2, 0, 3 * day, 4100, 0), kMono0, kDay0);  // outside the range

  const json trend = record.trend_json({.from_unix_ms = kDay0, .to_unix_ms = kDay0 + 2 * day});
  EXPECT_EQ(trend, json::parse(R"({"record":"on",
    "days":[
      {"day":"2026-11-28","floor":2,"arrivals":4,
       "stop_error_mm":{"count":4,"mean":0.75,"worst":5},"travel_ms":{"count":3,"mean":3733.33}},
      {"day":"2026-11-29","floor":0,"arrivals":1,
       "stop_error_mm":{"count":0,"mean":null,"worst":null},"travel_ms":{"count":1,"mean":4100.0}}],
    "pairs":[
      {"day":"2026-11-28","from":0,"to":2,"count":2,"mean_ms":4100.0},
      {"day":"2026-11-28","from":1,"to":2,"count":1,"mean_ms":3000.0},
      {"day":"2026-11-29","from":2,"to":0,"count":1,"mean_ms":4100.0}]})"));

  // A range inside one day covers that whole day; a floor keeps its rows and the pairs it is in.
  const json one = record.trend_json(
      {.from_unix_ms = kDay0 + day + 5, .to_unix_ms = kDay0 + day + 6, .floor = 0});
  EXPECT_EQ(one["days"].size(), 1U);
  EXPECT_EQ(one["days"][0]["day"], "2026-11-29");
  EXPECT_EQ(one["pairs"].size(), 1U);
  EXPECT_EQ(record.trend_json({.floor = 1})["days"], json::array());
  EXPECT_EQ(record.trend_json({.floor = 1})["pairs"].size(), 1U);
  EXPECT_EQ(record.trend_json({})["days"].size(), 3U);
}

TEST(Record, reset_is_kept_and_an_unknown_name_is_refused) {
  TempDir dir;
  {
    LiftRecord record(options_at(dir.file("record.db")), kMono0, kDay0);
    record.fault_raised("drive_fault", kMono0);
    record.travel(arrived_travel(0, 1, 0, 3000, 2), kMono0, kDay0);
    const ResetResult refused = record.reset({"faults.*", "door_cycle"}, "api", kDay0 + 1);
    EXPECT_FALSE(refused.ok);
    EXPECT_TRUE(
        refused.error.starts_with("unknown counter name \"door_cycle\": give a counter name ("))
        << refused.error;
    EXPECT_EQ(record.counters_json()["counters"]["faults.drive_fault"], 1);  // nothing reset
    EXPECT_EQ(record.counters_json()["resets"], json::array());
    const ResetResult done = record.reset({"faults.*", "floors"}, "api", kDay0 + 2);
    EXPECT_TRUE(done.ok);
    EXPECT_EQ(done.error, "");
  }
  LiftRecord again(options_at(dir.file("record.db")), kMono0, kDay0);
  const json counters = again.counters_json();
  EXPECT_EQ(counters["counters"]["faults.drive_fault"], 0);
  EXPECT_EQ(counters["counters"]["travels"], 1);
  EXPECT_EQ(counters["floors"], json::parse(R"([{"floor":1,"arrivals":0,
      "stop_error_mm":{"count":0,"mean":null,"p95":null,"worst":null}}])"));
  EXPECT_EQ(counters["resets"], json::parse(R"([{"at":"2026-11-28T00:00:00.002Z","who":"api",
      "names":["faults.*","floors"]}])"));
  Peek peek(dir.file("record.db"));
  EXPECT_EQ(peek.number("SELECT count(*) FROM resets"), 1);
}

}  // namespace
}  // namespace liftd::record
