// One set of defaults for the DCP lift: a default configuration file gives its
// controller exactly the settings a test gets from the default-constructed structs (both read
// the kind's defaults), so a test that builds the controller directly runs the lift the daemon
// runs.
#include <gtest/gtest.h>

#include "dcp/host/dcp_lift.hpp"

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

}  // namespace
}  // namespace liftd::daemon
