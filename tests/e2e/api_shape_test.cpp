// The keys of `status` and `stats` for each drive kind, each as `liftd --simulate`
// (docs/api.md): the drive-neutral keys every kind has, and what only the kind has, under an
// object named after it. Each fact once: a DCP status has its mode, status bits, extended status
// and handshake problem under `dcp` only.
#include <gtest/gtest.h>

#include <ostream>
#include <set>
#include <string>
#include <thread>

#include "e2e/drive_cases.hpp"
#include "e2e/harness.hpp"

namespace liftd::e2e {
namespace {

using Keys = std::set<std::string>;

/// The keys of a JSON object (empty for anything else).
Keys keys_of(const json& object) {
  Keys out;
  if (object.is_object()) {
    for (const auto& [key, value] : object.items()) out.insert(key);
  }
  return out;
}

class ApiShapeTest : public ::testing::TestWithParam<DriveCase> {
 protected:
  void SetUp() override {
    lift_ = std::make_unique<Lift>(std::string("api-shape-") + GetParam().name, 4, json::object(),
                                   std::vector<std::string>{}, GetParam().config);
    ASSERT_EQ(lift_->setup_error(), "") << lift_->log();
  }
  std::unique_ptr<Lift> lift_;
};

// A dispatcher of a group learns who the car is from the greeting alone (issue #44).
TEST_P(ApiShapeTest, HelloNamesTheCarItsDriveKindAndItsFloors) {
  json config = GetParam().config;
  config["api"] = {{"car_name", "B"}};
  Lift named(std::string("api-shape-hello-") + GetParam().name, 4, json::object(), {}, config);
  ASSERT_EQ(named.setup_error(), "") << named.log();
  Client client(named.socket());
  ASSERT_TRUE(client.call({{"cmd", "version"}}).value("ok", false));
  ASSERT_FALSE(client.events().empty());
  const json& hello = client.events().front();
  ASSERT_EQ(hello["event"], "hello") << hello.dump();
  const json& car = hello["data"]["car"];
  EXPECT_EQ(car["name"], "B") << hello.dump();
  EXPECT_EQ(car["drive_kind"], GetParam().name);
  const json floors = config.contains("floors")
                          ? config["floors"]
                          : named.call({{"cmd", "config"}})["result"]["config"]["floors"];
  EXPECT_EQ(car["floors"], floors) << hello.dump();
  // Without a name the car is still told, its name null.
  Client unnamed(lift_->socket());
  ASSERT_TRUE(unnamed.call({{"cmd", "version"}}).value("ok", false));
  EXPECT_TRUE(unnamed.events().front()["data"]["car"]["name"].is_null());
}

TEST_P(ApiShapeTest, StatusHasTheNeutralKeysAndTheKindsObject) {
  const std::string kind = GetParam().name;
  const json s = lift_->status();
  EXPECT_EQ(keys_of(s),
            (Keys{"drive", "link", "car", "travel", "faults", "service", "rt", "record", kind}))
      << s.dump();
  EXPECT_EQ(s["drive"]["kind"], kind);
  EXPECT_EQ(keys_of(s["drive"]), (Keys{"kind", "state"})) << "DCP's mode, status and extended "
                                                             "are under dcp only: "
                                                          << s.dump();
  EXPECT_EQ(keys_of(s["link"]), (Keys{"state"})) << "handshake_problem is under dcp only";
  EXPECT_EQ(keys_of(s["car"]), (Keys{"position_mm", "floor", "next_possible_stop", "brake_open",
                                     "contactors_on", "doors", "motion"}));
  EXPECT_EQ(keys_of(s["service"]), (Keys{"in_service", "reason"})) << s.dump();
  EXPECT_EQ(keys_of(s["travel"]),
            (Keys{"state", "direction", "target_floor", "calls", "last_slip_mm"}));
  EXPECT_EQ(keys_of(s["rt"]), (Keys{"realtime", "policy", "priority", "memory_locked"}));
  EXPECT_EQ(keys_of(s["record"]), (Keys{"state", "path", "reason", "travels"})) << s.dump();
  EXPECT_EQ(keys_of(s[kind]), Keys(GetParam().status_keys.begin(), GetParam().status_keys.end()))
      << s.dump();
}

TEST_P(ApiShapeTest, StatsHaveTheNeutralCountersAndTheKindsOwnUnderItsName) {
  const std::string kind = GetParam().name;
  // The link is up, so frames went out; a USS pass of the polling list may still be running.
  json stats;
  for (int i = 0; i < 50; ++i) {
    stats = lift_->call({{"cmd", "stats"}})["result"];
    if (stats["cycle"]["cycles"].is_number() && stats["cycle"]["cycles"].get<long long>() > 0) {
      break;
    }
    std::this_thread::sleep_for(100ms);
  }
  EXPECT_EQ(keys_of(stats), (Keys{"link", "cycle", "api", kind})) << stats.dump();
  EXPECT_EQ(keys_of(stats["link"]), (Keys{"frames_sent"})) << stats.dump();
  EXPECT_EQ(keys_of(stats["cycle"]), (Keys{"cycles", "dropped_events", "dropped_travel_samples"}))
      << stats.dump();
  EXPECT_EQ(keys_of(stats[kind]), Keys(GetParam().stats_keys.begin(), GetParam().stats_keys.end()))
      << stats.dump();
  EXPECT_GT(stats["link"]["frames_sent"].get<long long>(), 0) << stats.dump();
  EXPECT_GT(stats["cycle"]["cycles"].get<long long>(), 0) << stats.dump();
}

TEST(ApiShapeCases, EveryRegisteredDriveKindHasItsCase) {
  expect_a_case_for_every_kind();
}

INSTANTIATE_TEST_SUITE_P(EveryDriveKind, ApiShapeTest, ::testing::ValuesIn(drive_cases()),
                         drive_case_name);

}  // namespace
}  // namespace liftd::e2e
