// Reload planning, one case per class of key: applied at once, or named and kept until a
// restart.
#include "daemon/reload.hpp"

#include <gtest/gtest.h>

#include <functional>

#include "kinds/config_schema.hpp"

namespace liftd::daemon {
namespace {

std::vector<std::string> keys(const std::vector<KeyChange>& changes) {
  std::vector<std::string> out;
  for (const auto& c : changes) out.push_back(c.key);
  return out;
}

struct Case {
  const char* legend;
  std::function<void(config::Config&)> change;
  std::vector<std::string> applied;
  std::vector<std::string> need_restart;
};

// Legend: what the file changes -> keys applied at once, keys kept until a restart (each list
// in alphabetical order of the key path).
TEST(ReloadPlan, ClassifiesEveryKindOfKey) {
  const std::vector<Case> cases = {
      {"nothing changed", [](config::Config&) {}, {}, {}},
      {"log level",
       [](config::Config& c) { c.log.level = config::LogLevel::debug; },
       {"log.level"},
       {}},
      {"API access groups",
       [](config::Config& c) {
         c.api.read_group = "staff";
         c.api.control_group = "operators";
         c.api.inputs_group = "iobox";
       },
       {"api.control_group", "api.inputs_group", "api.read_group"},
       {}},
      {"API limits",
       [](config::Config& c) {
         c.api.max_clients = 8;
         c.api.idle_timeout_s = 600;
         c.api.max_requests_per_s = 200;
       },
       {"api.idle_timeout_s", "api.max_clients", "api.max_requests_per_s"},
       {}},
      {"drive kind and device",
       [](config::Config& c) {
         c.drive.kind = config::DriveKind::Uss;
         c.drive.device = "/dev/ttyUSB0";
       },
       {},
       {"drive.device", "drive.kind"}},
      {"cycle and trace (the cycle thread owns them)",
       [](config::Config& c) {
         c.rt.priority = 70;
         c.rt.flight_recorder_s = 60;
       },
       {},
       {"rt.flight_recorder_s", "rt.priority"}},
      {"floors", [](config::Config& c) { c.floors[2].level_mm = 6100; }, {}, {"floors"}},
      {"a DCP3 deceleration distance",
       [](config::Config& c) { c.travel.dcp3_decel_distance_mm["V4"] = 2400; },
       {},
       {"travel.dcp3_decel_distance_mm.V4"}},
      {"a DCP3 speed added",
       [](config::Config& c) { c.travel.dcp3_decel_distance_mm["V2"] = 600; },
       {},
       {"travel.dcp3_decel_distance_mm.V2"}},
      {"socket path and group",
       [](config::Config& c) {
         c.api.socket = "/run/liftd/other.sock";
         c.api.socket_group = "staff";
       },
       {},
       {"api.socket", "api.socket_group"}},
      {"mixed",
       [](config::Config& c) {
         c.log.level = config::LogLevel::warn;
         c.inputs.timeout_ms = 300;
       },
       {"log.level"},
       {"inputs.timeout_ms"}},
  };
  for (const auto& c : cases) {
    const config::Config running;
    config::Config next;
    c.change(next);
    const ReloadPlan plan = plan_reload(running, next);
    EXPECT_EQ(keys(plan.applied), c.applied) << c.legend;
    EXPECT_EQ(keys(plan.need_restart), c.need_restart) << c.legend;
    // The effective configuration: live keys from the file, everything else as running.
    config::Config expected = running;
    expected.log = next.log;
    expected.api.read_group = next.api.read_group;
    expected.api.control_group = next.api.control_group;
    expected.api.inputs_group = next.api.inputs_group;
    expected.api.max_clients = next.api.max_clients;
    expected.api.idle_timeout_s = next.api.idle_timeout_s;
    expected.api.max_requests_per_s = next.api.max_requests_per_s;
    EXPECT_EQ(config::to_json(plan.effective, kinds::config_schema()),
              config::to_json(expected, kinds::config_schema()))
        << c.legend;
  }
}

TEST(ReloadPlan, NamesRunningAndRequestedValues) {
  const config::Config running;
  config::Config next;
  next.drive.device = "/dev/ttyUSB0";
  const ReloadPlan plan = plan_reload(running, next);
  ASSERT_EQ(plan.need_restart.size(), 1U);
  EXPECT_EQ(plan.need_restart[0],
            (KeyChange{"drive.device", "\"/dev/ttyS1\"", "\"/dev/ttyUSB0\""}));
}

TEST(ReloadPlan, LiveKeysAreExactlyTheseTen) {
  EXPECT_EQ(live_keys(), (std::vector<std::string>{
                             "log.level", "api.read_group", "api.control_group", "api.inputs_group",
                             "api.max_clients", "api.max_requests_per_s", "api.idle_timeout_s",
                             "api.max_clients_per_uid", "api.reserved_clients",
                             "api.stalled_reader_timeout_s"}));
}

}  // namespace
}  // namespace liftd::daemon
