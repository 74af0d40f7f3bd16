// One set of defaults for the USS lift: a default configuration file gives its
// controller exactly the settings a test gets from the default-constructed structs (both read
// the kind's defaults), so a test that builds the controller directly runs the lift the daemon
// runs.
#include <gtest/gtest.h>

#include "uss/host/uss_lift.hpp"

namespace liftd::daemon {
namespace {

TEST(Defaults, ADefaultConfigGivesTheUssControllersOwnDefaults) {
  const uss::UssControllerConfig daemon = uss_controller_config(config::Config{});
  const uss::UssControllerConfig direct{};
  const uss::LiftTravelConfig& a = daemon.travel;
  const uss::LiftTravelConfig& b = direct.travel;
  for (std::size_t i = 0; i < uss::kSpeedCount; ++i) {
    const auto name = uss::to_string(static_cast<uss::SpeedName>(i));
    EXPECT_DOUBLE_EQ(a.speed_percent[i], b.speed_percent[i]) << name;
    EXPECT_EQ(a.slowdown_mm[i], b.slowdown_mm[i]) << name;
  }
  EXPECT_EQ(a.reference, b.reference);
  EXPECT_EQ(a.stop_lead_mm, b.stop_lead_mm);
  EXPECT_EQ(a.level_tolerance_mm, b.level_tolerance_mm);
  EXPECT_EQ(a.max_travel_ms, b.max_travel_ms);
  EXPECT_EQ(a.relevel_doors_open, b.relevel_doors_open);
  EXPECT_EQ(a.profile.switch_on_timeout_ms, b.profile.switch_on_timeout_ms);
  EXPECT_EQ(daemon.drive_address, direct.drive_address);
  EXPECT_EQ(daemon.drive_pzd_words, direct.drive_pzd_words);
  EXPECT_EQ(daemon.normalisation.raw_full_scale, direct.normalisation.raw_full_scale);
  EXPECT_DOUBLE_EQ(daemon.normalisation.full_scale, direct.normalisation.full_scale);
  EXPECT_EQ(daemon.link_fault_replies, direct.link_fault_replies);
  EXPECT_EQ(daemon.auto_relevel, direct.auto_relevel);
  EXPECT_EQ(daemon.relevel_threshold_mm, direct.relevel_threshold_mm);
  EXPECT_EQ(daemon.lift.level_tolerance_mm, direct.lift.level_tolerance_mm);
  EXPECT_EQ(daemon.inputs_timeout, direct.inputs_timeout);
  EXPECT_EQ(daemon.inspection_hold, direct.inspection_hold);
  const uss::MasterConfig master = uss_master_config(config::Config{});
  const uss::MasterConfig master_direct{};
  EXPECT_EQ(master.baud, master_direct.baud);
  EXPECT_EQ(master.reply_delay, master_direct.reply_delay);
  EXPECT_EQ(master.pkw_repeat_limit, master_direct.pkw_repeat_limit);
  EXPECT_EQ(master.mirror_at_start, master_direct.mirror_at_start);
  EXPECT_EQ(master.cycle_time, master_direct.cycle_time);
}

}  // namespace
}  // namespace liftd::daemon
