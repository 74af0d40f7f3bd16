// One set of defaults: a default configuration file gives the controllers exactly the settings a
// test gets from their default-constructed structs (both read common/defaults.hpp). A test that
// builds a sequencer directly runs the lift the daemon runs.
#include <gtest/gtest.h>

#include "dcp/host/dcp_lift.hpp"
#include "sch001/host/hydraulic_lift.hpp"
#include "uss/host/uss_lift.hpp"

namespace liftd::daemon {
namespace {

TEST(Defaults, ADefaultConfigGivesTheDcpControllersOwnDefaults) {
  const control::ControllerConfig daemon = dcp_controller_config(config::Config{});
  const control::ControllerConfig direct{};
  const travel::TravelConfig& a = daemon.travel;
  const travel::TravelConfig& b = direct.travel;
  EXPECT_EQ(a.data_info_type, b.data_info_type);
  EXPECT_EQ(a.use_i7, b.use_i7);
  EXPECT_EQ(a.fast_start_timeout_ms, b.fast_start_timeout_ms);
  EXPECT_EQ(a.level_tolerance_mm, b.level_tolerance_mm);
  EXPECT_EQ(a.relevel_threshold_mm, b.relevel_threshold_mm);
  EXPECT_EQ(a.auto_relevel, b.auto_relevel);
  EXPECT_EQ(a.relevel_electric_stop, b.relevel_electric_stop);
  EXPECT_EQ(a.dcp3_reference, b.dcp3_reference);
  EXPECT_EQ(a.dcp3_speed_count, b.dcp3_speed_count);
  EXPECT_EQ(a.dcp3_decel_distance_mm, b.dcp3_decel_distance_mm);
  EXPECT_EQ(a.dcp3_stop_lead_mm, b.dcp3_stop_lead_mm);
  EXPECT_EQ(daemon.link.data_info_type, direct.link.data_info_type);
  EXPECT_EQ(daemon.link.extended_position, direct.link.extended_position);
  EXPECT_EQ(daemon.link.fault_after_bad_frames, direct.link.fault_after_bad_frames);
  EXPECT_EQ(daemon.link.recover_after_good_frames, direct.link.recover_after_good_frames);
  EXPECT_EQ(daemon.link.request_timeout, direct.link.request_timeout);
  EXPECT_EQ(daemon.lift.level_tolerance_mm, direct.lift.level_tolerance_mm);
  EXPECT_EQ(daemon.inputs_timeout, direct.inputs_timeout);
  EXPECT_EQ(daemon.inspection_hold, direct.inspection_hold);
  // The lift model and the travels agree on when the car is level (status car.floor and the
  // "already at that level" answer of travel).
  EXPECT_EQ(a.level_tolerance_mm, daemon.lift.level_tolerance_mm);
}

TEST(Defaults, ADefaultConfigGivesTheSch001ControllersOwnDefaults) {
  const sch001::ControllerConfig daemon = sch001_controller_config(config::Config{});
  const sch001::ControllerConfig direct{};
  const sch001::HydraulicConfig& a = daemon.hydraulic;
  const sch001::HydraulicConfig& b = direct.hydraulic;
  EXPECT_EQ(a.has_v3, b.has_v3);
  EXPECT_EQ(a.has_v4, b.has_v4);
  EXPECT_EQ(a.fast_down, b.fast_down);
  EXPECT_EQ(a.star_delta_ms, b.star_delta_ms);
  EXPECT_EQ(a.slowdown_up_mm, b.slowdown_up_mm);
  EXPECT_EQ(a.slowdown_down_mm, b.slowdown_down_mm);
  EXPECT_EQ(a.slowdown_v3_mm, b.slowdown_v3_mm);
  EXPECT_EQ(a.slowdown_v4_mm, b.slowdown_v4_mm);
  EXPECT_EQ(a.stop_tolerance_mm, b.stop_tolerance_mm);
  EXPECT_EQ(a.relevel_start_mm, b.relevel_start_mm);
  EXPECT_EQ(a.max_travel_ms, b.max_travel_ms);
  EXPECT_EQ(a.relevel_doors_open, b.relevel_doors_open);
  EXPECT_EQ(daemon.link.single_unit, direct.link.single_unit);
  EXPECT_EQ(daemon.link.ids.to_card, direct.link.ids.to_card);
  EXPECT_EQ(daemon.link.ids.from_card, direct.link.ids.from_card);
  EXPECT_EQ(daemon.auto_relevel, direct.auto_relevel);
  EXPECT_EQ(daemon.lift.level_tolerance_mm, direct.lift.level_tolerance_mm);
  EXPECT_EQ(daemon.inputs_timeout, direct.inputs_timeout);
  EXPECT_EQ(daemon.inspection_hold, direct.inspection_hold);
}

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
