// One set of defaults for the USS lift: a default configuration file gives its
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
#include "support/section_defaults.hpp"
#include "uss/config/section.hpp"
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

TEST(UssSection, AnEmptyFileGivesTheDocumentedDefaults) {
  // Legend: key path -> its default (docs/config.md); every key of `uss.*` is in the table.
  const liftd::testing::SectionDefaults expected = {
      {"/uss/baud", 38400},
      {"/uss/drive_address", 0},
      {"/uss/drive_pkw", "4"},
      {"/uss/drive_pzd_words", 2},
      {"/uss/slaves", nlohmann::json::array()},
      {"/uss/polling_list", nlohmann::json::array()},
      {"/uss/reply_delay_ms", 20},
      {"/uss/cycle_time_ms", 0},
      {"/uss/telegram_failures", 3},
      {"/uss/pkw_repeat_limit", 10},
      {"/uss/mirror_at_start", true},
      {"/uss/full_scale_raw", 16384},
      {"/uss/full_scale", 100},
      {"/uss/profile_timeout_ms", 2000},
      {"/uss/speeds", {{"V0", 5}, {"VN", 3}, {"VI", 30}, {"V3", 60}, {"V4", 100}}},
  };
  liftd::testing::expect_section_defaults("uss", expected);
}

TEST(UssSection, EveryKeyReachesTheTypedStruct) {
  const config::LoadResult r = kinds::parse_config(R"({"drive": {"kind": "uss"},
        "uss": {"baud": 187500, "drive_address": 7, "drive_pkw": "variable",
                "drive_pzd_words": 4,
                "slaves": [{"address": 12, "pkw": "3", "pzd_words": 0}, {"address": 31}],
                "polling_list": [7, 12, 7, 31], "reply_delay_ms": 5, "cycle_time_ms": 100,
                "telegram_failures": 7, "pkw_repeat_limit": 50, "mirror_at_start": false,
                "full_scale_raw": 8192, "full_scale": 50, "profile_timeout_ms": 500,
                "speeds": {"V0": 2.5, "VN": 1, "VI": 15, "V2": 20, "V3": 40, "V4": 99.9}}})",
                                                   "test");
  ASSERT_TRUE(r.ok());
  const config::Config& c = r.config;
  using config::uss_section;
  EXPECT_EQ(uss_section(c).baud, 187500);
  EXPECT_EQ(uss_section(c).drive_address, 7);
  EXPECT_EQ(uss_section(c).drive_pkw, config::UssPkw::variable);
  EXPECT_EQ(uss_section(c).drive_pzd_words, 4);
  EXPECT_EQ(uss_section(c).slaves, (std::vector<config::UssSlave>{{12, config::UssPkw::three, 0},
                                                                  {31, config::UssPkw::four, 2}}));
  EXPECT_EQ(uss_section(c).polling_list, (std::vector<int>{7, 12, 7, 31}));
  EXPECT_EQ(uss_section(c).reply_delay_ms, 5);
  EXPECT_EQ(uss_section(c).cycle_time_ms, 100);
  EXPECT_EQ(uss_section(c).telegram_failures, 7);
  EXPECT_EQ(uss_section(c).pkw_repeat_limit, 50);
  EXPECT_FALSE(uss_section(c).mirror_at_start);
  EXPECT_EQ(uss_section(c).full_scale_raw, 8192);
  EXPECT_EQ(uss_section(c).full_scale, 50);
  EXPECT_EQ(uss_section(c).profile_timeout_ms, 500);
  EXPECT_EQ(uss_section(c).speeds,
            (std::map<std::string, double>{
                {"V0", 2.5}, {"VN", 1}, {"VI", 15}, {"V2", 20}, {"V3", 40}, {"V4", 99.9}}));
}

}  // namespace
}  // namespace liftd::daemon
