// `sim` as the registry of drive kinds (lib/kinds/lifts.cpp) builds it: every kind's actions in the
// documented order, each once; and an action reaches only the simulator of a kind that declared
// it (lib/<kind>/host/sim_actions.*, routed by apply_sim of lib/host/lift_common.hpp).
#include <gtest/gtest.h>

#include <algorithm>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "api/commands.hpp"
#include "api/dispatcher.hpp"
#include "api/fake_backend.hpp"
#include "common/mono_time.hpp"
#include "config/config.hpp"
#include "e2e/drive_cases.hpp"
#include "host/lift_common.hpp"
#include "kinds/commands.hpp"

namespace liftd::daemon {
namespace {

using nlohmann::json;

/// The `sim` actions in the order docs/api.md and docs/api.schema.json list them.
const std::vector<std::string> kDocumentedActions = {
    "general_fault",  "advance_warning",   "not_ready",     "reply_fault",     "clear_reply_faults",
    "drift",          "safety_chain_open", "door_reversal", "open_doors",      "close_doors",
    "obstruct_doors", "channel_fault",     "refuse_target", "oil_temperature", "pressure",
    "overpressure",   "card_silence",      "bus_off",       "cold_oil",        "sink",
    "card_reconnect"};

/// The actions on the simulated I/O board, which every simulated lift has.
const std::set<std::string> kBoardActions = {"safety_chain_open", "door_reversal", "open_doors",
                                             "close_doors", "obstruct_doors"};

/// Every registered kind (tests/<kind>/e2e_case.json says which actions its simulator takes).
std::vector<drive::Kind> every_kind() {
  std::vector<drive::Kind> kinds;
  for (const std::string_view name : drive::kKindNames) kinds.push_back(*drive::parse_kind(name));
  return kinds;
}

/// A simulated lift of one kind whose simulator only records which handler an action reached.
class RecordingSimBackend : public api::testing::FakeBackend {
 public:
  explicit RecordingSimBackend(drive::Kind kind) : board_(config::Config{}, mono_now()) {
    status_snapshot.drive_kind = kind;
  }

  void sim(const api::SimRequest& request, api::Responder done) override {
    const auto shared = [&](api::SimAction action) -> std::optional<api::Result> {
      reached.push_back("shared " +
                        std::string(api::kSimActions[static_cast<std::size_t>(action)]));
      return std::nullopt;
    };
    const auto own = [&](std::size_t index) -> std::optional<api::Result> {
      reached.push_back("own " + std::string(kinds::sim_actions_of(drive_kind()).own[index]));
      return std::nullopt;
    };
    done(apply_sim(kinds::sim_actions_of(drive_kind()), request, board_, mono_now(), shared, own,
                   [&request] {
                     return json{{"applied", std::string(request.name)}};
                   }));
  }

  std::vector<std::string> reached;  ///< "shared NAME" / "own NAME", in order

 private:
  SimulatedBoard board_;
};

json handle_sim(api::Dispatcher& dispatcher, const json& request) {
  api::Peer peer;
  peer.access = {true, true, true};
  api::testing::QuietSession session;
  json reply;
  dispatcher.handle_line(request.dump(), peer, session,
                         [&reply](std::string text, bool) { reply = json::parse(text); });
  return reply;
}

/// A valid `sim` request for `action` (with the arguments it needs).
json sim_request(const std::string& action) {
  json request = {{"cmd", "sim"}, {"action", action}};
  if (action == "reply_fault") request["fault"] = "no_reply";
  if (action == "channel_fault") request["channel"] = "garbage";
  if (action == "drift") request["drift_mm"] = 5;
  return request;
}

TEST(SimActions, TheSimCommandListsEveryKindsActionsOnceInTheDocumentedOrder) {
  for (const drive::Kind kind : every_kind()) {
    api::testing::FakeBackend backend;
    backend.status_snapshot.drive_kind = kind;
    api::Dispatcher dispatcher;
    api::add_builtin_commands(dispatcher, backend);
    kinds::add_drive_kind_commands(dispatcher, backend);
    const api::CommandSpec* sim = dispatcher.find("sim");
    ASSERT_NE(sim, nullptr) << drive::to_string(kind);
    std::vector<std::string> arg_names;
    for (const auto& arg : sim->args) arg_names.push_back(arg.name);
    EXPECT_EQ(arg_names,
              (std::vector<std::string>{"action", "on", "fault", "channel", "frames", "drift_mm"}));
    const std::vector<std::string>& choices = sim->args.at(0).choices;
    EXPECT_EQ(choices, kDocumentedActions) << drive::to_string(kind);
    const std::set<std::string> distinct(choices.begin(), choices.end());
    EXPECT_EQ(distinct.size(), choices.size()) << "an action name twice";
  }
}

TEST(SimActions, AnActionReachesOnlyTheSimulatorOfAKindThatDeclaredIt) {
  e2e::expect_a_case_for_every_kind();
  for (const e2e::DriveCase& expected : e2e::drive_cases()) {
    const std::set<std::string> shared(expected.sim_shared.begin(), expected.sim_shared.end());
    const std::set<std::string> own(expected.sim_own.begin(), expected.sim_own.end());
    RecordingSimBackend backend(*drive::parse_kind(expected.name));
    api::Dispatcher dispatcher;
    api::add_builtin_commands(dispatcher, backend);
    kinds::add_drive_kind_commands(dispatcher, backend);
    for (const std::string& action : kDocumentedActions) {
      SCOPED_TRACE(expected.name + " " + action);
      backend.reached.clear();
      const json reply = handle_sim(dispatcher, sim_request(action));
      if (shared.count(action) != 0) {
        EXPECT_TRUE(reply.value("ok", false)) << reply.dump();
        EXPECT_EQ(backend.reached, std::vector<std::string>{"shared " + action});
      } else if (own.count(action) != 0) {
        EXPECT_TRUE(reply.value("ok", false)) << reply.dump();
        EXPECT_EQ(backend.reached, std::vector<std::string>{"own " + action});
      } else if (kBoardActions.count(action) != 0) {
        EXPECT_TRUE(reply.value("ok", false)) << reply.dump();
        EXPECT_TRUE(backend.reached.empty()) << "a board action reached the drive's simulator";
      } else {
        EXPECT_TRUE(backend.reached.empty()) << "another kind's action reached this simulator";
        ASSERT_TRUE(reply.contains("error")) << reply.dump();
        EXPECT_EQ(reply.at("error").at("code"), "bad_request");
        EXPECT_EQ(reply.at("error").at("message"),
                  "\"" + action + "\" is for the simulator of another drive kind; this lift is " +
                      expected.sim_lift_name);
      }
    }
  }
}

TEST(SimActions, AKindsOwnArgumentIsCheckedOnEveryLift) {
  for (const drive::Kind kind : every_kind()) {
    RecordingSimBackend backend(kind);
    api::Dispatcher dispatcher;
    api::add_builtin_commands(dispatcher, backend);
    kinds::add_drive_kind_commands(dispatcher, backend);
    const json reply = handle_sim(dispatcher, {{"cmd", "sim"}, {"action", "channel_fault"}});
    ASSERT_TRUE(reply.contains("error")) << reply.dump();
    EXPECT_EQ(reply.at("error").at("message"), "channel_fault needs a channel");
    EXPECT_TRUE(backend.reached.empty());
  }
}

}  // namespace
}  // namespace liftd::daemon
