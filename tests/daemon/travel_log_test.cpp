// The travel log: samples make travels by run, an end event gives the cause, the last 16 are
// kept, a long travel keeps every second sample, and `travels` shows them with their bits named.
#include <gtest/gtest.h>

#include <chrono>

#include "host/travel_log.hpp"

namespace liftd::daemon {
namespace {

using namespace std::chrono_literals;

TravelBitNames names() {
  return {{"B0_enable", "B1_travel"}, {"S0_ready", "", "S2_warning"}};
}

lift::TravelSample sample(std::uint32_t run, MonoTime at, std::int64_t position,
                          bool last = false) {
  lift::TravelSample s;
  s.at = at;
  s.run = run;
  s.kind = "distance";
  s.position_known = true;
  s.position_mm = position;
  s.speed_known = true;
  s.speed_mm_s = 1000;
  s.command_bits = 0x03;
  s.status_bits = 0x07;
  s.target_floor = 1;
  s.last = last;
  return s;
}

std::chrono::system_clock::time_point wall(MonoTime at) {
  return std::chrono::system_clock::time_point(
      std::chrono::duration_cast<std::chrono::system_clock::duration>(at));
}

TEST(TravelLog, ATravelWithItsSamplesCauseAndTarget) {
  TravelLog log(names(), {0, 3000});
  for (int i = 0; i < 5; ++i) log.add(sample(1, 1s + i * 15ms, i * 100, i == 4));
  log.end(1s + 60ms, "arrived");
  const nlohmann::json r = log.to_json(5, wall);
  ASSERT_EQ(r["travels"].size(), 1U);
  const nlohmann::json& t = r["travels"][0];
  EXPECT_EQ(t["id"], 1);
  EXPECT_EQ(t["kind"], "distance");
  EXPECT_EQ(t["cause"], "arrived");
  EXPECT_EQ(t["target_floor"], 1);
  EXPECT_EQ(t["target_mm"], 3000);
  EXPECT_EQ(t["duration_ms"], 60);
  EXPECT_EQ(t["start"], "1970-01-01T00:00:01.000Z");
  EXPECT_EQ(t["end"], "1970-01-01T00:00:01.060Z");
  EXPECT_EQ(t["command_bits"], (nlohmann::json{"B0_enable", "B1_travel"}));
  EXPECT_EQ(t["status_bits"], (nlohmann::json{"S0_ready", "S2_warning"}));
  ASSERT_EQ(t["samples"].size(), 5U);
  EXPECT_EQ(t["samples"][1], (nlohmann::json{{"t_ms", 15},
                                             {"position_mm", 100},
                                             {"speed_mm_s", 1000},
                                             {"remaining_mm", nullptr},
                                             {"command", {"B0_enable", "B1_travel"}},
                                             {"status", {"S0_ready", "S2_warning"}}}));
  EXPECT_EQ(r["dropped_samples"], 0);
}

TEST(TravelLog, AnEndToldBeforeTheSamplesArriveStillFindsItsTravel) {
  TravelLog log(names(), {0, 3000});
  log.end(2s, "safety_chain_open");
  log.add(sample(1, 1s, 0));
  log.add(sample(1, 2s, 10, true));
  EXPECT_EQ(log.to_json(5, wall)["travels"][0]["cause"], "safety_chain_open");
}

TEST(TravelLog, ARunningTravelHasNoEndYet) {
  TravelLog log(names(), {0, 3000});
  log.add(sample(1, 1s, 0));
  const nlohmann::json t = log.to_json(5, wall)["travels"][0];
  EXPECT_TRUE(t["end"].is_null());
  EXPECT_TRUE(t["cause"].is_null());
}

TEST(TravelLog, KeepsTheLastSixteenAndReturnsTheLastAskedOldestFirst) {
  TravelLog log(names(), {0, 3000});
  for (std::uint32_t run = 1; run <= 20; ++run) {
    const MonoTime start = run * 10s;
    log.add(sample(run, start, 0));
    log.add(sample(run, start + 1s, 3000, true));
    log.end(start + 1s, "arrived");
  }
  EXPECT_EQ(log.travels().size(), TravelLog::kTravelsKept);
  const nlohmann::json all = log.to_json(16, wall)["travels"];
  ASSERT_EQ(all.size(), 16U);
  EXPECT_EQ(all.front()["id"], 5);
  EXPECT_EQ(all.back()["id"], 20);
  const nlohmann::json three = log.to_json(3, wall)["travels"];
  ASSERT_EQ(three.size(), 3U);
  EXPECT_EQ(three[0]["id"], 18);
  for (const auto& t : all) EXPECT_EQ(t["cause"], "arrived") << t["id"];
}

TEST(TravelLog, ALongTravelKeepsEverySecondSampleOfTheWholeRun) {
  TravelLog log(names(), {0, 3000});
  const std::size_t n = TravelLog::kMaxSamples * 2 + 11;
  for (std::size_t i = 0; i < n; ++i) {
    log.add(sample(1, 1s + static_cast<int>(i) * 15ms, static_cast<std::int64_t>(i), i + 1 == n));
  }
  const RecordedTravel& t = log.travels().back();
  EXPECT_LE(t.samples.size(), TravelLog::kMaxSamples + 1);
  EXPECT_GE(t.samples.size(), TravelLog::kMaxSamples / 2);
  EXPECT_EQ(t.stride, 4U);
  EXPECT_EQ(t.samples.front().position_mm, 0) << "the start is kept";
  EXPECT_EQ(t.samples.back().position_mm, static_cast<std::int64_t>(n - 1)) << "the end is kept";
  for (std::size_t i = 1; i < t.samples.size(); ++i) {
    ASSERT_GT(t.samples[i].at, t.samples[i - 1].at);
  }
  EXPECT_EQ(log.to_json(1, wall)["travels"][0]["stride"], 4);
}

}  // namespace
}  // namespace liftd::daemon
