// Car profile: the I7 examples of DCP 11.1.2.1 from the simulator's own profile, exact landing,
// limits respected.
#include "sim/profile.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "sim/drive_sim.hpp"

namespace liftd::sim {
namespace {

TEST(SimProfile, I7ShortTravelExampleFromSpec) {
  // DCP 11.1.2.1 example 1: 300 cm at V4 -> short travel, Sg 300 cm, Sv 143 cm.
  const DriveSim sim;
  const auto p = sim.start_parameters(300, true);
  EXPECT_EQ(p.travel_type, 's');
  EXPECT_EQ(p.total_cm, 300U);
  EXPECT_EQ(p.decel_cm, 143U);
}

TEST(SimProfile, I7LongTravelExampleFromSpec) {
  // DCP 11.1.2.1 example 2: 1000 cm at V4 -> long travel, Sg 520 cm, Sv 250 cm.
  const DriveSim sim;
  const auto p = sim.start_parameters(1000, true);
  EXPECT_EQ(p.travel_type, 'l');
  EXPECT_EQ(p.total_cm, 520U);
  EXPECT_EQ(p.decel_cm, 250U);
}

TEST(SimProfile, I7AtV3IsSlowerAndShorter) {
  const DriveSim sim;
  const auto p = sim.start_parameters(1000, false);
  EXPECT_EQ(p.travel_type, 'l');
  EXPECT_LT(p.total_cm, 520U);
  EXPECT_LT(p.decel_cm, 250U);
}

TEST(SimProfile, RampDistanceMatchesIntegratedPlan) {
  const RampLimits accel{0.54, 1.3};
  const RampLimits decel{0.56, 2.1};
  MotionPlan plan;
  plan.plan_speed(0.0, MotionState{}, 1.6, accel, decel);
  EXPECT_NEAR(plan.final_position_m(), ramp_distance_m(0.0, 1.6, accel), 1e-9);
  // Triangular case: a small speed change never reaches full acceleration.
  plan.plan_speed(0.0, MotionState{}, 0.05, accel, decel);
  EXPECT_NEAR(plan.final_position_m(), ramp_distance_m(0.0, 0.05, accel), 1e-9);
}

struct Landing {
  double distance_m;  // travel length
  double vmax_mps;    // speed limit
  const char* legend;
};

TEST(SimProfile, ArrivalLandsExactlyAndRespectsLimits) {
  const RampLimits accel{0.54, 1.3};
  const RampLimits decel{0.56, 2.1};
  const Landing cases[] = {
      {0.010, 0.05, "1 cm at crawl"},
      {0.150, 0.05, "15 cm, crawl-limited start"},
      {1.000, 1.6, "1 m: short travel, V4 never reached"},
      {3.000, 1.6, "one floor: the spec's short example"},
      {10.00, 1.6, "the spec's long example"},
      {60.00, 1.6, "long shaft"},
  };
  for (const auto& c : cases) {
    MotionPlan plan;
    ASSERT_TRUE(plan.plan_arrival(0.0, MotionState{}, c.distance_m, c.vmax_mps, 0.0, accel, decel))
        << c.legend;
    // Landing error well under 1 mm (the model is analytic: under a micrometre).
    EXPECT_NEAR(plan.final_position_m(), c.distance_m, 1e-6) << c.legend;
    EXPECT_EQ(plan.final_speed_mps(), 0.0) << c.legend;
    double prev_s = 0.0;
    for (double t = 0.0; t <= plan.settle_time_s() + 0.1; t += 0.001) {
      const MotionState st = plan.at(t);
      EXPECT_LE(st.v_mps, c.vmax_mps + 1e-9) << c.legend << " t=" << t;
      EXPECT_GE(st.v_mps, -1e-9) << c.legend << " t=" << t;
      EXPECT_LE(st.a_mps2, accel.accel_mps2 + 1e-9) << c.legend;
      EXPECT_GE(st.a_mps2, -decel.accel_mps2 - 1e-9) << c.legend;
      EXPECT_GE(st.s_m, prev_s - 1e-12) << c.legend << " never reverses";
      EXPECT_LE(st.s_m, c.distance_m + 1e-6) << c.legend << " never overshoots";
      prev_s = st.s_m;
    }
  }
}

TEST(SimProfile, ExtensionDuringAccelerationStillLandsExactly) {
  const RampLimits accel{0.54, 1.3};
  const RampLimits decel{0.56, 2.1};
  MotionPlan plan;
  ASSERT_TRUE(plan.plan_arrival(0.0, MotionState{}, 3.0, 1.6, 0.0, accel, decel));
  const MotionState mid = plan.at(1.0);  // still accelerating
  ASSERT_GT(mid.a_mps2, 0.0);
  ASSERT_TRUE(plan.plan_arrival(1.0, mid, 9.0, 1.6, 0.0, accel, decel));
  EXPECT_NEAR(plan.final_position_m(), 9.0, 1e-6);
  EXPECT_NEAR(plan.at(1.0).s_m, mid.s_m, 1e-12) << "continuous at the replan";
}

TEST(SimProfile, TooCloseTargetIsReportedAndRampsDown) {
  const RampLimits accel{0.54, 1.3};
  const RampLimits decel{0.56, 2.1};
  MotionPlan plan;
  const MotionState fast{5.0, 1.6, 0.0};
  EXPECT_FALSE(plan.plan_arrival(0.0, fast, 5.5, 1.6, 0.0, accel, decel));
  EXPECT_EQ(plan.final_speed_mps(), 0.0);
  EXPECT_NEAR(plan.final_position_m(), 5.0 + ramp_distance_m(1.6, 0.0, decel), 1e-9);
}

TEST(SimProfile, PeakSpeedOfShortTravel) {
  const RampLimits accel{0.54, 1.3};
  const RampLimits decel{0.56, 2.1};
  const double v = peak_speed_mps(3.0, 1.6, accel, decel);
  EXPECT_LT(v, 1.6);
  EXPECT_NEAR(ramp_distance_m(0.0, v, accel) + ramp_distance_m(v, 0.0, decel), 3.0, 1e-9);
  EXPECT_EQ(peak_speed_mps(10.0, 1.6, accel, decel), 1.6);
}

}  // namespace
}  // namespace liftd::sim
