// The hydraulic lift end to end: `liftd --simulate` with drive.kind "sch001" as a process, the
// controller and the simulated SCH001 card on a Unix socket in its runtime directory, driven
// through the API. Every fault ends the travel at once, reported once, and no travel command goes
// out in any frame after it (card document 3d, 3e).
#include <gtest/gtest.h>

#include "e2e/harness.hpp"

namespace liftd::e2e {
namespace {

// Three floors 1200 mm apart and short slowdowns keep each travel to a few seconds.
const json kHydraulic = {
    {"drive", {{"kind", "sch001"}}},
    {"floors", json::array({{{"name", "0"}, {"level_mm", 0}},
                            {{"name", "1"}, {"level_mm", 1200}},
                            {{"name", "2"}, {"level_mm", 2400}}})},
    {"sch001", {{"star_delta_ms", 500}, {"slowdown_up_mm", 300}, {"slowdown_down_mm", 350}}}};

double level(int floor) {
  return 1200.0 * floor;
}

/// The command byte (3c: SP3 SP2 SP1 SFY MSP HSP DW UP) of a traced answer "05 51 68 CC F D".
int command_byte(const json& frame) {
  const std::string tx = frame["tx"];
  if (tx.size() < 11 || tx.substr(6, 2) != "68") return 0;  // an acknowledgement
  return std::stoi(tx.substr(9, 2), nullptr, 16);
}

class HydraulicTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const std::string name = ::testing::UnitTest::GetInstance()->current_test_info()->name();
    lift_ = std::make_unique<Lift>("hyd-" + name, 4, json::object(), std::vector<std::string>{},
                                   kHydraulic);
    ASSERT_EQ(lift_->setup_error(), "") << lift_->log();
  }

  /// Travels to `floor` and checks where the car stopped.
  void travel_to(int floor) {
    const json r = lift_->call({{"cmd", "travel"}, {"floor", floor}});
    ASSERT_TRUE(r.value("ok", false)) << r.dump();
    const json end = lift_->wait_travel_end(40s);
    ASSERT_TRUE(end.is_object()) << "no end of travel to " << floor << "\n" << lift_->log();
    ASSERT_EQ(end["data"]["event"], "finished") << end.dump();
    EXPECT_EQ(end["data"]["kind"], "hydraulic");
    const json s = lift_->status();
    EXPECT_EQ(s["car"]["floor"], floor) << s.dump();
    EXPECT_NEAR(s["car"]["position_mm"].get<double>(), level(floor), 5.0);
    // The next answers carry the new floor (3c): within a few of the card's 100 ms frames.
    json sent;
    for (int i = 0; i < 30 && sent != floor; ++i) {
      lift_->api().drain(100ms);
      sent = lift_->status()["sch001"]["current_floor"];
    }
    EXPECT_EQ(sent, floor) << "3c: the current floor is updated at each stop";
  }

  /// Starts a travel 0 -> 2 and waits until the car moves fast.
  void start_long_travel() {
    ASSERT_TRUE(lift_->call({{"cmd", "travel"}, {"floor", 2}}).value("ok", false));
    ASSERT_TRUE(lift_->wait_moved(0, 300)) << lift_->log();
  }

  /// After the abort with `cause`: reported once, the car stops, and from the abort on every
  /// answer carries no travel bit.
  void expect_ended_by(const std::string& cause) {
    const json end = lift_->wait_travel_end(20s);
    ASSERT_TRUE(end.is_object()) << lift_->log();
    EXPECT_EQ(end["data"]["event"], "aborted") << end.dump();
    EXPECT_EQ(end["data"]["cause"], cause) << end.dump();
    const std::int64_t after = mono_us();
    // Every answer after the abort, until at least three more of the card's frames came.
    int checked = 0;
    for (int round = 0; round < 30 && checked < 3; ++round) {
      lift_->api().drain(200ms);
      checked = 0;
      const json trace = lift_->call({{"cmd", "trace"}, {"count", 60}});
      for (const auto& f : trace["result"]["frames"]) {
        if (f["t_us"].get<std::int64_t>() < after) continue;
        EXPECT_EQ(command_byte(f), 0) << "travel command after the fault: " << f.dump();
        ++checked;
      }
    }
    EXPECT_GE(checked, 3) << "the card's frames stopped coming or were not answered";
    EXPECT_EQ(lift_->count_events("travel", [](const json& d) { return d["event"] == "aborted"; }),
              1);
    EXPECT_EQ(lift_->status()["travel"]["state"], "idle");
    // The card's side: no answer broke 3d/3e (travel bits answering a status with ERR or
    // without RDY), none went missing.
    const json sim = lift_->call({{"cmd", "sim"}, {"action", "cold_oil"}, {"on", false}});
    ASSERT_TRUE(sim.value("ok", false)) << sim.dump();
    EXPECT_EQ(sim["result"]["violations"], 0) << lift_->log();
  }

