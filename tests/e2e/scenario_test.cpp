// End to end through a real `liftd --simulate` process (real pty, cycle and API socket): travels
// changed or ended mid-way (target extension, stop, fast stop, inspection), relevelling after a
// drift, fast start with the doors, and faults injected with `sim` while the car moves. Each
// case starts its own daemon, checks the travel events (right `cause`), the faults raised and
// drive enable (B0) off on the wire once the car stands.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <ostream>
#include <string>
#include <thread>

#include "e2e/harness.hpp"
#include "e2e/witness.hpp"

namespace liftd::e2e {
namespace {

// DCP 11.1.2: a DCP4 distance travel ends on the level; our acceptance is 2 mm (as in
// tests/dcp/control/travel_test.cpp).
constexpr double kLandingMm = 2.0;

bool is_ok(const json& reply) {
  return reply.is_object() && reply.value("ok", false);
}

/// A daemon that came up, or the test fails here.
#define START_LIFT(var, ...)                                                              \
  Lift var(::testing::UnitTest::GetInstance()->current_test_info()->name(), __VA_ARGS__); \
  ASSERT_TRUE(var.setup_error().empty()) << var.setup_error()

// ---- sim: argument checks of the command table ----

TEST(SimCommand, ValidatesItsArgumentsAndReportsTheInjectedState) {
  START_LIFT(lift, 4);
  json r = lift.call({{"cmd", "sim"}, {"action", "reply_fault"}});
  EXPECT_EQ(r["error"]["code"], "bad_request") << r.dump();
  EXPECT_EQ(r["error"]["field"], "fault") << r.dump();
  r = lift.call({{"cmd", "sim"}, {"action", "reply_fault"}, {"fault", "no_reply"}, {"frames", 0}});
  EXPECT_EQ(r["error"]["field"], "frames") << r.dump();
  r = lift.call({{"cmd", "sim"}, {"action", "drift"}});
  EXPECT_EQ(r["error"]["field"], "drift_mm") << r.dump();
  r = lift.call({{"cmd", "sim"}, {"action", "drift"}, {"drift_mm", 1001}});
  EXPECT_EQ(r["error"]["field"], "drift_mm") << r.dump();
  r = lift.call({{"cmd", "sim"}, {"action", "explode"}});
  EXPECT_EQ(r["error"]["field"], "action") << r.dump();
  r = lift.call({{"cmd", "sim"}, {"action", "general_fault"}, {"on", "yes"}});
  EXPECT_EQ(r["error"]["field"], "on") << r.dump();

  r = lift.call({{"cmd", "sim"}, {"action", "advance_warning"}});
  ASSERT_TRUE(is_ok(r)) << r.dump();
  EXPECT_EQ(r["result"]["advance_warning"], true);
  EXPECT_EQ(r["result"]["doors"], "locked");
  EXPECT_EQ(r["result"]["position_mm"], 0);
  // S2 reaches the status through the drive's replies.
  const json warned = lift.api().wait_event(
      "fault", [](const json& d) { return d["code"] == "advance_warning" && d["active"]; }, 5s);
  EXPECT_FALSE(warned.is_null()) << "no advance_warning fault after S2";
  r = lift.call({{"cmd", "sim"}, {"action", "advance_warning"}, {"on", false}});
  EXPECT_EQ(r["result"]["advance_warning"], false);
  r = lift.call({{"cmd", "sim"}, {"action", "open_doors"}});
  EXPECT_EQ(r["result"]["doors"], "opening") << r.dump();
}

// ---- travels changed or ended mid-way ----

TEST(Travel, ExtendedMidTravelLandsOnTheNewFloor) {
  judged_unless_stalled([&] {
    START_LIFT(lift, 4);
    ASSERT_TRUE(is_ok(lift.call({{"cmd", "travel"}, {"floor", 2}})));
    ASSERT_TRUE(lift.wait_moved(0, 500)) << lift.log();
    const json r = lift.call({{"cmd", "travel"}, {"floor", 4}});
    ASSERT_TRUE(is_ok(r)) << r.dump();
    EXPECT_EQ(r["result"]["extended"], true) << r.dump();
    const json end = lift.wait_travel_end();
    ASSERT_FALSE(end.is_null()) << lift.log();
    EXPECT_EQ(end["data"]["event"], "finished") << end.dump() << lift.log();
    EXPECT_EQ(end["data"]["target_mm"], level_mm(4));
    EXPECT_NEAR(end["data"]["position_mm"].get<double>(), level_mm(4), kLandingMm);
    // One travel, moved on: no second start; the drive's S5 confirmed the new target once.
    EXPECT_EQ(lift.count_events("travel", [](const json& d) { return d["event"] == "started"; }),
              1);
    EXPECT_EQ(
        lift.count_events("travel", [](const json& d) { return d["event"] == "target_extended"; }),
        1);
    EXPECT_EQ(lift.status()["car"]["floor"], 4);
    EXPECT_TRUE(lift.b0_off_in_newest());
  });
}

/// Travels 0 -> 5, and once the car is 3000 mm on its way sends `cmd`; returns how far the car
/// went from the request to standstill (NaN on failure).
double stop_distance(Lift& lift, const std::string& cmd) {
  if (!is_ok(lift.call({{"cmd", "travel"}, {"floor", 5}}))) return std::nan("");
  if (!lift.wait_moved(0, 3000)) return std::nan("");
  const double at = lift.position_mm();
  const json r = lift.call({{"cmd", cmd}});
  EXPECT_TRUE(is_ok(r)) << r.dump();
  const json end = lift.wait_travel_end();
  if (end.is_null()) return std::nan("");
  if (cmd == "stop") {
    // `stop` lands at the next possible floor (DCP 11.1.1 d: B2 until S6 falls at a level).
    EXPECT_EQ(end["data"]["event"], "finished") << end.dump();
    EXPECT_EQ(end["data"]["target_mm"], level_mm(r["result"]["floor"].get<int>())) << r.dump();
  } else {
    EXPECT_EQ(end["data"]["event"], "aborted") << end.dump();
    EXPECT_EQ(end["data"]["cause"], "stop_requested") << end.dump();
  }
  EXPECT_TRUE(lift.b0_off_in_newest());
  const json status = lift.status();
  EXPECT_EQ(status["travel"]["state"], "idle");
  EXPECT_TRUE(status["faults"].empty()) << status.dump();
  return status["car"]["position_mm"].get<double>() - at;
}

TEST(Travel, StopAndFastStopMidTravelAndTheFastStopIsShorter) {
  judged_unless_stalled([&] {
    // Two daemons at once: the same travel, the same point, one stop each way.
    double normal = std::nan("");
    double fast = std::nan("");
    std::thread other([&] {
      Lift lift("stop-normal", 4);
      if (lift.setup_error().empty()) normal = stop_distance(lift, "stop");
    });
    {
      START_LIFT(lift, 4);
      fast = stop_distance(lift, "fast_stop");
    }
    other.join();
    ASSERT_FALSE(std::isnan(normal));
    ASSERT_FALSE(std::isnan(fast));
    std::printf("  stop: %.0f mm, fast stop: %.0f mm after the request\n", normal, fast);
    EXPECT_GT(normal, 0.0);
    EXPECT_GT(fast, 0.0);
    EXPECT_LT(fast, normal) << "a fast stop (DCP 13) must stop sooner than the normal stop";
  });
}

// ---- inspection through the API ----

/// The monotonic time (us) of the newest frame with B0 on among the newest 1000 frames.
std::int64_t last_b0_on_us(Lift& lift) {
  std::int64_t last = 0;
  for (const auto& [t_us, command] : lift.newest_commands(1000)) {
    if ((command & 0x01) != 0) last = t_us;
  }
  return last;
}

TEST(Inspection, HeldByRepeatingStopsAtOnceOnRelease) {
  judged_unless_stalled([&] {
    START_LIFT(lift, 4);
    ASSERT_TRUE(is_ok(lift.call({{"cmd", "inspection"}, {"mode", "on"}, {"direction", "up"}})));
    // Hold: repeat well inside travel.inspection_hold_ms (500 ms) until the car moved 300 mm.
    bool moved = false;
    for (int i = 0; i < 100 && !moved; ++i) {
      lift.api().drain(150ms);
      ASSERT_TRUE(is_ok(lift.call({{"cmd", "inspection"}, {"mode", "on"}, {"direction", "up"}})));
      moved = lift.position_mm() >= 300;
    }
    ASSERT_TRUE(moved) << lift.log();
    EXPECT_EQ(lift.status()["travel"]["state"], "inspection");
    const std::int64_t released_us = mono_us();
    ASSERT_TRUE(is_ok(lift.call({{"cmd", "inspection"}, {"mode", "on"}, {"direction", "none"}})));
    const json end = lift.wait_travel_end(10s);
    ASSERT_FALSE(end.is_null());
    EXPECT_EQ(end["data"]["kind"], "inspection");
    ASSERT_TRUE(lift.b0_off_in_newest());
    // B0 drops in the first cycles after the release (2 cycles are 30 ms; 150 ms allows for a
    // loaded machine), not after the hold time.
    const std::int64_t dropped_after_us = last_b0_on_us(lift) - released_us;
    EXPECT_LT(dropped_after_us, 150'000) << "B0 stayed on " << dropped_after_us << " us";
    ASSERT_TRUE(is_ok(lift.call({{"cmd", "inspection"}, {"mode", "off"}})));
  });
}

TEST(Inspection, NotRepeatedStopsAfterTheHoldTime) {
  judged_unless_stalled([&] {
    START_LIFT(lift, 4);
    const std::int64_t held_us = mono_us();
    ASSERT_TRUE(is_ok(lift.call({{"cmd", "inspection"}, {"mode", "on"}, {"direction", "up"}})));
    ASSERT_FALSE(lift.wait_travel("started").is_null()) << lift.log();
    const json end = lift.wait_travel_end(10s);
    ASSERT_FALSE(end.is_null());
    EXPECT_EQ(end["data"]["kind"], "inspection");
    ASSERT_TRUE(lift.b0_off_in_newest());
    // travel.inspection_hold_ms = 500: B0 stays on until the hold runs out, then drops.
    const std::int64_t on_for_us = last_b0_on_us(lift) - held_us;
    EXPECT_GT(on_for_us, 450'000);
    EXPECT_LT(on_for_us, 800'000);
    EXPECT_GT(lift.position_mm(), 0.0) << "the car moved while the direction was held";
    ASSERT_TRUE(is_ok(lift.call({{"cmd", "inspection"}, {"mode", "off"}})));
  });
}

// ---- relevelling ----

TEST(Relevel, DriftOf25MmIsRelevelledByItselfOnDcp4) {
  judged_unless_stalled([&] {
    START_LIFT(lift, 4);
    // The controller relevels to the level of its last travel: travel there first.
    ASSERT_TRUE(is_ok(lift.call({{"cmd", "travel"}, {"floor", 1}})));
    const json arrived = lift.wait_travel_end();
    ASSERT_FALSE(arrived.is_null()) << lift.log();
    ASSERT_EQ(arrived["data"]["event"], "finished") << arrived.dump();
    ASSERT_TRUE(lift.b0_off_in_newest());
    // 25 mm up is beyond travel.relevel_threshold_mm (15).
    const json r = lift.call({{"cmd", "sim"}, {"action", "drift"}, {"drift_mm", 25}});
    ASSERT_TRUE(is_ok(r)) << r.dump();
    const json started = lift.wait_travel("started");
    ASSERT_FALSE(started.is_null()) << "no relevelling after a 25 mm drift\n" << lift.log();
    EXPECT_EQ(started["data"]["kind"], "relevel_distance") << started.dump();  // DCP 11.1.4: VN'
    EXPECT_NEAR(started["data"]["position_mm"].get<double>(), level_mm(1) + 25, 1.0);
    const json end = lift.wait_travel_end(30s);
    ASSERT_FALSE(end.is_null());
    EXPECT_EQ(end["data"]["event"], "finished") << end.dump();
    EXPECT_NEAR(end["data"]["position_mm"].get<double>(), level_mm(1), kLandingMm);
    EXPECT_TRUE(lift.b0_off_in_newest());
    EXPECT_EQ(lift.status()["car"]["floor"], 1);
    EXPECT_EQ(lift.count_events("travel", [](const json& d) { return d["event"] == "aborted"; }),
              0);
  });
}

// ---- fast start (DCP 12) with the simulated doors ----

/// Opens the doors and waits until they are open (2 s in the simulator).
void open_doors(Lift& lift) {
  ASSERT_TRUE(is_ok(lift.call({{"cmd", "sim"}, {"action", "open_doors"}})));
  for (int i = 0; i < 50; ++i) {
    lift.api().drain(100ms);
    // A request that changes nothing reports the door state.
    const json r = lift.call({{"cmd", "sim"}, {"action", "clear_reply_faults"}});
    if (r["result"]["doors"] == "open") return;
  }
  FAIL() << "the doors did not open";
}

// The hold must outlast closing (2 s) and locking (300 ms) in the simulator.
const json kFastStartTravel = {{"fast_start_timeout_ms", 5000}};

/// Opens the doors, arms a fast start to floor 2 (DCP 12) and waits until the lift says so.
::testing::AssertionResult fast_start_armed_at_open_doors(Lift& lift) {
  open_doors(lift);
  if (!is_ok(lift.call({{"cmd", "fast_start"}, {"action", "arm"}, {"floor", 2}}))) {
    return ::testing::AssertionFailure() << "fast_start arm refused\n" << lift.log();
  }
  if (lift.wait_travel("fast_start_armed").is_null()) {
    return ::testing::AssertionFailure() << "no fast_start_armed event\n" << lift.log();
  }
  return ::testing::AssertionSuccess();
}

TEST(FastStart, DoorReversalWhileArmedAbortsIt) {
  judged_unless_stalled([&] {
    START_LIFT(lift, 4, kFastStartTravel);
    ASSERT_TRUE(fast_start_armed_at_open_doors(lift));
    ASSERT_TRUE(is_ok(lift.call({{"cmd", "sim"}, {"action", "close_doors"}})));
    lift.api().drain(800ms);
    ASSERT_TRUE(is_ok(lift.call({{"cmd", "sim"}, {"action", "door_reversal"}})));
    const json end = lift.wait_travel_end(10s);
    ASSERT_FALSE(end.is_null()) << lift.log();
    EXPECT_EQ(end["data"]["event"], "aborted") << end.dump();
    EXPECT_EQ(end["data"]["cause"], "door_reversal") << end.dump();
    EXPECT_TRUE(lift.b0_off_in_newest());
    const json status = lift.status();
    EXPECT_EQ(status["travel"]["state"], "idle");
    EXPECT_NEAR(status["car"]["position_mm"].get<double>(), 0.0, 1.0) << "the car never left";
  });
}

TEST(FastStart, ADoorReversalFromTheInputsApiEndsItAsDcp12_2Says) {
  judged_unless_stalled([&] {
    // The I/O board's daemon reports the reversal through `inputs` (not the simulated doors).
    START_LIFT(lift, 4, kFastStartTravel);
    ASSERT_TRUE(fast_start_armed_at_open_doors(lift));
    ASSERT_TRUE(is_ok(lift.call({{"cmd", "sim"}, {"action", "close_doors"}})));
    lift.api().drain(800ms);
    const json reply = lift.call({{"cmd", "inputs"}, {"door_reversal", true}});
    ASSERT_TRUE(is_ok(reply)) << reply.dump();
    EXPECT_EQ(reply["result"]["door_reversal"], true);
    const json end = lift.wait_travel_end(10s);
    ASSERT_FALSE(end.is_null()) << lift.log();
    EXPECT_EQ(end["data"]["event"], "aborted") << end.dump();
    EXPECT_EQ(end["data"]["cause"], "door_reversal") << end.dump();
    EXPECT_TRUE(lift.b0_off_in_newest());
    EXPECT_NEAR(lift.position_mm(), 0.0, 1.0) << "the car never left";
  });
}

TEST(FastStart, ArmedThenDoorsLockedTravelsAndFinishes) {
  judged_unless_stalled([&] {
    START_LIFT(lift, 4, kFastStartTravel);
    ASSERT_TRUE(fast_start_armed_at_open_doors(lift));
    EXPECT_EQ(lift.status()["travel"]["state"], "fast_start");
    ASSERT_TRUE(is_ok(lift.call({{"cmd", "sim"}, {"action", "close_doors"}})));
    const json end = lift.wait_travel_end(60s);
    ASSERT_FALSE(end.is_null()) << lift.log();
    EXPECT_EQ(end["data"]["event"], "finished") << end.dump();
    EXPECT_NEAR(end["data"]["position_mm"].get<double>(), level_mm(2), kLandingMm);
    EXPECT_TRUE(lift.b0_off_in_newest());
    EXPECT_EQ(lift.status()["car"]["floor"], 2);
  });
}

// ---- faults while the car moves ----

/// True once each of the newest few master frames satisfies `pred` (checked for up to 3 s).
bool newest_frames_all(Lift& lift, const std::function<bool(int)>& pred) {
  for (int i = 0; i < 60; ++i) {
    const auto frames = lift.newest_commands(3);
    if (!frames.empty() &&
        std::all_of(frames.begin(), frames.end(), [&](const auto& f) { return pred(f.second); })) {
      return true;
    }
    lift.api().drain(50ms);
  }
  return false;
}

TEST(ShaftSignals, ADcp3TravelUpAtV4SlowsOnlyAtTheV4UpPointFromTheInputsApi) {
  judged_unless_stalled([&] {
    // DCP 10.1.1 step 3: B1 off at the deceleration point of the travel's own speed. The shaft's
    // points come through `inputs`; those of other speeds and of the other direction pass by.
    START_LIFT(lift, 3, json{{"dcp3_reference", "shaft_signals"}});
    ASSERT_TRUE(is_ok(lift.call({{"cmd", "travel"}, {"floor", 4}, {"speed", "V4"}})));
    ASSERT_TRUE(lift.wait_moved(level_mm(0), 1500.0)) << lift.log();
    ASSERT_TRUE(newest_frames_all(lift, [](int c) { return (c & 0x02) != 0; })) << "B1 on at V4";
    const json others = {{"cmd", "inputs"},     {"decel_v1_down", true}, {"decel_v1_up", true},
                         {"decel_v3_up", true}, {"decel_v4_down", true}, {"decel_v2_up", true},
                         {"decel_v7_up", true}, {"decel_v5_up", true}};
    ASSERT_TRUE(is_ok(lift.call(others)));
    lift.api().drain(500ms);
    for (const auto& [t, command] : lift.newest_commands(20)) {
      EXPECT_NE(command & 0x02, 0) << "B1 went off at another speed's or direction's point";
    }
    ASSERT_TRUE(is_ok(lift.call({{"cmd", "inputs"}, {"decel_v4_up", true}})));
    EXPECT_TRUE(newest_frames_all(lift, [](int c) { return (c & 0x07) == 0x05; }))
        << "B1 off, B2 and B0 on at the V4-up point";
    ASSERT_TRUE(is_ok(lift.call({{"cmd", "inputs"}, {"zone_level", true}})));
    const json end = lift.wait_travel_end(20s);
    ASSERT_FALSE(end.is_null()) << lift.log();
    EXPECT_EQ(end["data"]["event"], "finished") << end.dump();
  });
}

struct FaultCase {
  const char* legend;  ///< what happens, in plain English
  json inject;         ///< the sim request
  const char* cause;   ///< expected abort cause
  const char* fault;   ///< expected fault code, raised exactly once
};

/// Test names show the legend, not the bytes.
void PrintTo(const FaultCase& c, std::ostream* os) {
  *os << c.legend;
}

class FaultMidTravel : public ::testing::TestWithParam<FaultCase> {};

TEST_P(FaultMidTravel, AbortsWithTheCauseRaisesTheFaultOnceAndDropsB0) {
  judged_unless_stalled([&] {
    const FaultCase& c = GetParam();
    START_LIFT(lift, 4);
    ASSERT_TRUE(is_ok(lift.call({{"cmd", "travel"}, {"floor", 4}})));
    ASSERT_TRUE(lift.wait_moved(0, 1500)) << lift.log();
    json inject = c.inject;
    inject["cmd"] = "sim";
    ASSERT_TRUE(is_ok(lift.call(inject)));
    const json end = lift.wait_travel_end(20s);
    ASSERT_FALSE(end.is_null()) << lift.log();
    EXPECT_EQ(end["data"]["event"], "aborted") << end.dump();
    EXPECT_EQ(end["data"]["cause"], c.cause) << end.dump();
    EXPECT_TRUE(lift.b0_off_in_newest());
    lift.api().drain(1s);  // a repeated fault event would show by now
    const std::string code = c.fault;
    EXPECT_EQ(
        lift.count_events("fault", [&](const json& d) { return d["code"] == code && d["active"]; }),
        1);
    EXPECT_EQ(lift.count_events("travel", [](const json& d) { return d["event"] == "aborted"; }),
              1);
    EXPECT_EQ(lift.status()["travel"]["state"], "idle");
  });
}

INSTANTIATE_TEST_SUITE_P(
    Sim, FaultMidTravel,
    ::testing::Values(FaultCase{"the drive reports a general fault (S3)",
                                {{"action", "general_fault"}},
                                "drive_fault",
                                "drive_fault"},
                      FaultCase{"the safety chain opens",
                                {{"action", "safety_chain_open"}},
                                "safety_chain_open",
                                "safety_chain_open"},
                      FaultCase{
                          "the drive stays silent for 20 frames (link supervision trips after 10)",
                          {{"action", "reply_fault"}, {"fault", "no_reply"}, {"frames", 20}},
                          "link_down",
                          "link_fault"}),
    [](const auto& p) {
      const std::string fault = p.param.fault;
      return fault == "drive_fault"  ? std::string("DriveFault")
             : fault == "link_fault" ? std::string("LinkFails")
                                     : std::string("SafetyChainOpens");
    });

}  // namespace
}  // namespace liftd::e2e
