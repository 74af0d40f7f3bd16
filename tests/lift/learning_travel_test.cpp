// The learning travel's sequence as every drive kind runs it (lift/learning_travel.hpp): the
// legs it asks for, the run-out after the last zone, the record of a learning that ended well,
// and the ends without a record (a stop, a fault, a refused leg up).
#include <gtest/gtest.h>

#include <optional>
#include <vector>

#include "lift/learning_travel.hpp"

namespace liftd::lift {
namespace {

struct Leg {
  std::int64_t target_mm;
  Direction direction;
  bool operator==(const Leg&) const = default;
};

class LearningTravelTest : public ::testing::Test {
 protected:
  LearningTravelTest() {
    const std::vector<std::int64_t> levels = {0, 400, 800};
    floors_.assign(levels);
  }
  bool begin(std::int64_t position_mm) {
    return learning_.begin(7, floors_, position_mm, 5, [this](std::int64_t mm, Direction d) {
      legs_.push_back({mm, d});
      return take_legs_;
    });
  }
  std::optional<Answer> step(bool leg_running, std::optional<Answer> refusal = std::nullopt) {
    return learning_.step(
        leg_running, floors_, [&] { return refusal; },
        [this](std::int64_t mm, Direction d) {
          legs_.push_back({mm, d});
          return take_legs_;
        });
  }
  /// The car crawls up from `from_mm` to `to_mm` in 2 mm steps through zones 100 mm long centred
  /// on `levels`; the run-out's end, once asked for.
  std::optional<std::int64_t> crawl(std::int64_t from_mm, std::int64_t to_mm,
                                    const std::vector<std::int64_t>& levels) {
    std::optional<std::int64_t> end;
    for (std::int64_t at = from_mm; at <= to_mm && !end; at += 2) {
      bool zone = false;
      for (const std::int64_t level : levels) zone = zone || (at >= level - 50 && at <= level + 50);
      learning_.sample(at, zone, Direction::Up, floors_.size(), [&](std::int64_t mm) {
        end = mm;
        return true;
      });
    }
    return end;
  }