  std::unique_ptr<Lift> lift_;
};

TEST_F(HydraulicTest, EveryFloorToEveryFloorUpAndDown) {
  // 0->1, 1->2, 2->0, 0->2, 2->1, 1->0: every ordered pair of three floors.
  for (int floor : {1, 2, 0, 2, 1, 0}) {
    travel_to(floor);
    if (HasFatalFailure()) return;
  }
  EXPECT_EQ(lift_->status()["drive"]["state"], "ready");
  const json s = lift_->call({{"cmd", "sim"}, {"action", "cold_oil"}, {"on", false}});
  ASSERT_TRUE(s.value("ok", false)) << s.dump();
  EXPECT_EQ(s["result"]["violations"], 0) << "the simulated card saw a violation:\n"
                                          << lift_->log();
}

TEST_F(HydraulicTest, StatusIsTheDriveNeutralOneWithTheCardsObject) {
  const json s = lift_->status();
  EXPECT_EQ(s["drive"], (json{{"kind", "sch001"}, {"state", "ready"}}));
  EXPECT_FALSE(s.contains("dcp"));
  EXPECT_EQ(s["sch001"]["card"]["rdy"], true);
  EXPECT_EQ(s["sch001"]["card"]["err"], false);
  EXPECT_EQ(s["sch001"]["timeout_enabled"], true);
  // DCP-only commands are not offered; the DCP drive's fault injections are refused.
  EXPECT_EQ(lift_->call({{"cmd", "key"}, {"key", 1}})["error"]["code"], "not_offered");
  EXPECT_EQ(lift_->call({{"cmd", "fast_stop"}})["error"]["code"], "not_offered");
  EXPECT_EQ(lift_->call({{"cmd", "sim"}, {"action", "refuse_target"}})["error"]["code"],
            "bad_request");
}

TEST_F(HydraulicTest, InspectionRunsWhileHeld) {
  const auto hold_up = [&] {
    return lift_->call({{"cmd", "inspection"}, {"mode", "on"}, {"direction", "up"}});
  };
  ASSERT_TRUE(hold_up().value("ok", false));
  bool moved = false;
  for (int i = 0; i < 30 && !moved; ++i) {  // repeated like a held button
    lift_->api().drain(200ms);
    (void)hold_up();
    moved = lift_->position_mm() > 50;
  }
  EXPECT_TRUE(moved) << lift_->log();
  EXPECT_EQ(lift_->status()["travel"]["state"], "inspection");
  EXPECT_EQ(lift_->status()["sch001"]["commands"]["msp"], true);
  ASSERT_TRUE(lift_->call({{"cmd", "inspection"}, {"mode", "off"}}).value("ok", false));
  const json end = lift_->wait_travel_end(5s);
  ASSERT_TRUE(end.is_object());
  EXPECT_EQ(end["data"]["kind"], "inspection");
}

TEST_F(HydraulicTest, RelevelsWhenTheCarSinks) {
  ASSERT_TRUE(lift_->call({{"cmd", "sim"}, {"action", "sink"}}).value("ok", false));
  const json start = lift_->wait_travel("started", 20s);
  ASSERT_TRUE(start.is_object()) << lift_->log();
  EXPECT_EQ(start["data"]["kind"], "relevel");
  ASSERT_TRUE(lift_->call({{"cmd", "sim"}, {"action", "sink"}, {"on", false}}).value("ok", false));
  const json end = lift_->wait_travel_end(20s);
  ASSERT_TRUE(end.is_object());
  EXPECT_EQ(end["data"]["event"], "finished");
  EXPECT_NEAR(lift_->position_mm(), 0.0, 5.0);
}

