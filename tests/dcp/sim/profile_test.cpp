// Car profile: the I7 examples of DCP 11.1.2.1 from the simulator's own profile, exact landing,
// limits respected.
#include "dcp/sim/profile.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "dcp/sim/drive_sim.hpp"

namespace liftd::dcp::sim {
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

// ---- fixed-distance arrival (DCP3 SVx, DCP 10.1.2) ----

struct FixedCase {
  const char* legend;
  MotionState state;  // when B1 drops (s = 0)
  double target_m;    // SVx
  bool harder;        // the normal ramps cannot make it
};

TEST(SimProfile, FixedArrivalMeetsTheDistanceWithinTheHardestLimits) {
  const RampLimits accel{0.54, 1.3};
  const RampLimits decel{0.56, 2.1};
  const RampLimits hardest{1.2, 4.0};  // the simulator's fast-stop ramp (DCP 13)
  const double vmax = 1.6;
  const double v0 = 0.05;
  const FixedCase cases[] = {
      {"0.6 m/s still speeding up, 2.55 m: accelerates on", {0.0, 0.6, 0.54}, 2.55, false},
      {"1.4 m/s at full acceleration, 2.55 m", {0.0, 1.4, 0.54}, 2.55, true},
      {"1.57 m/s rounding off, 2.55 m", {0.0, 1.57, 0.2}, 2.55, true},
      {"cruising at V4, 2.55 m: normal ramp and a short cruise", {0.0, 1.6, 0.0}, 2.55, false},
      {"cruising at V4, 2.2 m: shorter than the normal ramp", {0.0, 1.6, 0.0}, 2.2, true},
      {"braking already (a speed change down), 1.6 m", {0.0, 1.2, -0.3}, 1.6, false},
  };
  for (const auto& c : cases) {
    MotionPlan plan;
    const auto r =
        plan.plan_fixed_arrival(0.0, c.state, c.target_m, vmax, v0, accel, decel, hardest);
    ASSERT_TRUE(r.fits) << c.legend;
    EXPECT_EQ(r.harder > 0.0, c.harder) << c.legend << " harder=" << r.harder;
    EXPECT_LE(r.harder, 1.0) << c.legend;
    EXPECT_NEAR(plan.final_position_m(), c.target_m, 1e-6) << c.legend;
    EXPECT_NEAR(plan.final_speed_mps(), v0, 1e-9) << c.legend;
    EXPECT_NEAR(plan.at(0.0).v_mps, c.state.v_mps, 1e-12) << c.legend << " continuous";
    EXPECT_NEAR(plan.at(0.0).a_mps2, c.state.a_mps2, 1e-12) << c.legend << " continuous";
    for (const Segment& seg : plan) {
      EXPECT_LE(std::fabs(seg.jerk_mps3), hardest.jerk_mps3 + 1e-9) << c.legend;
      if (!c.harder) {
        EXPECT_LE(std::fabs(seg.jerk_mps3), decel.jerk_mps3 + 1e-9) << c.legend;
      }
    }
    for (double t = 0.0; t <= plan.settle_time_s() + 0.1; t += 0.001) {
      const MotionState st = plan.at(t);
      EXPECT_LE(st.v_mps, vmax + 1e-9) << c.legend << " t=" << t;
      EXPECT_GE(st.v_mps, v0 - 1e-9) << c.legend << " t=" << t;
      EXPECT_LE(st.a_mps2, std::max(accel.accel_mps2, c.state.a_mps2) + 1e-9) << c.legend;
      const double brake = c.harder ? hardest.accel_mps2 : decel.accel_mps2;
      EXPECT_GE(st.a_mps2, -brake - 1e-9) << c.legend << " t=" << t;
      if (t <= plan.settle_time_s()) {
        EXPECT_LE(st.s_m, c.target_m + 1e-6) << c.legend << " crawl not before SVx, t=" << t;
      }
    }
  }
}

TEST(SimProfile, FixedArrivalBrakesNoHarderThanNeeded) {
  // The share found is the least that fits: a little less leaves the normal arrival short.
  const RampLimits accel{0.54, 1.3};
  const RampLimits decel{0.56, 2.1};
  const RampLimits hardest{1.2, 4.0};
  const MotionState st{0.0, 1.4, 0.54};
  MotionPlan plan;
  const auto r = plan.plan_fixed_arrival(0.0, st, 2.55, 1.6, 0.05, accel, decel, hardest);
  ASSERT_TRUE(r.fits);
  ASSERT_GT(r.harder, 0.01);
  const double k = r.harder - 0.01;
  const RampLimits accel_k{accel.accel_mps2, accel.jerk_mps3 + k * (hardest.jerk_mps3 - 1.3)};
  const RampLimits decel_k{decel.accel_mps2 + k * (hardest.accel_mps2 - decel.accel_mps2),
                           decel.jerk_mps3 + k * (hardest.jerk_mps3 - decel.jerk_mps3)};
  MotionPlan softer;
  EXPECT_FALSE(softer.plan_arrival(0.0, st, 2.55, 1.6, 0.05, accel_k, decel_k));
}

TEST(SimProfile, FixedArrivalBeyondTheHardestRampIsReported) {
  const RampLimits accel{0.54, 1.3};
  const RampLimits decel{0.56, 2.1};
  const RampLimits hardest{1.2, 4.0};
  MotionPlan plan;
  const auto r = plan.plan_fixed_arrival(0.0, MotionState{0.0, 1.6, 0.0}, 0.8, 1.6, 0.05, accel,
                                         decel, hardest);
  EXPECT_FALSE(r.fits);
  EXPECT_EQ(r.harder, 1.0);
  // Straight onto the hardest ramp: 1313 mm from 1.6 to 0.05 m/s, 513 mm past the target.
  EXPECT_NEAR(plan.final_position_m(), ramp_distance_m(1.6, 0.05, hardest), 1e-9);
  EXPECT_NEAR(r.overshoot_m, ramp_distance_m(1.6, 0.05, hardest) - 0.8, 1e-9);
  EXPECT_NEAR(plan.final_speed_mps(), 0.05, 1e-12);
}

}  // namespace
}  // namespace liftd::dcp::sim
