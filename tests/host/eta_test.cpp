// `eta` (docs/api.md "Arrival times"): the profile before any travel, what one measured travel
// teaches, the stops queued before a floor, a running travel, a floor added to the queue, and
// a car out of service. Times are worked out by hand from the trapezoid profile.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "host/eta.hpp"

namespace liftd::daemon {
namespace {

// Six floors 3 m apart; 1 m/s, 0.5 m/s^2, 2 s overhead, 3 s at a stop.
TravelTimes six_floors() {
  return TravelTimes({0, 3000, 6000, 9000, 12000, 15000}, EtaDefaults{1000.0, 500.0, 2.0, 3.0});
}

double floor_s(const nlohmann::json& answer, int floor) {
  return answer.at("floors").at(static_cast<std::size_t>(floor)).at("s").get<double>();
}

EtaCar at_rest(int floor) {
  EtaCar car;
  car.floor = floor;
  car.position_mm = floor * 3000;
  return car;
}

// A hydraulic travel's samples: 1 s up the ramp to 500 mm/s, 10 s at speed with the position's
// noise (+-25 mm/s), 0.9 s down to the slow speed, 5 s at 50 mm/s. Its speed is the run at speed,
// 500, where the fastest tenth's slowest read 525 (the noise's top).
TEST(EtaProfile, TheTravelsSpeedIsItsRunAtSpeedNotItsNoisiestSamples) {
  std::vector<double> speeds;
  for (int i = 1; i <= 10; ++i) speeds.push_back(50.0 * i);  // the ramp, 100 ms apart
  for (int i = 0; i < 100; ++i) speeds.push_back(500.0 + ((i % 5) - 2) * 12.5);  // -25..+25
  for (int i = 1; i <= 9; ++i) speeds.push_back(500.0 - 50.0 * i);  // down to the slow speed
  for (int i = 0; i < 50; ++i) speeds.push_back(-50.0 + 0.0 * i);   // any sign is a speed
  speeds.push_back(0.0);                                            // at rest: no speed
  EXPECT_DOUBLE_EQ(cruise_speed_mm_s(speeds), 500.0);
  EXPECT_DOUBLE_EQ(cruise_speed_mm_s({}), 0.0);
  EXPECT_DOUBLE_EQ(cruise_speed_mm_s({0.0, 0.0}), 0.0);
  EXPECT_DOUBLE_EQ(cruise_speed_mm_s({-800.0}), 800.0);
}

TEST(EtaProfile, TrapezoidAndTriangleFromTheConfiguredProfile) {
  const TravelTimes t = six_floors();
  struct Case {
    double distance_mm;
    double seconds;
  };
  // Ramps together: v^2/a = 2000 mm, taking v/a = 2 s. 3000 mm: 3 s + 2 s; 1000 mm (a
  // triangle): 2 sqrt(1000/500) = 2.828 s; each plus the 2 s overhead.
  for (const Case c : {Case{3000.0, 7.0}, Case{15000.0, 19.0}, Case{2000.0, 6.0},
                       Case{1000.0, 2.0 + 2.0 * std::sqrt(2.0)}, Case{0.0, 2.0}}) {
    EXPECT_NEAR(t.profile_s(c.distance_mm), c.seconds, 1e-9) << c.distance_mm;
  }
}

TEST(Eta, AtRestEveryFloorIsOneTravelAway) {
  const nlohmann::json a = estimate_eta(six_floors(), at_rest(2), {});
  EXPECT_TRUE(a.at("in_service").get<bool>());
  EXPECT_TRUE(a.at("stops").empty());
  const std::vector<double> want = {10.0, 7.0, 0.0, 7.0, 10.0, 13.0};
  for (int f = 0; f < 6; ++f) EXPECT_NEAR(floor_s(a, f), want[static_cast<std::size_t>(f)], 1e-3);
  EXPECT_TRUE(a.at("floors").at(2).at("learned").get<bool>());
  EXPECT_FALSE(a.at("floors").at(3).at("learned").get<bool>());
}

TEST(Eta, AMeasuredPairIsTakenAsMeasuredAndTheProfileFittedToIt) {
  TravelTimes t = six_floors();
  // 0 -> 3 (9000 mm) in 12.5 s at 1.5 m/s, 90 % of it 2 s after the start of motion.
  t.travel({0, 3, 12.5, 1500.0, 2.0});
  EXPECT_NEAR(t.leg_s(0, 3), 12.5, 1e-9);
  EXPECT_TRUE(t.learned(0, 3));
  EXPECT_FALSE(t.learned(3, 0));  // each direction is its own pair
  // Fitted: a = 0.9 * 1500 / 2 = 675; motion of 9000 mm = 6 s + 1500/675 s; the overhead is
  // the rest of the 12.5 s.
  const double motion = 9000.0 / 1500.0 + 1500.0 / 675.0;
  EXPECT_NEAR(t.profile_s(9000.0), 12.5, 1e-9);
  EXPECT_NEAR(t.profile_s(6000.0), 12.5 - motion + 6000.0 / 1500.0 + 1500.0 / 675.0, 1e-9);
  // The median of the newest measurements, not the last one.
  t.travel({0, 3, 12.0, 1500.0, 2.0});
  t.travel({0, 3, 19.0, 1500.0, 2.0});  // one slow start does not move it far
  EXPECT_NEAR(t.leg_s(0, 3), 12.5, 1e-9);
  // Nonsense is not learned.
  t.travel({0, 0, 5.0, 1000.0, 1.0});
  t.travel({0, 9, 5.0, 1000.0, 1.0});
  t.travel({1, 2, -1.0, 1000.0, 1.0});
  EXPECT_FALSE(t.learned(0, 0));
  EXPECT_FALSE(t.learned(1, 2));
}

// A car at 1.5 m/s and 0.675 m/s^2 with 3 s beyond its motion on every travel. Its first travel
// told no speed (the configured 1 m/s and 0.5 m/s^2 stand then); the second did. The overhead is
// fitted to both with the profile as it stands now: 3 s, so a pair never travelled comes out
// right, where the first travel's overhead fixed against the configured profile (1.22 s) put the
// median at 2.11 s and a 12 m travel 0.89 s short.
TEST(Eta, TheOverheadIsFittedWithTheProfileAsItStandsNow) {
  TravelTimes t = six_floors();
  const double ramp = 1500.0 / 675.0;  // accelerating and decelerating, at 675 mm/s^2
  t.travel({0, 2, 6000.0 / 1500.0 + ramp + 3.0, 0.0, std::nullopt});
  t.travel({0, 3, 9000.0 / 1500.0 + ramp + 3.0, 1500.0, 2.0});  // a = 0.9 * 1500 / 2 = 675
  EXPECT_NEAR(t.profile_s(12000.0), 12000.0 / 1500.0 + ramp + 3.0, 1e-9);
  EXPECT_NEAR(t.basis_json().at("up").at("overhead_s").get<double>(), 3.0, 1e-3);
}

TEST(Eta, EachDirectionHasItsOwnProfileOnceMeasured) {
  // A hydraulic car: up on its pump at 0.6 m/s, down on its valve at 0.3 m/s.
  TravelTimes t = six_floors();
  t.travel({0, 1, 9.0, 600.0, 1.0});
  EXPECT_NEAR(t.profile_s(6000.0, false), t.profile_s(6000.0, true), 1e-9);  // down: up's, yet
  t.travel({3, 2, 14.0, 300.0, 1.0});
  EXPECT_NEAR(t.leg_s(4, 2) - t.leg_s(4, 3), 3000.0 / 300.0, 1e-9);  // at 0.3 m/s
  EXPECT_NEAR(t.leg_s(2, 4) - t.leg_s(3, 4), 3000.0 / 600.0, 1e-9);  // at 0.6 m/s
}

TEST(Eta, ACarThatJustArrivedStartsOnceItsStopTimeIsOver) {
  EtaCar car = at_rest(0);
  car.since_arrival_s = 1.0;  // of the 3 s a stop takes
  const nlohmann::json a = estimate_eta(six_floors(), car, {});
  EXPECT_NEAR(floor_s(a, 1), 2.0 + 7.0, 1e-3);
  EXPECT_NEAR(floor_s(a, 0), 0.0, 1e-3);  // where it stands: there now
}

TEST(Eta, FromRestTheMeasuredStartComesFirst) {
  TravelTimes t = six_floors();
  t.start(0.2);
  t.start(0.4);
  t.start(0.3);
  EXPECT_DOUBLE_EQ(t.start_s(), 0.3);
  EXPECT_NEAR(floor_s(estimate_eta(t, at_rest(0), {}), 1), 0.3 + 7.0, 1e-3);
  EtaCar just_arrived = at_rest(0);
  just_arrived.since_arrival_s = 2.0;  // 1 s of the 3 s stop left: longer than the start
  EXPECT_NEAR(floor_s(estimate_eta(t, just_arrived, {}), 1), 1.0 + 7.0, 1e-3);
}

TEST(Eta, QueuedStopsComeFirstEachWithItsStopTime) {
  EtaCar car = at_rest(0);
  car.calls = {3, 1};
  const nlohmann::json a = estimate_eta(six_floors(), car, {});
  // 0 -> 3: 9 + 2 + 2 = 13 s; stop 3 s; 3 -> 1 (6000 mm): 6 + 2 + 2 = 10 s.
  ASSERT_EQ(a.at("stops").size(), 2U);
  EXPECT_EQ(a.at("stops").at(0).at("floor"), 3);
  EXPECT_NEAR(a.at("stops").at(0).at("s").get<double>(), 13.0, 1e-3);
  EXPECT_NEAR(a.at("stops").at(1).at("s").get<double>(), 26.0, 1e-3);
  EXPECT_NEAR(floor_s(a, 3), 13.0, 1e-3);  // a queued floor: its stop
  EXPECT_NEAR(floor_s(a, 1), 26.0, 1e-3);
  // Not queued: after the last stop, its stop time, then the travel there (1 -> 5: 12000 mm).
  EXPECT_NEAR(floor_s(a, 5), 26.0 + 3.0 + 16.0, 1e-3);
  EXPECT_NEAR(floor_s(a, 0), 26.0 + 3.0 + 7.0, 1e-3);  // back to where it stands now
}

TEST(Eta, ARunningTravelCountsFromItsStart) {
  TravelTimes t = six_floors();
  t.travel({1, 4, 14.0, 1000.0, 1.8});
  EtaCar car;
  car.position_mm = 5000;
  car.travelling = true;
  car.origin = 1;
  car.target = 4;
  car.elapsed_s = 5.5;
  car.calls = {2};
  const nlohmann::json a = estimate_eta(t, car, {});
  ASSERT_EQ(a.at("stops").size(), 2U);
  EXPECT_NEAR(a.at("stops").at(0).at("s").get<double>(), 8.5, 1e-3);
  EXPECT_TRUE(a.at("stops").at(0).at("learned").get<bool>());
  EXPECT_NEAR(floor_s(a, 4), 8.5, 1e-3);
  // Then the stop at 4 and 4 -> 2, which the profile gives.
  EXPECT_NEAR(floor_s(a, 2), 8.5 + 3.0 + t.leg_s(4, 2), 1e-3);
  EXPECT_FALSE(a.at("stops").at(1).at("learned").get<bool>());
  // Late: a travel that takes longer than it did is due now, never in the past.
  car.elapsed_s = 20.0;
  EXPECT_NEAR(floor_s(estimate_eta(t, car, {}), 4), 0.0, 1e-9);
}

TEST(Eta, AFloorAddedSaysWhatItCostsEachLaterStop) {
  EtaCar car = at_rest(0);
  car.calls = {3, 5};
  const TravelTimes t = six_floors();
  // At the end: nobody waits longer.
  nlohmann::json a = estimate_eta(t, car, {1, std::nullopt});
  EXPECT_EQ(a.at("with").at("position"), 2);
  EXPECT_NEAR(a.at("with").at("s").get<double>(), floor_s(a, 1), 1e-3);
  for (const auto& d : a.at("with").at("delays")) EXPECT_EQ(d.at("s").get<double>(), 0.0);
  // First: 0 -> 1 (7 s), stop, 1 -> 3 (10 s) instead of 0 -> 3 (13 s): 3 and 5 are 7 s later.
  a = estimate_eta(t, car, {1, 0});
  EXPECT_NEAR(a.at("with").at("s").get<double>(), 7.0, 1e-3);
  ASSERT_EQ(a.at("with").at("delays").size(), 2U);
  EXPECT_EQ(a.at("with").at("delays").at(0).at("floor"), 3);
  EXPECT_NEAR(a.at("with").at("delays").at(0).at("s").get<double>(), 7.0, 1e-3);
  EXPECT_NEAR(a.at("with").at("delays").at(1).at("s").get<double>(), 7.0, 1e-3);
  // Between: a floor on the way (4, between 3 and 5) costs 5 only the stop and the extra start.
  a = estimate_eta(t, car, {4, 1});
  EXPECT_NEAR(a.at("with").at("delays").at(0).at("s").get<double>(), 0.0, 1e-3);
  EXPECT_NEAR(a.at("with").at("delays").at(1).at("s").get<double>(),
              t.leg_s(3, 4) + 3.0 + t.leg_s(4, 5) - t.leg_s(3, 5), 1e-3);
}

TEST(Eta, ACarOutOfServiceGivesNoTimes) {
  EtaCar car = at_rest(1);
  car.in_service = false;
  car.reason = "inspection";
  const nlohmann::json a = estimate_eta(six_floors(), car, {2, std::nullopt});
  EXPECT_FALSE(a.at("in_service").get<bool>());
  EXPECT_EQ(a.at("reason"), "inspection");
  EXPECT_TRUE(a.at("floors").is_null());
  EXPECT_TRUE(a.at("with").is_null());
  // Nor does a car whose position nobody knows.
  EtaCar lost;
  EXPECT_TRUE(estimate_eta(six_floors(), lost, {}).at("floors").is_null());
}

TEST(Eta, TheStopTimeIsTheMeasuredMedian) {
  TravelTimes t = six_floors();
  EXPECT_DOUBLE_EQ(t.stop_s(), 3.0);
  t.stop(1.0);
  t.stop(1.4);
  t.stop(9.0);
  EXPECT_DOUBLE_EQ(t.stop_s(), 1.4);
}

TEST(Eta, AStopNotMeasuredYetLastsAtLeastTheStartTime) {
  // The next travel of a queue is asked for at the arrival at the earliest, so the car cannot
  // stand shorter than a request takes to its run's start. The configured 3.0 s holds until a
  // start time longer than it is measured; a measured stop wins over both.
  TravelTimes t = six_floors();
  t.start(1.0);
  EXPECT_DOUBLE_EQ(t.stop_s(), 3.0);
  t.start(4.5);
  t.start(4.5);
  EXPECT_DOUBLE_EQ(t.stop_s(), 4.5);
  t.stop(2.0);
  EXPECT_DOUBLE_EQ(t.stop_s(), 2.0);
}

TEST(EtaKinds, OnlyFloorToFloorTravelsAreLearned) {
  for (const char* kind : {"distance", "speed", "hydraulic"}) {
    EXPECT_TRUE(eta_floor_to_floor(kind)) << kind;
  }
  for (const char* kind :
       {"relevel", "relevel_distance", "inspection", "recall", "learn", "crawl"}) {
    EXPECT_FALSE(eta_floor_to_floor(kind)) << kind;
  }
}

TEST(Eta, AFloorPlannedAlreadyCostsNothing) {
  // `calls add` of a floor already queued adds nothing: `with` is its stop as planned.
  EtaCar car = at_rest(0);
  car.calls = {2, 4};
  const TravelTimes times = six_floors();
  const nlohmann::json plain = estimate_eta(times, car, {});
  const nlohmann::json again = estimate_eta(times, car, {4, std::nullopt});
  EXPECT_EQ(again["with"]["queued"], true);
  EXPECT_TRUE(again["with"]["position"].is_null());
  EXPECT_EQ(again["with"]["s"], plain["stops"][1]["s"]);
  for (const auto& d : again["with"]["delays"]) EXPECT_EQ(d["s"], 0.0);
  // At a position the dispatcher chose, the floor is a stop more, as `calls insert` makes it.
  const nlohmann::json inserted = estimate_eta(times, car, {4, std::size_t{0}});
  EXPECT_EQ(inserted["with"]["queued"], false);
  EXPECT_EQ(inserted["with"]["position"], 0);
}

TEST(EtaPreload, TheRecordsFloorToFloorArrivalsAreLearnedOldestFirst) {
  // A `history` answer's travels, newest first: only arrived floor-to-floor runs between two
  // floors that ended standing at their target count.
  const auto travel = [](const char* kind, const char* outcome, nlohmann::json from, int to,
                         nlohmann::json end, int duration_ms, nlohmann::json error_mm) {
    return nlohmann::json{{"kind", kind},
                          {"outcome", outcome},
                          {"from_floor", from},
                          {"to_floor", to},
                          {"end_floor", end},
                          {"duration_ms", duration_ms},
                          {"stop_error_mm", error_mm},
                          {"top_speed_mm_s", 1000}};
  };
  const nlohmann::json travels = nlohmann::json::array({
      travel("distance", "arrived", 0, 2, 2, 9000, 1),              // newest: 0 -> 2 in 9 s
      travel("distance", "arrived", 0, 2, 2, 7000, -2),             // older: 7 s
      travel("distance", "aborted", 0, 3, nullptr, 4000, nullptr),  // ended early
      travel("relevel_distance", "arrived", 1, 1, 1, 900, 0),       // not floor to floor
      travel("distance", "arrived", nullptr, 4, 4, 5000, 0),        // started between floors
      travel("distance", "arrived", 0, 5, 5, 14000, 40),            // stood off its level
      travel("hydraulic", "arrived", 5, 1, 1, 16000, 3),
  });
  TravelTimes times = six_floors();
  EXPECT_EQ(preload_travel_times(times, travels, 20), 3U);
  EXPECT_TRUE(times.learned(0, 2));
  EXPECT_TRUE(times.learned(5, 1));
  EXPECT_FALSE(times.learned(0, 3));
  EXPECT_FALSE(times.learned(0, 5));
  EXPECT_FALSE(times.learned(1, 4));
  EXPECT_DOUBLE_EQ(times.leg_s(0, 2), 8.0);  // the median of 7 and 9
  EXPECT_EQ(preload_travel_times(times, nlohmann::json::object(), 20), 0U);
}

}  // namespace
}  // namespace liftd::daemon