TEST_F(HydraulicTest, RdyDroppingMidTravelEndsIt) {
  start_long_travel();
  ASSERT_TRUE(lift_->call({{"cmd", "sim"}, {"action", "not_ready"}}).value("ok", false));
  expect_ended_by("drive_not_ready");
}

TEST_F(HydraulicTest, ErrMidTravelEndsItAndIsAFault) {
  start_long_travel();
  ASSERT_TRUE(lift_->call({{"cmd", "sim"}, {"action", "general_fault"}}).value("ok", false));
  expect_ended_by("drive_fault");
  EXPECT_EQ(
      lift_->count_events(
          "fault", [](const json& d) { return d["code"] == "drive_fault" && d["active"] == true; }),
      1);
  EXPECT_EQ(lift_->call({{"cmd", "travel"}, {"floor", 0}})["error"]["code"], "fault");
}

TEST_F(HydraulicTest, CardSilenceMidTravelEndsItAfterTenSeconds) {
  start_long_travel();
  ASSERT_TRUE(lift_->call({{"cmd", "sim"}, {"action", "card_silence"}}).value("ok", false));
  const json end = lift_->wait_travel_end(15s);
  ASSERT_TRUE(end.is_object()) << lift_->log();
  EXPECT_EQ(end["data"]["cause"], "card_silent");
  EXPECT_EQ(
      lift_->count_events(
          "fault", [](const json& d) { return d["code"] == "link_fault" && d["active"] == true; }),
      1);
  EXPECT_EQ(lift_->status()["link"]["state"], "fault");
  // The card speaks again: the link recovers without a restart.
  ASSERT_TRUE(
      lift_->call({{"cmd", "sim"}, {"action", "card_silence"}, {"on", false}}).value("ok", false));
  EXPECT_TRUE(
      lift_->api()
          .wait_event(
              "fault",
              [](const json& d) { return d["code"] == "link_fault" && d["active"] == false; }, 3s)
          .is_object());
}

TEST_F(HydraulicTest, BusOffMidTravelEndsIt) {
  start_long_travel();
  ASSERT_TRUE(lift_->call({{"cmd", "sim"}, {"action", "bus_off"}}).value("ok", false));
  expect_ended_by("bus_fault");
}

TEST_F(HydraulicTest, AReconnectedSilentCardIsUnknownUntilItSpeaksAgain) {
  ASSERT_TRUE(lift_->call({{"cmd", "sim"}, {"action", "card_silence"}}).value("ok", false));
  ASSERT_TRUE(lift_->call({{"cmd", "sim"}, {"action", "card_reconnect"}}).value("ok", false));
  json s;
  for (int i = 0; i < 100; ++i) {
    s = lift_->status();
    if (s["link"]["state"] == "init") break;
    lift_->api().drain(50ms);
  }
  EXPECT_EQ(s["link"]["state"], "init") << s.dump();
  EXPECT_NE(s["drive"]["state"], "ready") << s.dump();
  EXPECT_TRUE(s["sch001"]["card"].is_null()) << "the old connection's status was kept";
  const json refused = lift_->call({{"cmd", "travel"}, {"floor", 2}});
  EXPECT_EQ(refused["error"]["code"], "not_ready") << refused.dump();
  const std::int64_t silent_since = mono_us();
  ASSERT_TRUE(
      lift_->call({{"cmd", "sim"}, {"action", "card_silence"}, {"on", false}}).value("ok", false));
  for (int i = 0; i < 100 && lift_->status()["drive"]["state"] != "ready"; ++i) {
    lift_->api().drain(50ms);
  }
  EXPECT_EQ(lift_->status()["link"]["state"], "up");
  // The first answers on the new connection carry no travel bit, and the loss was one fault.
  const json trace = lift_->call({{"cmd", "trace"}, {"count", 20}});
  for (const auto& f : trace["result"]["frames"]) {
    if (f["t_us"].get<std::int64_t>() >= silent_since) {
      EXPECT_EQ(command_byte(f), 0) << f.dump();
    }
  }
  EXPECT_EQ(
      lift_->count_events(
          "fault", [](const json& d) { return d["code"] == "link_fault" && d["active"] == true; }),
      1);
  EXPECT_EQ(
      lift_->count_events(
          "fault", [](const json& d) { return d["code"] == "link_fault" && d["active"] == false; }),
      1);
  travel_to(2);
}

