// status `drive.state` against what a travel command is answered, alike for the three drive
// kinds, each as `liftd --simulate` (docs/api.md: `ready` when the drive lets a travel start).
// The simulated drive stops being ready (`sim not_ready`: DCP S0 = 0, SCH001 RDY = 0, USS local
// control by status word bit 9 = 0): the state is `not_ready` in `status` and in the watch
// stream's `state` event, and a travel is refused `not_ready`; ready again, a travel starts. A
// travel that a fault ends is reported alike and empties the calls queue on every kind.
#include <gtest/gtest.h>

#include <ostream>

#include "e2e/harness.hpp"

namespace liftd::e2e {
namespace {

struct DriveCase {
  const char* name;     ///< the test's name: the drive kind
  json config;          ///< merged into the lift's config
  const char* refusal;  ///< what the refused travel's message says
  const char* journal;  ///< what the journal says of the drive not being ready ("" for nothing)
};

void PrintTo(const DriveCase& c, std::ostream* out) {
  *out << c.name;
}

// Three floors 1200 mm apart for the hydraulic and USS cars, as in their own e2e tests.
const json kThreeFloors = json::array({{{"name", "0"}, {"level_mm", 0}},
                                       {{"name", "1"}, {"level_mm", 1200}},
                                       {{"name", "2"}, {"level_mm", 2400}}});

const DriveCase kCases[] = {
    {"dcp", json::object(), "drive not ready (S0 = 0)", ""},
    {"sch001",
     {{"drive", {{"kind", "sch001"}}},
      {"floors", kThreeFloors},
      {"sch001", {{"star_delta_ms", 500}, {"slowdown_up_mm", 300}, {"slowdown_down_mm", 350}}}},
     "RDY = 0",
     "[event=card_fault relays="},
    {"uss",
     {{"drive", {{"kind", "uss"}}},
      {"floors", kThreeFloors},
      {"travel", {{"dcp3_decel_distance_mm", {{"V4", 700}, {"V3", 500}}}}},
      {"uss", {{"speeds", {{"V0", 10}, {"VN", 3}, {"VI", 30}, {"V3", 63}, {"V4", 100}}}}}},
     "local control",
     "in local control (status word bit 9 = 0): no travel starts"},
};

class DriveStateTest : public ::testing::TestWithParam<DriveCase> {
 protected:
  void SetUp() override {
    lift_ = std::make_unique<Lift>(std::string("drive-state-") + GetParam().name, 4, json::object(),
                                   std::vector<std::string>{}, GetParam().config);
    ASSERT_EQ(lift_->setup_error(), "") << lift_->log();
  }
  json sim_not_ready(bool on) {
    return lift_->call({{"cmd", "sim"}, {"action", "not_ready"}, {"on", on}});
  }
  /// The next `state` event whose drive.state is `state` (null after 10 s).
  json state_event(const std::string& state) {
    return lift_->api().wait_event(
        "state", [&](const json& d) { return d["drive"]["state"] == state; }, 10s);
  }
  std::unique_ptr<Lift> lift_;
};

TEST_P(DriveStateTest, NotReadyWhileTheDriveIsNotReadyAndATravelIsRefusedExactlyThen) {
  ASSERT_TRUE(lift_->wait_drive_state("ready")) << lift_->status().dump();
  ASSERT_TRUE(sim_not_ready(true).value("ok", false));
  // Before: `ready` here on every kind, while every travel was refused.
  ASSERT_TRUE(lift_->wait_drive_state("not_ready")) << lift_->status().dump() << lift_->log();
  EXPECT_TRUE(state_event("not_ready").is_object()) << "the watch stream did not say it";
  const json s = lift_->status();
  EXPECT_TRUE(s["faults"].empty()) << "a drive that is not ready is no fault: " << s.dump();
  EXPECT_EQ(s["link"]["state"], "up") << s.dump();
  const json refused = lift_->call({{"cmd", "travel"}, {"floor", 1}});
  EXPECT_EQ(refused["error"]["code"], "not_ready") << refused.dump();
  EXPECT_NE(refused["error"]["message"].get<std::string>().find(GetParam().refusal),
            std::string::npos)
      << refused.dump();
  EXPECT_EQ(lift_->status()["drive"]["state"], "not_ready");
  EXPECT_EQ(lift_->status()["travel"]["state"], "idle");
  EXPECT_NE(lift_->log().find(GetParam().journal), std::string::npos) << lift_->log();

  ASSERT_TRUE(sim_not_ready(false).value("ok", false));
  ASSERT_TRUE(lift_->wait_drive_state("ready")) << lift_->status().dump() << lift_->log();
  EXPECT_TRUE(state_event("ready").is_object()) << "the watch stream did not say it";
  const json accepted = lift_->call({{"cmd", "travel"}, {"floor", 1}});
  ASSERT_TRUE(accepted.value("ok", false)) << accepted.dump();
  EXPECT_TRUE(lift_->wait_travel("started").is_object()) << lift_->log();
  // How the travel ends is the drive kinds' own tests' business (a loaded machine may lose a
  // USS reply): it is stopped here, and the state follows it.
  EXPECT_TRUE(lift_->call({{"cmd", "stop"}}).value("ok", false));
  EXPECT_TRUE(lift_->wait_travel_end(40s).is_object()) << lift_->log();
}

TEST_P(DriveStateTest, ATravelEndedByAFaultIsOneWarningAndEmptiesTheCallsQueue) {
  // docs/api.md `calls`: a travel that ends early empties the queue, whoever dispatches the lift
  // decides again. Before, the hydraulic and USS lifts kept it and set off by themselves once
  // the fault cleared; the DCP lift journalled the aborted travel as info, the others as a
  // warning.
  ASSERT_TRUE(lift_->wait_drive_state("ready")) << lift_->status().dump();
  for (int floor : {2, 1}) {
    const json added = lift_->call({{"cmd", "calls"}, {"action", "add"}, {"floor", floor}});
    ASSERT_TRUE(added.value("ok", false)) << added.dump();
  }
  ASSERT_TRUE(lift_->wait_travel("started").is_object()) << lift_->log();
  ASSERT_TRUE(lift_->call({{"cmd", "sim"}, {"action", "safety_chain_open"}}).value("ok", false));
  const json ended = lift_->wait_travel_end(20s);
  ASSERT_TRUE(ended.is_object()) << lift_->log();
  EXPECT_EQ(ended["data"]["event"], "aborted") << ended.dump();
  EXPECT_TRUE(ended["data"]["cause"].is_string()) << ended.dump();
  EXPECT_TRUE(lift_->status()["travel"]["calls"].empty()) << lift_->status().dump();
  const std::string log = lift_->log();
  const auto line = log.find("WARN  travel: travel aborted (");
  ASSERT_NE(line, std::string::npos) << log;
  const std::string aborted = log.substr(line, log.find('\n', line) - line);
  EXPECT_NE(aborted.find("[event=travel_aborted kind="), std::string::npos) << aborted;
  EXPECT_NE(aborted.find(" cause="), std::string::npos) << aborted;
  EXPECT_NE(aborted.find(" position_mm="), std::string::npos) << aborted;

  // The chain closes again: the car stays where it is, the dropped calls start nothing.
  ASSERT_TRUE(lift_->call({{"cmd", "sim"}, {"action", "safety_chain_open"}, {"on", false}})
                  .value("ok", false));
  ASSERT_TRUE(lift_->wait_drive_state("ready")) << lift_->status().dump() << lift_->log();
  EXPECT_FALSE(lift_->wait_travel("started", 2s).is_object()) << lift_->log();
  EXPECT_EQ(lift_->status()["travel"]["state"], "idle");
}

INSTANTIATE_TEST_SUITE_P(EveryDriveKind, DriveStateTest, ::testing::ValuesIn(kCases),
                         [](const ::testing::TestParamInfo<DriveCase>& param) {
                           return std::string(param.param.name);
                         });

}  // namespace
}  // namespace liftd::e2e
