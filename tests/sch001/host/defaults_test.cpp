// One set of defaults for the hydraulic (SCH001) lift: a default configuration file gives its
// controller exactly the settings a test gets from the default-constructed structs (both read
// the kind's defaults), so a test that builds the controller directly runs the lift the daemon
// runs.
#include <gtest/gtest.h>

#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "kinds/config_schema.hpp"
#include "sch001/config/section.hpp"
#include "sch001/host/hydraulic_lift.hpp"
#include "support/section_defaults.hpp"

namespace liftd::daemon {
namespace {

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

TEST(Sch001Section, AnEmptyFileGivesTheDocumentedDefaults) {
  // Legend: key path -> its default (docs/config.md); every key of `sch001.*` is in the table.
  const liftd::testing::SectionDefaults expected = {
      {"/sch001/base", 0},
      {"/sch001/controller_node", 49},
      {"/sch001/single_unit", true},
      {"/sch001/fast_down", "hsp"},
      {"/sch001/has_v3", false},
      {"/sch001/has_v4", false},
      {"/sch001/star_delta_ms", 1500},
      {"/sch001/slowdown_up_mm", 500},
      {"/sch001/slowdown_down_mm", 700},
      {"/sch001/slowdown_v3_mm", 1000},
      {"/sch001/slowdown_v4_mm", 1500},
      {"/sch001/stop_tolerance_mm", 3},
      {"/sch001/relevel_start_mm", 10},
      {"/sch001/max_travel_ms", 45000},
      {"/sch001/auto_relevel", true},
  };
  liftd::testing::expect_section_defaults("sch001", expected);
}

}  // namespace
}  // namespace liftd::daemon
