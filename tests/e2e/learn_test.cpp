// The learning travel end to end: on the DCP lift, `liftd --simulate` whose floor table is wrong
// by 20-60 mm learns the simulated shaft's true levels within 2 mm on DCP3 and DCP4 and `liftctl
// learn --apply` writes them; `stop` mid-learning ends it with nothing learned, on the hydraulic
// and USS lifts too. On every kind (parity_test.cpp, LearnParity): learned within 2 mm, a travel
// with the learned table lands on the true level, a shaft with a missing zone is refused. A try
// that a stalled machine ended (the witness of witness.hpp saw it) runs again.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <future>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "daemon/process.hpp"
#include "e2e/harness.hpp"
#include "e2e/witness.hpp"

namespace {

using namespace std::chrono_literals;
using liftd::e2e::Client;
using liftd::e2e::Lift;
using liftd::testing::Process;
using nlohmann::json;

// Three floors 500 mm apart: a short shaft, so the crawl through it takes about a quarter of a
// minute.
const std::vector<std::int64_t> kConfigured = {0, 500, 1000};
// The simulated shaft's true levels: off the configured ones by -35, +25 and +55 mm.
const std::vector<std::int64_t> kTrue = {-35, 525, 1055};

json floors(const std::vector<std::int64_t>& levels) {
  json out = json::array();
  for (std::size_t i = 0; i < levels.size(); ++i) {
    out.push_back({{"name", std::to_string(i)}, {"level_mm", levels[i]}});
  }
  return out;
}

// The simulated drive's crawl V0 at 100 mm/s, twice its default: 1.5 mm per 15 ms cycle keeps
// each zone edge within 0.75 mm of a sample, and the crawl through the shaft takes half as long.
constexpr int kLearnCrawlMmPerS = 100;

json config(int dcp, const std::vector<std::int64_t>& shaft) {
  return {{"floors", floors(kConfigured)},
          {"sim",
           {{"dcp", dcp},
            {"shaft_levels_mm", shaft},
            {"level_zone_mm", 100},
            {"slow_mm_per_s", kLearnCrawlMmPerS}}}};
}

constexpr auto kLearnTimeout = 150s;

void expect_learned(int dcp) {
  Lift lift("learn-dcp" + std::to_string(dcp), dcp, json::object(), {}, config(dcp, kTrue));
  ASSERT_EQ(lift.setup_error(), "");
  const json reply = lift.api().call({{"cmd", "learn"}}, kLearnTimeout);
  ASSERT_TRUE(reply.is_object()) << lift.log();
  ASSERT_TRUE(reply.value("ok", false)) << reply.dump();
  const json& result = reply["result"];
  EXPECT_TRUE(result["accepted"].get<bool>()) << result.dump();
  EXPECT_EQ(result["verdict"], "ok");
  EXPECT_EQ(result["zones_found"], 3);
  ASSERT_EQ(result["floors"].size(), 3U) << result.dump();
  for (std::size_t i = 0; i < 3; ++i) {
    const json& f = result["floors"][i];
    EXPECT_EQ(f["configured_mm"], kConfigured[i]);
    EXPECT_NEAR(f["learned_mm"].get<double>(), static_cast<double>(kTrue[i]), 2.0) << f.dump();
    EXPECT_EQ(f["difference_mm"].get<std::int64_t>(),
              f["learned_mm"].get<std::int64_t>() - kConfigured[i]);
    EXPECT_NEAR(f["zone_mm"].get<double>(), 100.0, 3.0) << f.dump();
  }
  // The watchers got the same table as the `learn` event; nothing else changed.
  const json event = lift.api().wait_event(
      "learn", [](const json&) { return true; }, 5s);
  ASSERT_TRUE(event.is_object());
  EXPECT_EQ(event["data"]["floors"], result["floors"]);
  const json cfg = lift.call({{"cmd", "config"}});
  EXPECT_EQ(cfg["result"]["config"]["floors"], floors(kConfigured));
  // The car stopped just above the top zone (the top terminal), at rest.
  EXPECT_TRUE(lift.wait_drive_state("ready", 10s));
  const double at = lift.position_mm();
  EXPECT_GT(at, static_cast<double>(kTrue.back() + 50));
  EXPECT_LT(at, static_cast<double>(kTrue.back() + 150));
}

// liftctl learn --apply on the daemon's own file, then a daemon started from the new file lands
// a travel on the shaft's true level.
void expect_liftctl_applies_the_learned_levels() {
  json written;  // the daemon's file after --apply (the Lift's directory goes with it)
  {
    Lift lift("learn-apply", 4, json::object(), {}, config(4, kTrue));
    ASSERT_EQ(lift.setup_error(), "");
    const std::filesystem::path file = lift.dir() / "liftd.json";
    const std::string before = [&] {
      std::ifstream in(file);
      std::stringstream text;
      text << in.rdbuf();
      return text.str();
    }();
    Process liftctl({LIFTCTL_BINARY, "--socket", lift.socket(), "learn", "--apply", file.string()},
                    {"PATH=/usr/bin:/bin"}, lift.dir().string(), "liftctl");
    const auto code = liftctl.wait(kLearnTimeout);
    ASSERT_EQ(code, 0) << liftctl.out() << liftctl.err() << lift.log();
    EXPECT_NE(liftctl.out().find("accepted: "), std::string::npos) << liftctl.out();
    EXPECT_NE(liftctl.out().find("restart liftd"), std::string::npos) << liftctl.out();
    std::ifstream bak(file.string() + ".bak");
    std::stringstream kept;
    kept << bak.rdbuf();
    EXPECT_EQ(kept.str(), before);
    std::ifstream in(file);
    written = json::parse(in);
    for (std::size_t i = 0; i < kTrue.size(); ++i) {
      EXPECT_NEAR(written["floors"][i]["level_mm"].get<double>(), static_cast<double>(kTrue[i]),
                  2.0);
    }
  }
  json next = config(4, kTrue);
  next["floors"] = written["floors"];
  Lift lift("learn-applied", 4, json::object(), {}, next);
  ASSERT_EQ(lift.setup_error(), "");
  const json reply = lift.call({{"cmd", "travel"}, {"floor", 1}});
  ASSERT_TRUE(reply.value("ok", false)) << reply.dump();
  const json end = lift.wait_travel_end();
  ASSERT_TRUE(end.is_object());
  EXPECT_EQ(end["data"]["event"], "finished") << end.dump();
  EXPECT_TRUE(lift.wait_drive_state("ready", 10s));
  EXPECT_NEAR(lift.position_mm(), static_cast<double>(kTrue[1]), 5.0);
}

TEST(Learn, Dcp4LiftctlAppliesTheLearnedLevelsAndATravelLandsThere) {
  liftd::e2e::judged_unless_stalled(expect_liftctl_applies_the_learned_levels);
}

TEST(Learn, Dcp3LearnsTheShaftsLevelsWithinTwoMillimetres) {
  liftd::e2e::judged_unless_stalled([] { expect_learned(3); });
}

void expect_dcp_stop_learns_nothing() {
  Lift lift("learn-stop", 4, json::object(), {}, config(4, kTrue));
  ASSERT_EQ(lift.setup_error(), "");
  auto learning = std::async(std::launch::async, [&lift] {
    Client other(lift.socket());
    return other.call({{"cmd", "learn"}}, kLearnTimeout);
  });
  // Well into the crawl up (the approach down takes a few seconds).
  ASSERT_TRUE(lift.api()
                  .wait_event(
                      "travel",
                      [](const json& d) {
                        return d.value("event", "") == "started" && d.value("kind", "") == "crawl";
                      },
                      30s)
                  .is_object())
      << lift.log();
  std::this_thread::sleep_for(3s);
  const json stop = lift.call({{"cmd", "stop"}});
  EXPECT_TRUE(stop.value("ok", false)) << stop.dump();
  ASSERT_EQ(learning.wait_for(30s), std::future_status::ready);
  const json reply = learning.get();
  ASSERT_TRUE(reply.is_object());
  EXPECT_FALSE(reply.value("ok", true)) << reply.dump();
  EXPECT_EQ(reply["error"]["code"], "not_ready") << reply.dump();
  EXPECT_EQ(reply["error"]["message"], "learning travel stopped: nothing learned");
  EXPECT_EQ(lift.api().wait_event(
                "learn", [](const json&) { return true; }, 2s),
            nullptr);
  const json cfg = lift.call({{"cmd", "config"}});
  EXPECT_EQ(cfg["result"]["config"]["floors"], floors(kConfigured));
}

TEST(Learn, StopMidLearningEndsItWithNothingLearned) {
  liftd::e2e::judged_unless_stalled(expect_dcp_stop_learns_nothing);
}

// The hydraulic and USS lifts on three floors 400 mm apart, with brisk learning speeds (the slow
// speed 200 mm/s, the crawl V0 30 %): these tests stop a learning, they measure no level.
json kind_config(const std::string& kind) {
  json out = {
      {"drive", {{"kind", kind}}},
      {"floors", floors({0, 400, 800})},
      {"sim",
       {{"shaft_levels_mm", {-35, 425, 855}}, {"level_zone_mm", 100}, {"slow_mm_per_s", 200}}}};
  if (kind == "sch001") {
    out["sch001"] = {{"star_delta_ms", 500}, {"slowdown_up_mm", 300}, {"slowdown_down_mm", 350}};
  } else {
    out["travel"] = {{"dcp3_decel_distance_mm", {{"V4", 700}, {"V3", 500}}}};
    out["uss"] = {{"speeds", {{"V0", 30}, {"VN", 3}, {"VI", 30}, {"V3", 63}, {"V4", 100}}}};
  }
  return out;
}

/// `stop` once the leg up runs: the learn command is answered not_ready, the car stops, nothing
/// is learned and no `learn` event follows.
void expect_stop_learns_nothing(const std::string& kind) {
  Lift lift("learn-stop-" + kind, 4, json::object(), {}, kind_config(kind));
  ASSERT_EQ(lift.setup_error(), "") << lift.log();
  ASSERT_TRUE(lift.wait_drive_state("ready")) << lift.status().dump();
  auto learning = std::async(std::launch::async, [&lift] {
    Client other(lift.socket());
    return other.call({{"cmd", "learn"}}, 60s);
  });
  // The approach down is one leg; the second `learn` travel is the leg up.
  int legs = 0;
  ASSERT_TRUE(lift.api()
                  .wait_event(
                      "travel",
                      [&legs](const json& d) {
                        return d.value("event", "") == "started" &&
                               d.value("kind", "") == "learn" && ++legs == 2;
                      },
                      20s)
                  .is_object())
      << lift.log();
  ASSERT_TRUE(lift.wait_moved(-300, 100)) << lift.status().dump();  // well under way up
  const json stop = lift.call({{"cmd", "stop"}});
  EXPECT_TRUE(stop.value("ok", false)) << stop.dump();
  ASSERT_EQ(learning.wait_for(20s), std::future_status::ready);
  const json reply = learning.get();
  ASSERT_TRUE(reply.is_object());
  EXPECT_FALSE(reply.value("ok", true)) << reply.dump();
  EXPECT_EQ(reply["error"]["code"], "not_ready") << reply.dump();
  EXPECT_EQ(reply["error"]["message"], "learning travel stopped: nothing learned");
  EXPECT_EQ(lift.api().wait_event(
                "learn", [](const json&) { return true; }, 1s),
            nullptr);
  EXPECT_TRUE(lift.wait_drive_state("ready", 10s));
  const json s = lift.status();
  EXPECT_EQ(s["travel"]["state"], "idle") << s.dump();
  EXPECT_LT(s["car"]["position_mm"].get<double>(), 425.0) << "stopped, not run on: " << s.dump();
  EXPECT_EQ(lift.call({{"cmd", "config"}})["result"]["config"]["floors"], floors({0, 400, 800}));
}

TEST(Learn, Sch001StopMidLearningEndsItWithNothingLearned) {
  liftd::e2e::judged_unless_stalled([] { expect_stop_learns_nothing("sch001"); });
}

TEST(Learn, UssStopMidLearningEndsItWithNothingLearned) {
  liftd::e2e::judged_unless_stalled([] { expect_stop_learns_nothing("uss"); });
}

}  // namespace
