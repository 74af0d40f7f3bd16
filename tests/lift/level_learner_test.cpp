// The learning travel's recorder: zone edges, levels and zone lengths from per-cycle samples,
// a one-cycle bounce at an edge, and the judgement (zone count, implausible lengths).
#include <gtest/gtest.h>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "lift/level_learner.hpp"

namespace liftd::lift {
namespace {

struct Zone {
  std::int64_t lo = 0;
  std::int64_t hi = 0;
};

struct Ride {
  std::int64_t from_mm = -300;
  std::int64_t to_mm = 1300;
  std::int64_t step_mm = 3;  // per cycle: 0.2 m/s in a 15 ms cycle
  std::vector<Zone> zones;
  std::optional<std::int64_t> flip_at_mm;  // the input inverted for one sample here
};

LevelLearner ride(const Ride& r) {
  LevelLearner learner;
  bool flipped = false;
  for (std::int64_t p = r.from_mm; p <= r.to_mm; p += r.step_mm) {
    bool zone = false;
    for (const Zone& z : r.zones) zone = zone || (p >= z.lo && p <= z.hi);
    if (r.flip_at_mm && !flipped && p >= *r.flip_at_mm) {
      zone = !zone;
      flipped = true;
    }
    learner.sample(p, zone, Direction::Up);
  }
  return learner;
}

// Zones 100 mm long centred on 0, 500 and 1000 mm.
const std::vector<Zone> kThreeZones = {{-50, 50}, {450, 550}, {950, 1050}};

TEST(LevelLearner, LevelsAreTheZonesMiddlesWithinHalfAStepAtEverySpeed) {
  for (std::int64_t step : {1, 2, 3, 4}) {
    SCOPED_TRACE("step " + std::to_string(step));
    Ride r;
    r.step_mm = step;
    r.zones = kThreeZones;
    const LevelLearner learner = ride(r);
    ASSERT_TRUE(learner.judge(3).ok());
    ASSERT_EQ(learner.zone_count(), 3U);
    const std::int64_t expected[] = {0, 500, 1000};
    for (std::size_t i = 0; i < 3; ++i) {
      EXPECT_NEAR(static_cast<double>(learner.zone(i).level_mm()), static_cast<double>(expected[i]),
                  2.0);
      EXPECT_NEAR(static_cast<double>(learner.zone(i).length_mm()), 100.0,
                  static_cast<double>(step));
    }
  }
}

TEST(LevelLearner, JudgesEachRecord) {
  struct Case {
    std::string name;
    Ride ride;
    std::size_t floors;
    LearnVerdict verdict;
    std::size_t zones;
    std::size_t zone;  // the offending zone, where it applies
  };
  Ride bounce_before{};
  bounce_before.zones = kThreeZones;
  bounce_before.flip_at_mm = 440;  // one sample "in zone" 10 mm before the second zone
  Ride bounce_inside{};
  bounce_inside.zones = kThreeZones;
  bounce_inside.flip_at_mm = 500;  // one sample "out of zone" in the middle of the second
  Ride missing{};
  missing.zones = {{-50, 50}, {950, 1050}};
  Ride short_zone{};
  short_zone.zones = {{-50, 50}, {490, 510}, {950, 1050}};
  Ride long_zone{};
  long_zone.zones = {{-50, 50}, {250, 750}, {950, 1050}};
  Ride began_inside{};
  began_inside.from_mm = 0;
  began_inside.zones = kThreeZones;
  Ride ended_inside{};
  ended_inside.to_mm = 1000;
  ended_inside.zones = kThreeZones;
  Ride extra{};
  extra.zones = {{-50, 50}, {450, 550}, {700, 800}, {950, 1050}};
  const std::vector<Case> cases = {
      {"bounce before a zone", bounce_before, 3, LearnVerdict::Ok, 3, 0},
      {"bounce inside a zone", bounce_inside, 3, LearnVerdict::Ok, 3, 0},
      {"missing zone", missing, 3, LearnVerdict::ZoneCountDiffers, 2, 0},
      {"extra zone", extra, 3, LearnVerdict::ZoneCountDiffers, 4, 0},
      {"zone too short", short_zone, 3, LearnVerdict::ZoneTooShort, 3, 1},
      {"zone too long", long_zone, 3, LearnVerdict::ZoneTooLong, 3, 1},
      {"began inside a zone", began_inside, 3, LearnVerdict::BeganInZone, 2, 0},
      {"ended inside a zone", ended_inside, 3, LearnVerdict::EndedInZone, 2, 2},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    const LevelLearner learner = ride(c.ride);
    const LearnJudgement j = learner.judge(c.floors);
    EXPECT_EQ(j.verdict, c.verdict) << to_string(j.verdict);
    EXPECT_EQ(learner.zone_count(), c.zones);
    if (!j.ok()) {
      EXPECT_EQ(j.zone, c.zone);
    }
  }
}

TEST(LevelLearner, ABounceLeavesTheLevelsWhereTheyWere) {
  Ride clean{};
  clean.zones = kThreeZones;
  Ride bounced = clean;
  bounced.flip_at_mm = 500;
  const LevelLearner a = ride(clean);
  const LevelLearner b = ride(bounced);
  ASSERT_EQ(a.zone_count(), b.zone_count());
  for (std::size_t i = 0; i < a.zone_count(); ++i) EXPECT_EQ(a.zone(i), b.zone(i));
}

TEST(LevelLearner, SamplesTravellingDownRecordNothing) {
  LevelLearner learner;
  for (std::int64_t p = 1300; p >= -300; p -= 3) {
    learner.sample(p, p >= 450 && p <= 550, Direction::Down);
  }
  EXPECT_EQ(learner.zones_seen(), 0U);
  EXPECT_FALSE(learner.in_zone());
  learner.reset();
  EXPECT_EQ(learner.judge(1).verdict, LearnVerdict::ZoneCountDiffers);
}

TEST(LevelLearner, VerdictNames) {
  EXPECT_EQ(to_string(LearnVerdict::Ok), "ok");
  EXPECT_EQ(to_string(LearnVerdict::ZoneCountDiffers), "zone_count_differs");
  EXPECT_EQ(to_string(LearnVerdict::ZoneTooShort), "zone_too_short");
  EXPECT_EQ(to_string(LearnVerdict::ZoneTooLong), "zone_too_long");
  EXPECT_EQ(to_string(LearnVerdict::BeganInZone), "began_in_zone");
  EXPECT_EQ(to_string(LearnVerdict::EndedInZone), "ended_in_zone");
}

}  // namespace
}  // namespace liftd::lift