/// A flight-recorder file of the hydraulic lift holds the card's status frames (identifier
/// 0x581: 61 and the status byte, 3b) and our answers to them (0x551: 68 and the command, 3c).
void expect_card_frames(const std::string& text) {
  EXPECT_NE(text.find("rx 05 81 61 "), std::string::npos) << text.substr(0, 2000);
  EXPECT_NE(text.find("tx 05 51 68 "), std::string::npos) << text.substr(0, 2000);
}

TEST_F(HydraulicTest, TraceSaveWritesTheFlightRecorderAsOnEveryLift) {
  expect_card_frames(expect_trace_save_writes_file(*lift_, "sch001", 2));
}

TEST_F(HydraulicTest, Sigusr1WritesTheFlightRecorder) {
  expect_card_frames(expect_sigusr1_writes_file(*lift_));
}

// The card simulator as a process of its own on a Unix socket (can.interface "unix:PATH"), the
// way a real card sits on the bus: liftd without --simulate connects, loses the card when its
// process ends, reopens with backoff and recovers when it is back, without a restart.
TEST(HydraulicSeparateSimulator, LinkComesUpFallsAndRecoversWithoutRestart) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("liftd-e2e-" + std::to_string(::getpid()) + "-hyd-separate");
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string card_socket = (dir / "card.sock").string();
  const std::string api_socket = (dir / "api.sock").string();
  const auto start_sim = [&] {
    auto sim = std::make_unique<liftd::testing::Process>(
        std::vector<std::string>{SCH001_SIM_BINARY, "--socket", card_socket}, daemon_env(),
        dir.string(), "sim");
    for (int i = 0; i < 100 && !std::filesystem::exists(card_socket); ++i) {
      std::this_thread::sleep_for(20ms);
    }
    return sim;
  };
  auto sim = start_sim();
  json config = kHydraulic;
  config["can"] = {{"interface", "unix:" + card_socket}};
  config["api"] = {{"socket", api_socket},
                   {"socket_group", ""},
                   {"read_group", ""},
                   {"control_group", ""},
                   {"inputs_group", ""}};
  config["rt"] = {{"require_realtime", false}, {"lock_memory", false}};
  const std::string config_path = (dir / "liftd.json").string();
  std::ofstream(config_path) << config.dump(2);
  liftd::testing::Process daemon({LIFTD_BINARY, "--config", config_path}, daemon_env(),
                                 dir.string(), "liftd");
  const auto wait_link = [&](const std::string& state) {
    for (int i = 0; i < 150; ++i) {
      Client c(api_socket);
      if (c.connected()) {
        const json s = c.call({{"cmd", "status"}});
        if (s.is_object() && s["result"]["link"]["state"] == state) return s["result"];
      }
      std::this_thread::sleep_for(100ms);
    }
    return json(nullptr);
  };
  const json up = wait_link("up");
  ASSERT_TRUE(up.is_object()) << daemon.err() << sim->out();
  EXPECT_EQ(up["sch001"]["card"]["rdy"], true);
  sim->signal(SIGTERM);
  ASSERT_TRUE(sim->wait(5s).has_value());
  const json lost = wait_link("fault");
  ASSERT_TRUE(lost.is_object()) << daemon.err();
  EXPECT_TRUE(std::any_of(lost["faults"].begin(), lost["faults"].end(),
                          [](const json& f) { return f["code"] == "link_fault"; }))
      << lost.dump() << daemon.err();
  sim = start_sim();
  const json again = wait_link("up");
  ASSERT_TRUE(again.is_object()) << daemon.err();
  EXPECT_NE(daemon.err().find("reopening"), std::string::npos) << daemon.err();
  daemon.signal(SIGTERM);
  EXPECT_EQ(daemon.wait(10s), std::optional<int>(0)) << daemon.err();
  std::error_code ignored;
  std::filesystem::remove_all(dir, ignored);
}

}  // namespace
}  // namespace liftd::e2e
