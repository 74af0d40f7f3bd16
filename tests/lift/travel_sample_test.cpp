// The travel sampler: a sample per step while a run is in progress and one at the first step at
// rest, a new run number per run, the speed from the position over at least 45 ms.
#include <gtest/gtest.h>

#include <chrono>
#include <vector>

#include "lift/travel_sample.hpp"

namespace liftd::lift {
namespace {

using namespace std::chrono_literals;

constexpr MonoTime kCycle = 15ms;

TEST(TravelSampler, SamplesEachStepOfARunAndTheFirstStepAtRestOnly) {
  TravelSampler sampler;
  DriveBits bits;
  bits.command = 0x03;
  bits.status = 0x41;
  std::vector<TravelSample> samples;
  MonoTime now{};
  const auto step = [&](bool running, std::int64_t position) {
    now += kCycle;
    if (const auto s = sampler.step(now, running, "distance", position, 2, bits)) {
      samples.push_back(*s);
    }
  };
  step(false, 0);
  step(false, 0);
  EXPECT_TRUE(samples.empty()) << "no sample at rest";
  for (int i = 0; i < 10; ++i) step(true, i * 15);
  step(false, 150);
  step(false, 150);
  ASSERT_EQ(samples.size(), 11U);
  for (std::size_t i = 0; i < samples.size(); ++i) {
    EXPECT_EQ(samples[i].run, 1U);
    EXPECT_EQ(samples[i].kind, "distance");
    EXPECT_EQ(samples[i].target_floor, 2);
    EXPECT_EQ(samples[i].command_bits, 0x03U);
    EXPECT_EQ(samples[i].status_bits, 0x41U);
    EXPECT_FALSE(samples[i].remaining_known);
    EXPECT_EQ(samples[i].last, i == 10) << i;
    if (i > 0) {
      EXPECT_EQ(samples[i].at - samples[i - 1].at, kCycle);
    }
  }
  // 15 mm per 15 ms cycle.
  EXPECT_EQ(samples[5].speed_mm_s, 1000);
  EXPECT_TRUE(samples[5].speed_known);
  EXPECT_EQ(samples[10].position_mm, 150);

  step(true, 150);
  ASSERT_EQ(samples.size(), 12U);
  EXPECT_EQ(samples.back().run, 2U) << "a new run";
  EXPECT_FALSE(samples.back().last);
}

TEST(TravelSampler, SpeedOverAtLeastTheWindowAndDownIsNegative) {
  TravelSampler sampler;
  MonoTime now{};
  std::optional<TravelSample> s;
  for (int i = 0; i < 20; ++i) {
    now += 5ms;  // steps closer than a DCP cycle (a CAN card's frames)
    s = sampler.step(now, true, "hydraulic", 10'000 - i * 2, std::nullopt, {});
  }
  ASSERT_TRUE(s && s->speed_known);
  EXPECT_EQ(s->speed_mm_s, -400);  // 2 mm per 5 ms down
  EXPECT_EQ(s->target_floor, -1);
}

TEST(TravelSampler, NoPositionNoSpeedAndTheRemainingDistanceAsGiven) {
  TravelSampler sampler;
  DriveBits bits;
  bits.remaining_mm = 1234;
  const auto s = sampler.step(15ms, true, "distance", std::nullopt, 1, bits);
  ASSERT_TRUE(s);
  EXPECT_FALSE(s->position_known);
  EXPECT_FALSE(s->speed_known);
  EXPECT_TRUE(s->remaining_known);
  EXPECT_EQ(s->remaining_mm, 1234);
}

}  // namespace
}  // namespace liftd::lift
