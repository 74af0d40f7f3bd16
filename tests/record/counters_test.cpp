// The counting rules of the lift's record (issue #42), with no storage: each event against the
// exact counter values it must leave.
#include "record/counters.hpp"

#include <algorithm>
#include <map>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "record_fixture.hpp"

namespace liftd::record {
namespace {

using testing::aborted_travel;
using testing::arrived_travel;

/// Every fixed counter at 0, then the ones a case names.
std::map<std::string, std::int64_t, std::less<>> expect(
    std::map<std::string, std::int64_t> nonzero) {
  std::map<std::string, std::int64_t, std::less<>> all;
  for (const std::string& name : fixed_counter_names()) all[name] = 0;
  for (const auto& [name, value] : nonzero) all[name] = value;
  return all;
}

Travel with_kind(Travel t, std::string kind) {
  t.kind = std::move(kind);
  return t;
}

struct TravelCase {
  std::string name;
  std::vector<Travel> travels;
  std::map<std::string, std::int64_t> counters;
};

TEST(RecordCounters, each_travel_moves_exactly_its_counters) {
  const std::vector<TravelCase> cases = {
      {"arrived travel",
       {arrived_travel(0, 2, 0, 4000, -3)},
       {{"travels", 1}, {"travels.travel.arrived", 1}, {"motor_starts", 1}, {"running_ms", 4000}}},
      {"aborted travel",
       {aborted_travel(0, 2, 0, "link_down")},
       {{"travels", 1},
        {"travels.travel.aborted", 1},
        {"motor_starts", 1},
        {"running_ms", 1500},
        {"aborts.link_down", 1}}},
      {"relevel",
       {with_kind(arrived_travel(2, 2, 0, 800, 1), "relevel")},
       {{"travels", 1},
        {"travels.relevel.arrived", 1},
        {"motor_starts", 1},
        {"running_ms", 800},
        {"relevels", 1}}},
      {"DCP4's relevelling on remaining distance is a relevelling too",
       {with_kind(arrived_travel(2, 2, 0, 800, 1), "relevel_distance")},
       {{"travels", 1},
        {"travels.relevel_distance.arrived", 1},
        {"motor_starts", 1},
        {"running_ms", 800},
        {"relevels", 1}}},
      {"aborted learning leg, cause in odd letters: a leg is no learning travel",
       {with_kind(aborted_travel(0, 5, 0, "Stop Requested!"), "learn")},
       {{"travels", 1},
        {"travels.learn.aborted", 1},
        {"motor_starts", 1},
        {"running_ms", 1500},
        {"aborts.stop_requested_", 1}}},
      {"empty kind and cause",
       {with_kind(aborted_travel(0, 1, 0, ""), "")},
       {{"travels", 1},
        {"travels.unknown.aborted", 1},
        {"motor_starts", 1},
        {"running_ms", 1500},
        {"aborts.unknown", 1}}},
      {"three travels add up",
       {arrived_travel(0, 1, 0, 3000), arrived_travel(1, 0, 10'000, 3100),
        aborted_travel(0, 3, 20'000, "safety_chain_open")},
       {{"travels", 3},
        {"travels.travel.arrived", 2},
        {"travels.travel.aborted", 1},
        {"motor_starts", 3},
        {"running_ms", 7600},
        {"aborts.safety_chain_open", 1}}},
  };
  for (const TravelCase& c : cases) {
    SCOPED_TRACE(c.name);
    Counters counters;
    for (const Travel& t : c.travels) counters.count_travel(t);
    EXPECT_EQ(counters.values(), expect(c.counters));
  }
}

TEST(RecordCounters, arrivals_and_stop_errors_count_at_the_end_floor_of_arrived_travels) {
  Counters counters;
  counters.count_travel(arrived_travel(0, 2, 0, 4000, -3));
  counters.count_travel(arrived_travel(0, 2, 0, 4000, 5));
  counters.count_travel(arrived_travel(2, 1, 0, 4000, std::nullopt));  // arrival, no error known
  counters.count_travel(aborted_travel(1, 3, 0, "link_down"));         // no arrival
  Travel no_end_floor = arrived_travel(1, 4, 0, 4000, 2);
  no_end_floor.end_floor.reset();
  counters.count_travel(no_end_floor);  // arrived, but at no known floor: no arrival

  ASSERT_EQ(counters.floors().size(), 2U);
  const FloorCounters& second = counters.floors().at(2);
  EXPECT_EQ(second.arrivals, 2);
  EXPECT_EQ(second.stop_error.count(), 2);
  EXPECT_EQ(second.stop_error.sum_mm(), 2);
  EXPECT_EQ(second.stop_error.mean_mm(), 1.0);
  EXPECT_EQ(second.stop_error.worst_mm(), 5);
  const FloorCounters& first = counters.floors().at(1);
  EXPECT_EQ(first.arrivals, 1);
  EXPECT_EQ(first.stop_error.count(), 0);
  EXPECT_EQ(first.stop_error.mean_mm(), std::nullopt);
  EXPECT_EQ(first.stop_error.p95_mm(), std::nullopt);
  EXPECT_EQ(first.stop_error.worst_mm(), std::nullopt);
}

TEST(RecordCounters, faults_and_link_losses) {
  Counters counters;
  counters.count_fault("drive_fault");
  counters.count_fault("drive_fault");
  counters.count_fault("Position.Lost");
  counters.count_link_loss();
  EXPECT_EQ(counters.values(),
            expect({{"faults.drive_fault", 2}, {"faults.position_lost", 1}, {"link_losses", 1}}));
}

TEST(RecordCounters, a_learning_travel_counts_once_whatever_its_legs) {
  Counters counters;
  counters.count_travel(with_kind(arrived_travel(0, 0, 0, 3000), "learn"));
  counters.count_travel(with_kind(arrived_travel(0, 0, 3000, 9000), "learn"));
  counters.count_learning_travel();
  EXPECT_EQ(counters.values().at("learning_travels"), 1);
  EXPECT_EQ(counters.values().at("travels"), 2);
}

TEST(RecordCounters, floor_to_floor_is_an_arrival_at_another_floors_target) {
  struct Case {
    const char* what;
    Travel travel;
    bool expected;
  };
  Travel unknown_start = arrived_travel(0, 2, 0, 4000);
  unknown_start.from_floor.reset();
  Travel no_target = arrived_travel(0, 2, 0, 4000);
  no_target.to_floor.reset();  // an inspection run or a learning leg ending near a level
  Travel short_of_target = arrived_travel(0, 2, 0, 4000);
  short_of_target.end_floor = 1;
  const std::vector<Case> cases = {
      {"from 0 to 2, stood at 2", arrived_travel(0, 2, 0, 4000), true},
      {"aborted", aborted_travel(0, 2, 0, "link_down"), false},
      {"a relevelling at one floor", with_kind(arrived_travel(2, 2, 0, 800), "relevel"), false},
      {"a DCP4 relevelling that crossed to the next floor's window",
       with_kind(arrived_travel(1, 2, 0, 800), "relevel_distance"), false},
      {"no floor at the start", unknown_start, false},
      {"no target", no_target, false},
      {"stood at another floor than its target", short_of_target, false},
  };
  for (const Case& c : cases) EXPECT_EQ(is_floor_to_floor(c.travel), c.expected) << c.what;
}

struct EdgeCase {
  std::vector<bool> looks;
  std::int64_t expected;
};

TEST(RecordCounters, a_door_cycle_is_locked_unlocked_locked_again) {
  const std::vector<EdgeCase> cases = {
      {{true, false, true}, 1},
      {{false, true}, 0},  // started unlocked: the first lock ends no cycle seen whole
      {{false, true, false, true}, 1},
      {{true, true, false, false, true, false, true}, 2},
      {{true, false}, 0},  // not locked again yet
      {{true, false, false, false}, 0},
      {{}, 0},
  };
  for (const EdgeCase& c : cases) {
    SCOPED_TRACE(::testing::PrintToString(c.looks));
    Counters counters;
    std::int64_t now = 0;
    for (bool locked : c.looks) counters.count_inputs({.doors_locked = locked}, now += 10);
    EXPECT_EQ(counters.value("door_cycles"), c.expected);
    EXPECT_EQ(counters.value("safety_chain_openings"), 0);
  }
}

TEST(RecordCounters, a_safety_chain_opening_is_a_closed_to_open_edge) {
  const std::vector<EdgeCase> cases = {
      {{true, false, true, false}, 2},
      {{false, true}, 0},
      {{false, false}, 0},  // open from the first look: no edge seen
      {{true, true, false, false, false}, 1},
  };
  for (const EdgeCase& c : cases) {
    SCOPED_TRACE(::testing::PrintToString(c.looks));
    Counters counters;
    std::int64_t now = 0;
    for (bool closed : c.looks) counters.count_inputs({.safety_chain = closed}, now += 10);
    EXPECT_EQ(counters.value("safety_chain_openings"), c.expected);
    EXPECT_EQ(counters.value("door_cycles"), 0);
  }
}

TEST(RecordCounters, switch_times_run_from_each_look_to_the_next) {
  Counters counters;
  counters.count_inputs({.inspection = true}, 1000);
  counters.count_inputs({.inspection = true, .recall = true}, 1100);
  counters.count_inputs({.recall = true}, 1250);
  counters.count_inputs({.inspection = true}, 1400);
  counters.count_inputs({}, 1500);
  counters.count_inputs({}, 1400);  // a look from the past adds no time
  EXPECT_EQ(counters.value("inspection_ms"), 250 + 100);
  EXPECT_EQ(counters.value("recall_ms"), 150 + 150);
}

TEST(RecordCounters, operating_time_runs_from_the_start_and_never_backwards) {
  Counters counters;
  counters.start_operating(1000);
  counters.count_operating(1500);
  counters.count_operating(1400);
  counters.count_operating(3000);
  EXPECT_EQ(counters.value("operating_ms"), 2000);
}

TEST(RecordCounters, p95_of_stop_errors_is_the_nearest_rank_of_their_sizes) {
  struct Case {
    std::vector<std::int64_t> errors;
    std::int64_t p95;
    std::int64_t worst;
    double mean;
  };
  const std::vector<Case> cases = {
      // 1..20 with alternating signs: rank ceil(0.95 * 20) = 19.
      {{-1, 2, -3, 4, -5, 6, -7, 8, -9, 10, -11, 12, -13, 14, -15, 16, -17, 18, -19, 20},
       19,
       20,
       0.5},
      {{7}, 7, 7, 7.0},
      {{0, 0, 0}, 0, 0, 0.0},
      // 19 of 1 mm and one of 150 (overflow): rank 19 is 1 mm.
      {{1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, -150}, 1, -150, -6.55},
      // 8 small, 2 overflow: rank 10 is in the overflow bucket, which answers the worst.
      {{1, 2, 3, 4, 5, 6, 7, 8, 120, -250}, 250, -250, -9.4},
      // 99 and 100 sit either side of the overflow edge.
      {{99}, 99, 99, 99.0},
      {{100}, 100, 100, 100.0},
      // Equal sizes: the first keeps the worst place.
      {{5, -5}, 5, 5, 0.0},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(::testing::PrintToString(c.errors));
    StopErrorStats stats;
    for (std::int64_t e : c.errors) stats.add(e);
    EXPECT_EQ(stats.count(), static_cast<std::int64_t>(c.errors.size()));
    EXPECT_EQ(stats.p95_mm(), c.p95);
    EXPECT_EQ(stats.worst_mm(), c.worst);
    EXPECT_DOUBLE_EQ(*stats.mean_mm(), c.mean);
  }
}

TEST(RecordCounters, p95_from_the_histogram_equals_the_p95_of_every_value_kept) {
  std::mt19937 random(20261128);
  std::uniform_int_distribution<std::int64_t> error(-99, 99);
  StopErrorStats stats;
  std::vector<std::int64_t> sizes;
  for (int i = 0; i < 1237; ++i) {
    const std::int64_t e = error(random);
    stats.add(e);
    sizes.push_back(e < 0 ? -e : e);
  }
  std::sort(sizes.begin(), sizes.end());
  const std::size_t rank = (95 * sizes.size() + 99) / 100;  // 1176
  EXPECT_EQ(rank, 1176U);
  EXPECT_EQ(stats.p95_mm(), sizes[rank - 1]);
}

TEST(RecordCounters, a_kept_histogram_that_does_not_add_up_is_refused) {
  StopErrorStats::Buckets buckets{};
  buckets[3] = 2;
  StopErrorStats stats;
  EXPECT_FALSE(stats.restore(3, 6, 3, buckets));
  EXPECT_FALSE(stats.restore(2, 6, std::nullopt, buckets));
  EXPECT_TRUE(stats.restore(2, 6, 3, buckets));
  EXPECT_EQ(stats.p95_mm(), 3);
}

TEST(RecordCounters, reset_by_name_prefix_floors_and_all) {
  Counters counters;
  counters.count_travel(arrived_travel(0, 2, 0, 4000, -3));
  counters.count_travel(aborted_travel(0, 2, 0, "link_down"));
  counters.count_fault("drive_fault");
  counters.count_fault("position_lost");
  counters.mark_written();

  ASSERT_EQ(counters.check_reset({"faults.*", "motor_starts"}), std::nullopt);
  counters.apply_reset({"faults.*", "motor_starts"}, "tech", 77);
  EXPECT_EQ(counters.values(), expect({{"faults.drive_fault", 0},
                                       {"faults.position_lost", 0},
                                       {"travels", 2},
                                       {"travels.travel.arrived", 1},
                                       {"travels.travel.aborted", 1},
                                       {"running_ms", 5500},
                                       {"aborts.link_down", 1}}));
  EXPECT_EQ(counters.changed_names(),
            (std::set<std::string, std::less<>>{"faults.drive_fault", "faults.position_lost",
                                                "motor_starts"}));
  EXPECT_EQ(counters.floors().at(2).arrivals, 1);

  counters.apply_reset({"floors"}, "tech", 78);
  EXPECT_EQ(counters.floors().at(2).arrivals, 0);
  EXPECT_EQ(counters.floors().at(2).stop_error.count(), 0);
  EXPECT_EQ(counters.value("travels"), 2);

  counters.apply_reset({"all"}, "tech", 79);
  EXPECT_EQ(counters.values(), expect({{"faults.drive_fault", 0},
                                       {"faults.position_lost", 0},
                                       {"travels.travel.arrived", 0},
                                       {"travels.travel.aborted", 0},
                                       {"aborts.link_down", 0}}));
  ASSERT_EQ(counters.resets().size(), 3U);
  EXPECT_EQ(counters.resets()[0].at_unix_ms, 77);
  EXPECT_EQ(counters.resets()[0].who, "tech");
  EXPECT_EQ(counters.resets()[0].names, (std::vector<std::string>{"faults.*", "motor_starts"}));
}

TEST(RecordCounters, reset_of_an_unknown_name_says_which_and_what_is_allowed) {
  Counters counters;
  counters.count_fault("drive_fault");
  const std::string allowed =
      "give a counter name (travels, motor_starts, running_ms, relevels, learning_travels, "
      "link_losses, door_cycles, safety_chain_openings, inspection_ms, recall_ms, operating_ms, "
      "or a name counters lists), a prefix ending in \".*\" (travels.*, aborts.*, faults.*), "
      "\"floors\" or \"all\"";
  EXPECT_EQ(counters.check_reset({"travels", "motorstarts"}),
            "unknown counter name \"motorstarts\": " + allowed);
  EXPECT_EQ(counters.check_reset({"doors.*"}), "unknown counter name \"doors.*\": " + allowed);
  EXPECT_EQ(counters.check_reset({}), "no counter named to reset: " + allowed);
  // Known families and counters seen so far are accepted, even with nothing counted under them.
  EXPECT_EQ(counters.check_reset({"aborts.*", "faults.drive_fault", "floors", "all"}),
            std::nullopt);
}

}  // namespace
}  // namespace liftd::record
