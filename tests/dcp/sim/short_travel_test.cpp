// DCP3 time-optimised short travel (DCP 10.1.2 / 10.2.2): when B1 drops before Vx was reached,
// the drive still covers the same fixed distance SVx to crawl V0. Each case runs B1+B2 until
// the car passed a drop point, clears B1 and samples the car every millisecond until it crawls.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "dcp/sim/profile.hpp"
#include "sim_harness.hpp"

namespace liftd::dcp::sim {
namespace {

using namespace testing;

constexpr std::uint16_t kV4 = 0x0080;  // DCP 3.5.2: G7, fast
constexpr std::uint16_t kV3 = 0x0040;  // DCP 3.5.2: G6, intermediate 1
// Fixed deceleration distances configured for these tests (DCP 10.1.1 / 10.2.1). The default
// car needs 2503 mm from V4 = 1.6 m/s and 1030 mm from V3 = 1.0 m/s to V0 on its normal ramp.
constexpr std::uint32_t kSv4Mm = 2550;
constexpr std::uint32_t kSv3Mm = 1100;
// The crawl point is found to 1 ms of sampling, 0.05 mm at V0; the plan itself lands to 1 nm.
constexpr double kCrawlPointMm = 1.0;
// Deceleration measured as a 1 ms difference of speeds: the jerk (at most 4 m/s^3) blurs it by
// 2 mm/s^2; 10 mm/s^2 is the margin.
constexpr double kDecelMarginMps2 = 0.01;

struct Outcome {
  double drop_speed_mps = 0.0;   ///< speed when the B1-off frame arrived
  double crawl_at_mm = -1.0;     ///< distance from the drop to where the speed first is V0
  double peak_mps = 0.0;         ///< highest speed after the drop
  double max_decel_mps2 = 0.0;   ///< hardest deceleration after the drop
  double crawl_speed_mps = 0.0;  ///< speed 20 cycles after the crawl point
};

/// DCP3 travel at `speed` (B1+B2) until the car passed `drop_mm`, then B2 only (DCP 10.1.1).
Outcome short_travel(const DriveConfig& cfg, std::uint16_t speed, double drop_mm) {
  Harness m(cfg);
  m.init();
  m.cycle(cmd::kSpeed, speed);
  for (int i = 0; i < 2000 && m.sim.position_mm() < drop_mm; ++i) m.cycle(cmd::kTravel);
  Outcome out;
  m.sim.advance(m.now + 15ms);  // the car where the B1-off frame finds it
  const double off_at_mm = m.sim.position_mm();
  double prev_mps = m.sim.velocity_mps();
  out.drop_speed_mps = prev_mps;
  m.cycle(cmd::kDecel);
  for (int cycle = 0; cycle < 1000; ++cycle) {
    for (int ms = 1; ms <= 15; ++ms) {
      m.sim.advance(m.now + std::chrono::milliseconds(ms));
      const double v = m.sim.velocity_mps();
      out.peak_mps = std::max(out.peak_mps, v);
      out.max_decel_mps2 = std::max(out.max_decel_mps2, (prev_mps - v) / 0.001);
      if (out.crawl_at_mm < 0.0 && v <= cfg.speeds.v0_mps + 1e-9) {
        out.crawl_at_mm = m.sim.position_mm() - off_at_mm;
      }
      prev_mps = v;
    }
    m.cycle(cmd::kDecel);
    if (out.crawl_at_mm >= 0.0) break;
  }
  m.repeat(cmd::kDecel, 20);  // B2 still on: the car crawls
  out.crawl_speed_mps = m.sim.velocity_mps();
  return out;
}

DriveConfig dcp3_config() {
  DriveConfig cfg;
  cfg.protocol = dcp::Protocol::Dcp3;
  cfg.dcp3_decel_mm[7] = kSv4Mm;  // index = speed bit G7
  cfg.dcp3_decel_mm[6] = kSv3Mm;  // G6
  return cfg;
}

struct DropCase {
  const char* legend;
  std::uint16_t speed;
  double vx_mps;
  double drop_mm;  ///< B1 cleared once the car passed this point
  double sv_mm;    ///< the configured SVx
  bool harder;     ///< the normal ramp cannot make it: the car must brake harder
};

class Dcp3ShortTravel : public ::testing::TestWithParam<DropCase> {};

TEST_P(Dcp3ShortTravel, ReachesCrawlExactlyAfterSvx) {
  const DropCase c = GetParam();
  const DriveConfig cfg = dcp3_config();
  const Outcome o = short_travel(cfg, c.speed, c.drop_mm);
  SCOPED_TRACE(::testing::Message()
               << c.legend << ": B1 off at " << o.drop_speed_mps << " m/s, crawl after "
               << o.crawl_at_mm << " mm, peak " << o.peak_mps << " m/s, hardest deceleration "
               << o.max_decel_mps2 << " m/s^2");
  ASSERT_GE(o.crawl_at_mm, 0.0) << c.legend;
  EXPECT_NEAR(o.crawl_at_mm, c.sv_mm, kCrawlPointMm) << c.legend;
  // Never faster than the selected speed; crawl kept while B2 is on (DCP 10.1.1 step 4).
  EXPECT_LE(o.peak_mps, c.vx_mps + 1e-9) << c.legend;
  EXPECT_NEAR(o.crawl_speed_mps, cfg.speeds.v0_mps, 1e-9) << c.legend;
  // The normal deceleration ramp unless it cannot make SVx; never beyond the fast-stop ramp.
  const double limit_mps2 = c.harder ? cfg.fast_stop.accel_mps2 : cfg.decel.accel_mps2;
  EXPECT_LE(o.max_decel_mps2, limit_mps2 + kDecelMarginMps2) << c.legend;
  if (c.harder) {
    EXPECT_GT(o.max_decel_mps2, cfg.decel.accel_mps2 + kDecelMarginMps2) << c.legend;
  }
}

// Drop points in mm travelled from standstill. V4 = 1.6 m/s is reached after 2.70 m, V3 =
// 1.0 m/s after 1.13 m (accel 0.54 m/s^2, jerk 1.3 m/s^3).
INSTANTIATE_TEST_SUITE_P(
    Table, Dcp3ShortTravel,
    ::testing::Values(
        DropCase{"V4, 300 mm: slow, SV4 long: accelerates on, then brakes", kV4, 1.6, 300.0, kSv4Mm,
                 false},
        DropCase{"V4, 1000 mm: mid-ramp, keeps accelerating a little", kV4, 1.6, 1000.0, kSv4Mm,
                 false},
        DropCase{"V4, 1800 mm: full acceleration, harder braking", kV4, 1.6, 1800.0, kSv4Mm, true},
        DropCase{"V4, 2346 mm (5000 mm hop): rounding off, harder braking", kV4, 1.6, 2346.0,
                 kSv4Mm, true},
        DropCase{"V4, 2550 mm: last of the rounding off, harder braking", kV4, 1.6, 2550.0, kSv4Mm,
                 true},
        DropCase{"V4, 2650 mm: V4 all but reached: the normal ramp fits", kV4, 1.6, 2650.0, kSv4Mm,
                 false},
        DropCase{"V4, 4000 mm: long travel, cruising at V4: normal ramp", kV4, 1.6, 4000.0, kSv4Mm,
                 false},
        DropCase{"V3, 200 mm: slow, SV3 long: accelerates on, then brakes", kV3, 1.0, 200.0, kSv3Mm,
                 false},
        DropCase{"V3, 600 mm: full acceleration, harder braking", kV3, 1.0, 600.0, kSv3Mm, true},
        DropCase{"V3, 819 mm (2000 mm hop): rounding off, harder braking", kV3, 1.0, 819.0, kSv3Mm,
                 true},
        DropCase{"V3, 2000 mm: long travel, cruising at V3: normal ramp", kV3, 1.0, 2000.0, kSv3Mm,
                 false}),
    [](const auto& p) { return "Case" + std::to_string(p.index); });

TEST(Dcp3ShortTravelLimits, SvxShorterThanTheNormalRampBrakesHarderAtCruise) {
  // A configured SV4 of 2200 mm is 303 mm short of the normal ramp from V4: the drive brakes
  // harder, within the fast-stop ramp (1.2 m/s^2), and still crawls exactly after SV4.
  DriveConfig cfg = dcp3_config();
  cfg.dcp3_decel_mm[7] = 2200;
  const Outcome o = short_travel(cfg, kV4, 4000.0);
  EXPECT_NEAR(o.drop_speed_mps, 1.6, 1e-9);
  EXPECT_NEAR(o.crawl_at_mm, 2200.0, kCrawlPointMm);
  EXPECT_GT(o.max_decel_mps2, cfg.decel.accel_mps2 + kDecelMarginMps2);
  EXPECT_LE(o.max_decel_mps2, cfg.fast_stop.accel_mps2 + kDecelMarginMps2);
}

TEST(Dcp3ShortTravelLimits, SvxBeyondTheFastStopRampOvershootsOnThatRamp) {
  // 800 mm from V4 cannot be met even on the fast-stop ramp (1.2 m/s^2, 4 m/s^3: 1313 mm from
  // 1.6 to 0.05 m/s). The drive brakes on that ramp at once and crawls past SV4; the lift
  // controller's by-position stop then sees the car late (the installation is misconfigured).
  DriveConfig cfg = dcp3_config();
  cfg.dcp3_decel_mm[7] = 800;
  const Outcome o = short_travel(cfg, kV4, 4000.0);
  const double fast_stop_m = ramp_distance_m(1.6, cfg.speeds.v0_mps, cfg.fast_stop);
  EXPECT_NEAR(fast_stop_m, 1.313, 0.001);  // (1.55 / 1.2 + 1.2 / 4) s * 0.825 m/s
  EXPECT_NEAR(o.crawl_at_mm, fast_stop_m * 1000.0, kCrawlPointMm);
  EXPECT_NEAR(o.max_decel_mps2, cfg.fast_stop.accel_mps2, kDecelMarginMps2);
  EXPECT_NEAR(o.crawl_speed_mps, cfg.speeds.v0_mps, 1e-9);
}

}  // namespace
}  // namespace liftd::dcp::sim