  FloorTable floors_;
  LearningTravel learning_;
  std::vector<Leg> legs_;
  bool take_legs_ = true;
};

TEST_F(LearningTravelTest, ApproachesBelowTheBottomThenCrawlsUpAndRecordsEveryZone) {
  ASSERT_TRUE(begin(0));
  EXPECT_EQ(learning_.phase(), LearningTravel::Phase::Down);
  // kLearnApproachMm: half the longest plausible zone (200 mm) plus 100 mm.
  ASSERT_EQ(legs_, (std::vector<Leg>{{-300, Direction::Down}}));
  EXPECT_EQ(step(true), std::nullopt);
  learning_.leg_ended(false, Cause::None);
  EXPECT_EQ(step(false), std::nullopt);
  ASSERT_EQ(legs_.back(), (Leg{1100, Direction::Up}));
  EXPECT_EQ(learning_.phase(), LearningTravel::Phase::Up);
  // The true levels are off the table: -35, 425, 855. The leg ends 20 mm past the last zone.
  const auto end = crawl(-300, 1100, {-35, 425, 855});
  ASSERT_TRUE(end);
  EXPECT_EQ(*end, 908 + kLearnRunOutMm) << "the sample that confirmed the last zone's end";
  learning_.leg_ended(false, Cause::None);
  const auto answer = step(false);
  ASSERT_TRUE(answer);
  EXPECT_EQ(answer->code, ReplyCode::Ok);
  EXPECT_FALSE(learning_.active());
  const LearnRecord& r = learning_.record();
  EXPECT_EQ(r.tag, 7U);
  EXPECT_TRUE(r.judgement.ok());
  ASSERT_EQ(r.zone_count, 3U);
  EXPECT_EQ(r.zones[0].level_mm(), -35);
  EXPECT_EQ(r.zones[1].level_mm(), 425);
  EXPECT_EQ(r.zones[2].level_mm(), 855);
}

TEST_F(LearningTravelTest, ACarAtOrBelowTheApproachGoesUpAtOnce) {
  ASSERT_TRUE(begin(-296));  // within the 5 mm tolerance of -300
  ASSERT_EQ(legs_, (std::vector<Leg>{{1100, Direction::Up}}));
  EXPECT_EQ(learning_.phase(), LearningTravel::Phase::Up);
}

TEST_F(LearningTravelTest, ALegTheDriveDoesNotTakeStartsNothing) {
  take_legs_ = false;
  EXPECT_FALSE(begin(0));
  EXPECT_FALSE(learning_.active());
}

TEST_F(LearningTravelTest, EveryEarlyEndAnswersWithoutARecord) {
  struct Case {
    const char* legend;
    bool stop;           // `stop` during the leg
    bool aborted;        // the leg was aborted ...
    Cause cause;         // ... with this cause
    ReplyCode code;      // the learn command's answer
    const char* detail;  // and its text
  };
  const Case cases[] = {
      {"stop mid-leg", true, true, Cause::StopRequested, ReplyCode::NotReady,
       "learning travel stopped: nothing learned"},
      {"stop, the leg lands", true, false, Cause::None, ReplyCode::NotReady,
       "learning travel stopped: nothing learned"},
      {"safety chain", false, true, Cause::SafetyChainOpen, ReplyCode::Fault, "safety_chain_open"},
      {"abort without cause", false, true, Cause::None, ReplyCode::Fault, "stop_requested"},
  };
  for (const Case& c : cases) {
    learning_ = LearningTravel{};
    ASSERT_TRUE(begin(-300)) << c.legend;
    (void)crawl(-300, 200, {-35, 425, 855});
    if (c.stop) learning_.stop();
    EXPECT_EQ(step(true), std::nullopt) << c.legend << ": the leg still runs";
    learning_.leg_ended(c.aborted, c.cause);
    const auto answer = step(false);
    ASSERT_TRUE(answer) << c.legend;
    EXPECT_EQ(answer->code, c.code) << c.legend;
    EXPECT_EQ(answer->detail, c.detail) << c.legend;
    EXPECT_FALSE(learning_.active());
    EXPECT_EQ(learning_.record().tag, 0U) << c.legend << ": something was recorded";
  }
}

TEST_F(LearningTravelTest, AStopBetweenTheLegsEndsItAtOnce) {
  ASSERT_TRUE(begin(0));
  learning_.stop();
  const auto answer = step(false);
  ASSERT_TRUE(answer);
  EXPECT_EQ(answer->detail, kLearnStopped);
  EXPECT_EQ(legs_.size(), 1U) << "no leg up after the stop";
}

TEST_F(LearningTravelTest, TheLegUpPassesTheGatesOfATravel) {
  ASSERT_TRUE(begin(0));
  learning_.leg_ended(false, Cause::None);
  const auto answer = step(false, Answer{ReplyCode::NotReady, "doors not locked"});
  ASSERT_TRUE(answer);
  EXPECT_EQ(answer->code, ReplyCode::NotReady);
  EXPECT_EQ(answer->detail, "doors not locked");
  EXPECT_EQ(legs_.size(), 1U);
}

TEST_F(LearningTravelTest, AMissingZoneIsRecordedAndJudged) {
  ASSERT_TRUE(begin(-300));
  EXPECT_EQ(crawl(-300, 1100, {-35, 855}), std::nullopt) << "no run-out with a zone missing";
  learning_.leg_ended(false, Cause::None);
  const auto answer = step(false);
  ASSERT_TRUE(answer);
  EXPECT_EQ(answer->code, ReplyCode::Ok);
  EXPECT_EQ(learning_.record().judgement.verdict, LearnVerdict::ZoneCountDiffers);
  EXPECT_EQ(learning_.record().zones_seen, 2U);
}

TEST(LearnLegLimit, CoversASlowRunThroughTheLeg) {
  // 40 ms per mm: 25 mm/s, half the usual crawl or levelling speed of 0.05 m/s.
  EXPECT_EQ(learn_leg_limit_ms(45000, 1000), 85000U);
  EXPECT_EQ(learn_leg_limit_ms(45000, -1000), 85000U);
  // Two legs through the shaft (800 mm) and both approaches (300 mm each): 1400 mm each.
  EXPECT_EQ(learn_longest(45000, 0, 800), std::chrono::milliseconds(2 * (45000 + 1400 * 40)));
}

}  // namespace
}  // namespace liftd::lift
