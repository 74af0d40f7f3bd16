// status car.motion (docs/api.md): the phase read from the running travel's own samples, at
// points of a synthetic run (15 ms samples) whose speed is known at every moment.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <functional>
#include <string>

#include "host/motion.hpp"

namespace liftd::daemon {
namespace {

using namespace std::chrono_literals;

/// A run whose speed at `t` seconds is `speed(t)` mm/s, sampled every 15 ms up to `until_s`
/// (its position in whole millimetres, as an encoder gives it).
RecordedTravel run(const std::function<double(double)>& speed, double until_s) {
  RecordedTravel t;
  t.start = MonoTime{};
  double position_mm = 0.0;
  for (double s = 0.0; s <= until_s + 1e-9; s += 0.015) {
    lift::TravelSample sample;
    sample.at = MonoTime{} + std::chrono::microseconds(static_cast<std::int64_t>(s * 1e6));
    sample.speed_known = true;
    sample.speed_mm_s = static_cast<std::int32_t>(speed(s));
    sample.position_known = true;  // the encoder's whole millimetres
    sample.position_mm = std::llround(position_mm);
    t.samples.push_back(sample);
    position_mm += speed(s) * 0.015;
  }
  return t;
}

// A travel of a traction lift: 1 s still (brake, start), 2 s at 0.5 m/s^2 to 1 m/s, 4 s at
// speed, 1.8 s down to 100 mm/s, 1 s creeping, 0.2 s down to 0, then still.
double traction(double t) {
  if (t < 1.0) return 0.0;
  if (t < 3.0) return 500.0 * (t - 1.0);
  if (t < 7.0) return 1000.0;
  if (t < 8.8) return 1000.0 - 500.0 * (t - 7.0);
  if (t < 9.8) return 100.0;
  if (t < 10.0) return 100.0 - 500.0 * (t - 9.8);
  return 0.0;
}

TEST(MotionPhase, FollowsATravelThroughEachPhase) {
  // Legend: seconds into the run -> phase at that sample.
  const struct {
    double at_s;
    const char* phase;
  } cases[] = {
      {0.5, "starting"},     {1.6, "accelerating"}, {2.9, "accelerating"},
      {4.0, "at_speed"},     {6.9, "at_speed"},     {7.5, "decelerating"},
      {8.5, "decelerating"}, {9.5, "levelling"},    {10.3, "levelling"},
  };
  for (const auto& c : cases) {
    const RecordedTravel t = run(traction, c.at_s);
    EXPECT_EQ(motion_phase(true, &t), c.phase) << c.at_s << " s";
  }
}

TEST(MotionPhase, StandingWithoutATravelAndStartingBeforeTheLogShowsIt) {
  RecordedTravel ended = run(traction, 11.0);
  ended.ended = true;
  EXPECT_EQ(motion_phase(false, &ended), "standing");
  EXPECT_EQ(motion_phase(false, nullptr), "standing");
  EXPECT_EQ(motion_phase(true, nullptr), "starting");
  EXPECT_EQ(motion_phase(true, &ended), "starting") << "the log's newest travel is the last one";
  RecordedTravel blind;  // no position known: the run has not shown motion
  blind.samples.resize(10);
  EXPECT_EQ(motion_phase(true, &blind), "starting");
}

TEST(MotionPhase, AShortTravelGoesFromAcceleratingToDecelerating) {
  // A triangle: 1.2 s up at 0.5 m/s^2, then 1.2 s down; never a steady speed.
  const auto triangle = [](double t) { return t < 1.2 ? 500.0 * t : 600.0 - 500.0 * (t - 1.2); };
  const RecordedTravel up = run(triangle, 0.8);
  EXPECT_EQ(motion_phase(true, &up), "accelerating");
  const RecordedTravel down = run(triangle, 1.9);
  EXPECT_EQ(motion_phase(true, &down), "decelerating");
}

}  // namespace
}  // namespace liftd::daemon
