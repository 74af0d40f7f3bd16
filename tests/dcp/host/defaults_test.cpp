// One set of defaults for the DCP lift: a default configuration file gives its
// controller exactly the settings a test gets from the default-constructed structs (both read
// the kind's defaults), so a test that builds the controller directly runs the lift the daemon
// runs.
#include <gtest/gtest.h>

#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "dcp/config/section.hpp"
#include "dcp/host/dcp_lift.hpp"
#include "kinds/config_schema.hpp"
#include "support/section_defaults.hpp"

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

TEST(DcpSection, AnEmptyFileGivesTheDocumentedDefaults) {
  // Legend: key path -> its default (docs/config.md); every key of `dcp.*` is in the table.
  const liftd::testing::SectionDefaults expected = {
      {"/dcp/manufacturer", "LD"},  // DCP 5.12.2.3: a code no company holds in the table
      {"/dcp/language", "EN"},          {"/dcp/data_info_type", "0"},
      {"/dcp/extended_position", true}, {"/dcp/link_fault_frames", 10},
      {"/dcp/link_recover_frames", 10}, {"/dcp/request_timeout_ms", 2000},
  };
  liftd::testing::expect_section_defaults("dcp", expected);
}

TEST(DcpSection, EveryKeyReachesTheTypedStruct) {
  const config::LoadResult r =
      kinds::parse_config(R"({"dcp": {"manufacturer": "QX", "language": "DE", "data_info_type": "3",
                  "extended_position": false, "link_fault_frames": 20,
                  "link_recover_frames": 5, "request_timeout_ms": 100}})",
                          "test");
  ASSERT_TRUE(r.ok());
  const config::Config& c = r.config;
  using config::dcp_section;
  EXPECT_EQ(dcp_section(c).manufacturer, "QX");
  EXPECT_EQ(dcp_section(c).language, "DE");
  EXPECT_EQ(dcp_section(c).data_info_type, '3');
  EXPECT_FALSE(dcp_section(c).extended_position);
  EXPECT_EQ(dcp_section(c).link_fault_frames, 20);
  EXPECT_EQ(dcp_section(c).link_recover_frames, 5);
  EXPECT_EQ(dcp_section(c).request_timeout_ms, 100);
}

}  // namespace
}  // namespace liftd::daemon
