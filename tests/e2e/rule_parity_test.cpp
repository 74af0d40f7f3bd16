// The lift rules every drive kind keeps alike, run against `liftd --simulate` of each kind (the
// table of e2e/drive_cases.hpp): the inspection and recall switches end a normal travel with one
// cause and refuse the next with one text, `travel.relevel_with_doors` decides whether a sunk
// car relevels with its doors open, and a link fault writes the flight recorder. Each of these
// once differed between the kinds (the recall switch was read by the DCP lift only).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>

#include <string>
#include <thread>
#include <vector>

#include "e2e/drive_cases.hpp"
#include "e2e/harness.hpp"
#include "e2e/witness.hpp"

namespace liftd::e2e {
namespace {

/// The `error` object of a reply (empty when it has none: the request was accepted).
json error_of(const json& reply) {
  return reply.is_object() && reply.contains("error") && reply["error"].is_object()
             ? reply["error"]
             : json::object();
}

class RuleParity : public ::testing::TestWithParam<DriveCase> {
 protected:
  /// A lift of the case's kind with `extra` merged into its configuration last.
  std::unique_ptr<Lift> make_lift(const std::string& what, const json& extra = json::object()) {
    json config = GetParam().config;
    config.merge_patch(extra);
    auto lift = std::make_unique<Lift>(what + "-" + GetParam().name, 4, json::object(),
                                       std::vector<std::string>{}, config);
    EXPECT_EQ(lift->setup_error(), "") << lift->log();
    return lift;
  }
  /// A travel to the case's far floor, started and well under way.
  static void start_far_travel(Lift& lift) {
    ASSERT_TRUE(lift.wait_drive_state("ready")) << lift.status().dump();
    const json r = lift.call({{"cmd", "travel"}, {"floor", GetParam().far_floor}});
    ASSERT_TRUE(r.value("ok", false)) << r.dump();
    ASSERT_TRUE(lift.wait_travel("started").is_object()) << lift.log();
    ASSERT_TRUE(lift.wait_moved(0, 300)) << lift.status().dump() << lift.log();
  }
  /// The simulated doors held open (the obstruction keeps them there), once they are.
  static void hold_doors_open(Lift& lift) {
    ASSERT_TRUE(lift.call({{"cmd", "sim"}, {"action", "obstruct_doors"}}).value("ok", false));
    std::string doors;
    for (int i = 0; i < 100 && doors != "open"; ++i) {
      const json r = lift.call({{"cmd", "sim"}, {"action", "open_doors"}});
      ASSERT_TRUE(r.value("ok", false)) << r.dump();
      doors = r["result"].value("doors", "");
      if (doors != "open") lift.api().drain(100ms);
    }
    ASSERT_EQ(doors, "open") << lift.log();
  }
  /// The car at floor 1, at rest, then sunk 25 mm below its level (beyond every kind's
  /// relevelling threshold, inside its relevelling zone) with its doors held open and the door
  /// zone bridged by the I/O board.
  static void sink_at_floor_1_with_doors_open(Lift& lift, double& level) {
    ASSERT_TRUE(lift.wait_drive_state("ready")) << lift.status().dump();
    ASSERT_TRUE(lift.call({{"cmd", "travel"}, {"floor", 1}}).value("ok", false));
    const json arrived = lift.wait_travel_end(40s);
    ASSERT_TRUE(arrived.is_object()) << lift.log();
    ASSERT_EQ(arrived["data"]["event"], "finished") << arrived.dump();
    level = lift.position_mm();
    lift.api().drain(500ms);  // at rest (the drive's hold time after the stop)
    hold_doors_open(lift);
    ASSERT_TRUE(lift.call({{"cmd", "inputs"}, {"zone_door", true}}).value("ok", false));
    const json drift = lift.call({{"cmd", "sim"}, {"action", "drift"}, {"drift_mm", -25}});
    ASSERT_TRUE(drift.value("ok", false)) << drift.dump();
  }
};

// DCP 9.1.1: inspection or recall (test control) switched on ends a normal travel at once; no
// normal travel starts while either is on (docs/api.md `travel`: not_ready "inspection or recall
// is switched on"; `travel` events: cause `mode_changed`). The recall switch comes from the I/O
// board (`inputs`), the inspection switch here from the API's software switch.
TEST_P(RuleParity, InspectionOrRecallMidTravelEndsItAsModeChangedAndRefusesTheNext) {
  struct Switch {
    const char* name;
    json on;
    json off;
  };
  const Switch switches[] = {
      {"recall", {{"cmd", "inputs"}, {"recall", true}}, {{"cmd", "inputs"}, {"recall", false}}},
      {"inspection",
       {{"cmd", "inspection"}, {"mode", "on"}},
       {{"cmd", "inspection"}, {"mode", "off"}}},
  };
  for (const Switch& s : switches) {
    SCOPED_TRACE(s.name);
    judged_unless_stalled([&] {
      const std::unique_ptr<Lift> lift = make_lift(std::string("mode-") + s.name);
      ASSERT_EQ(lift->setup_error(), "");
      start_far_travel(*lift);
      const json on = lift->call(s.on);
      ASSERT_TRUE(on.value("ok", false)) << on.dump();
      const json ended = lift->wait_travel_end(20s);
      ASSERT_TRUE(ended.is_object()) << lift->log();
      EXPECT_EQ(ended["data"]["event"], "aborted") << ended.dump();
      EXPECT_EQ(ended["data"]["cause"], "mode_changed") << ended.dump();
      // Once the car is at rest (a DCP drive ramps down after the abort and reports S1 until
      // it stands: `busy`), the refusal is the switch's.
      json refused = lift->call({{"cmd", "travel"}, {"floor", 0}});
      for (int i = 0; i < 50 && error_of(refused).value("code", "") == "busy"; ++i) {
        lift->api().drain(200ms);
        refused = lift->call({{"cmd", "travel"}, {"floor", 0}});
      }
      EXPECT_EQ(error_of(refused).value("code", ""), "not_ready") << refused.dump();
      EXPECT_EQ(error_of(refused).value("message", ""), "inspection or recall is switched on")
          << refused.dump();
      // Nor is a call taken while the switch is on (issue #44: it was, and waited).
      const json call = lift->call({{"cmd", "calls"}, {"action", "add"}, {"floor", 0}});
      EXPECT_EQ(error_of(call).value("code", ""), "not_ready") << call.dump();
      EXPECT_EQ(error_of(call).value("message", ""),
                std::string("the car is out of service (") + s.name + "): it takes no calls")
          << call.dump();
      EXPECT_FALSE(lift->wait_travel("started", 2s).is_object()) << lift->log();
      // Switched off, the car is in service again.
      ASSERT_TRUE(lift->call(s.off).value("ok", false));
      ASSERT_TRUE(lift->wait_drive_state("ready")) << lift->status().dump() << lift->log();
      const json accepted = lift->call({{"cmd", "travel"}, {"floor", 0}});
      EXPECT_TRUE(accepted.value("ok", false)) << accepted.dump();
      EXPECT_TRUE(lift->call({{"cmd", "stop"}}).value("ok", false));
      EXPECT_TRUE(lift->wait_travel_end(40s).is_object()) << lift->log();
    });
  }
}

// `travel.relevel_with_doors`: a car that sank at a floor with its doors held open and the door
// zone bridged relevels at once with "both" (the default: the bridge stands for locked doors),
// and with "closed" only once its doors are locked again.
TEST_P(RuleParity, RelevelWithDoorsDecidesWhetherASunkCarRelevelsWithItsDoorsOpen) {
  for (const bool doors_open_allowed : {true, false}) {
    const std::string mode = doors_open_allowed ? "both" : "closed";
    SCOPED_TRACE(mode);
    judged_unless_stalled([&] {
      const std::unique_ptr<Lift> lift =
          make_lift("relevel-" + mode, {{"travel", {{"relevel_with_doors", mode}}}});
      ASSERT_EQ(lift->setup_error(), "");
      double level = 0;
      sink_at_floor_1_with_doors_open(*lift, level);
      if (!doors_open_allowed) {
        EXPECT_FALSE(lift->wait_travel("started", 3s).is_object())
            << "relevelled with the doors open\n"
            << lift->log();
        ASSERT_TRUE(lift->call({{"cmd", "sim"}, {"action", "obstruct_doors"}, {"on", false}})
                        .value("ok", false));
        ASSERT_TRUE(lift->call({{"cmd", "sim"}, {"action", "close_doors"}}).value("ok", false));
      }
      const json started = lift->wait_travel("started", 15s);
      ASSERT_TRUE(started.is_object()) << "no relevelling\n" << lift->log();
      EXPECT_NE(started["data"]["kind"].get<std::string>().find("relevel"), std::string::npos)
          << started.dump();
      const json ended = lift->wait_travel_end(20s);
      ASSERT_TRUE(ended.is_object()) << lift->log();
      EXPECT_EQ(ended["data"]["event"], "finished") << ended.dump();
      EXPECT_NEAR(lift->position_mm(), level, 10.0) << lift->status().dump();
    });
  }
}

// A link fault writes the flight recorder once, on every kind: the frames that led to it are
// what a technician needs first (docs/operations.md "The flight recorder").
TEST_P(RuleParity, ALinkFaultWritesTheFlightRecorder) {
  judged_unless_stalled([&] {
    const std::unique_ptr<Lift> lift = make_lift("link-fault-trace");
    ASSERT_EQ(lift->setup_error(), "");
    ASSERT_TRUE(lift->wait_drive_state("ready")) << lift->status().dump();
    lift->api().drain(500ms);  // frames to record
    ASSERT_TRUE(lift->trace_files().empty());
    const json broken = lift->call(GetParam().link_fault);
    ASSERT_TRUE(broken.value("ok", false)) << broken.dump();
    const json fault = lift->api().wait_event(
        "fault", [](const json& d) { return d["code"] == "link_fault" && d["active"] == true; },
        10s);
    ASSERT_TRUE(fault.is_object()) << lift->log();
    bool written = false;
    for (int i = 0; i < 100 && !written; ++i) {
      written = lift->log().find(" after link fault") != std::string::npos;
      if (!written) lift->api().drain(50ms);
    }
    EXPECT_TRUE(written) << lift->log();
    EXPECT_EQ(lift->trace_files().size(), 1U) << lift->log();
  });
}

// docs/api.md `status`: car.floor is the floor the car stands at, null while a travel runs, on
// every kind (issue #44: it was set while the car passed a level at speed).
TEST_P(RuleParity, TheCarsFloorIsNullWhileATravelRuns) {
  judged_unless_stalled([this] {
    const auto lift = make_lift("floor-null");
    ASSERT_NO_FATAL_FAILURE(start_far_travel(*lift));
    const json end = lift->wait_travel_end(60s);
    ASSERT_TRUE(end.is_object()) << lift->log();
    int running = 0;
    for (const json& e : lift->api().events()) {
      if (e["event"] != "state" || e["data"]["travel"]["state"] == "idle") continue;
      ++running;
      EXPECT_TRUE(e["data"]["car"]["floor"].is_null()) << e.dump();
    }
    EXPECT_GT(running, 3) << "state events while the travel ran";
    ASSERT_TRUE(lift->wait_drive_state("ready"));
    const json at_rest = lift->status();
    EXPECT_EQ(at_rest["car"]["floor"], GetParam().far_floor) << at_rest.dump();
  });
}

// A travel that a fault ends names the floor it was going to, as its start did (issue #44: SCH001
// and USS named the floor the car had left), on every kind.
TEST_P(RuleParity, AnAbortedTravelNamesItsOwnTarget) {
  judged_unless_stalled([this] {
    const auto lift = make_lift("aborted-target");
    const json floors = lift->call({{"cmd", "config"}})["result"]["config"]["floors"];
    const json target = floors[static_cast<std::size_t>(GetParam().far_floor)]["level_mm"];
    ASSERT_NO_FATAL_FAILURE(start_far_travel(*lift));
    ASSERT_TRUE(lift->call(GetParam().link_fault).value("ok", false));
    const json end = lift->wait_travel_end(30s);
    ASSERT_TRUE(end.is_object()) << lift->log();
    EXPECT_EQ(end["data"]["event"], "aborted") << end.dump();
    EXPECT_EQ(end["data"]["target_mm"], target) << end.dump();
    for (const json& e : lift->api().events()) {
      if (e["event"] == "travel" && e["data"]["event"] == "started") {
        EXPECT_EQ(e["data"]["target_mm"], target) << e.dump();
      }
    }
  });
}

// Every travel answered ok ends with a travel event, even one stopped before it began (issue
// #44's dispatcher waits for it): on DCP a travel asked for right after a stop waits for the I9
// of that stop (DCP 5.12.9), and a stop in that window once dropped it without a word.
TEST_P(RuleParity, ATravelStoppedBeforeItBeginsStillEndsWithAnEvent) {
  judged_unless_stalled([this] {
    const auto lift = make_lift("stopped-at-once");
    ASSERT_TRUE(lift->wait_drive_state("ready")) << lift->status().dump();
    ASSERT_TRUE(lift->call({{"cmd", "travel"}, {"floor", 1}}).value("ok", false));
    const json arrived = lift->wait_travel_end(40s);
    ASSERT_TRUE(arrived.is_object()) << lift->log();
    ASSERT_EQ(arrived["data"]["event"], "finished") << arrived.dump();
    // At once: the travel back, then the stop (a drive still winding down answers busy).
    json accepted = lift->call({{"cmd", "travel"}, {"floor", 0}});
    for (int i = 0; i < 100 && error_of(accepted).value("code", "") == "busy"; ++i) {
      accepted = lift->call({{"cmd", "travel"}, {"floor", 0}});
    }
    ASSERT_TRUE(accepted.value("ok", false)) << accepted.dump();
    ASSERT_TRUE(lift->call({{"cmd", "stop"}}).value("ok", false));
    const json ended = lift->wait_travel_end(30s);
    ASSERT_TRUE(ended.is_object()) << "a travel answered ok never ended\n" << lift->log();
    ASSERT_TRUE(lift->wait_drive_state("ready")) << lift->status().dump();
    EXPECT_FALSE(lift->status()["car"]["floor"].is_null()) << lift->status().dump();
  });
}

// docs/api.md `calls`: a plan that visits a floor twice (set), a call_served for each stop the car
// makes at a queued floor, and a calls_dropped naming what a stop took away; the same on every
// kind (issue #44: the queue held each floor once, and a stop emptied it without a word).
TEST_P(RuleParity, CallsPlanRepeatsServeEachStopAndNameWhatAStopDrops) {
  judged_unless_stalled([this] {
    const auto lift = make_lift("calls-plan", {{"travel", {{"call_stop_ms", 2000}}}});
    ASSERT_TRUE(lift->wait_drive_state("ready")) << lift->status().dump();
    const json floors = lift->call({{"cmd", "config"}})["result"]["config"]["floors"];
    const auto served_floors = [&] {
      std::vector<int> served;
      for (const json& e : lift->api().events()) {
        if (e["event"] == "call_served") served.push_back(e["data"]["floor"].get<int>());
      }
      return served;
    };
    // 0 -> 1 -> 0 -> 1 in one request.
    const json plan = lift->call({{"cmd", "calls"}, {"action", "set"}, {"floors", {1, 0, 1}}});
    ASSERT_TRUE(plan.value("ok", false)) << plan.dump();
    // travel.call_stop_ms: the car stands at a served call before it sets off to the next (the
    // doors' time to open). A lower bound: a slow machine only makes it longer.
    ASSERT_TRUE(lift->api()
                    .wait_event(
                        "call_served", [](const json& d) { return d["floor"] == 1; }, 60s)
                    .is_object())
        << lift->log();
    const auto served_at = std::chrono::steady_clock::now();
    ASSERT_TRUE(lift->wait_travel("started", 20s).is_object()) << lift->log();
    EXPECT_GE(std::chrono::steady_clock::now() - served_at, 1800ms);
    for (int i = 0; i < 3 && served_floors().size() < 3; ++i) {
      (void)lift->api().wait_event(
          "call_served", [](const json&) { return true; }, 60s);
    }
    EXPECT_EQ(served_floors(), (std::vector<int>{1, 0, 1})) << lift->log();
    EXPECT_TRUE(lift->status()["travel"]["calls"].empty()) << lift->status().dump();
    EXPECT_EQ(lift->count_events("calls_dropped", [](const json&) { return true; }), 0);

    // Twice in a row is refused and changes nothing.
    const json twice = lift->call({{"cmd", "calls"}, {"action", "set"}, {"floors", {0, 0}}});
    EXPECT_EQ(error_of(twice).value("message", ""), "the same floor twice in a row")
        << twice.dump();
    EXPECT_TRUE(lift->status()["travel"]["calls"].empty()) << lift->status().dump();

    // A stop on the way to the far floor: what it drops is named once, with its cause; a floor
    // the stop lands at stays queued and is served there.
    const int far = GetParam().far_floor;
    ASSERT_TRUE(lift->wait_drive_state("ready")) << lift->status().dump();
    const json next = lift->call({{"cmd", "calls"}, {"action", "set"}, {"floors", {far, 0}}});
    ASSERT_TRUE(next.value("ok", false)) << next.dump();
    ASSERT_TRUE(lift->wait_travel("started", 20s).is_object()) << lift->log();
    ASSERT_TRUE(lift->wait_moved(floors[1]["level_mm"].get<double>(), 300))
        << lift->status().dump();
    ASSERT_TRUE(lift->call({{"cmd", "stop"}}).value("ok", false));
    const json dropped = lift->api().wait_event(
        "calls_dropped", [](const json&) { return true; }, 10s);
    ASSERT_TRUE(dropped.is_object()) << lift->log();
    EXPECT_EQ(dropped["data"]["cause"], "stop_requested") << dropped.dump();
    const json lost = dropped["data"]["floors"];
    EXPECT_TRUE(std::find(lost.begin(), lost.end(), json(0)) != lost.end()) << dropped.dump();
    const json ended = lift->wait_travel_end(40s);
    ASSERT_TRUE(ended.is_object()) << lift->log();
    lift->api().drain(500ms);
    const bool far_dropped = std::find(lost.begin(), lost.end(), json(far)) != lost.end();
    const std::vector<int> served = served_floors();
    EXPECT_EQ(std::count(served.begin(), served.end(), far), far_dropped ? 0 : 1)
        << "the far floor is either dropped or served\n"
        << lift->log();
    EXPECT_EQ(lift->count_events("calls_dropped", [](const json&) { return true; }), 1);
    EXPECT_TRUE(lift->status()["travel"]["calls"].empty()) << lift->status().dump();
  });
}

// docs/api.md `calls` cancel of the floor a travel runs to: the travel stops at the next floor it
// can still stop at (`car.next_possible_stop`, set while the car moves on every kind: issue #44
// found it null for whole travels on SCH001 and USS) and the rest of the queue goes on.
TEST_P(RuleParity, CancellingTheFloorATravelRunsToStopsItAtTheNextFloorItCan) {
  judged_unless_stalled([this] {
    const auto lift = make_lift("cancel-target");
    ASSERT_TRUE(lift->wait_drive_state("ready")) << lift->status().dump();
    const int far = GetParam().far_floor;
    ASSERT_TRUE(
        lift->call({{"cmd", "calls"}, {"action", "set"}, {"floors", {far, 0}}}).value("ok", false));
    ASSERT_TRUE(lift->wait_travel("started", 20s).is_object()) << lift->log();
    ASSERT_TRUE(lift->wait_moved(0, 300)) << lift->status().dump();
    const json moving = lift->status();
    EXPECT_TRUE(moving["car"]["next_possible_stop"].is_number_integer()) << moving.dump();
    const json cancelled = lift->call({{"cmd", "calls"}, {"action", "cancel"}, {"floor", far}});
    ASSERT_TRUE(cancelled.value("ok", false)) << cancelled.dump();
    EXPECT_EQ(cancelled["result"]["detail"], "the car stops at the next floor it can")
        << cancelled.dump();
    const int stop_floor = cancelled["result"].value("floor", -1);
    EXPECT_GT(stop_floor, 0) << cancelled.dump();
    EXPECT_LT(stop_floor, far) << cancelled.dump();
    const json ended = lift->wait_travel_end(40s);
    ASSERT_TRUE(ended.is_object()) << lift->log();
    EXPECT_EQ(ended["data"]["event"], "finished") << ended.dump();
    // The queue goes on: the car travels to floor 0 and serves it; nothing was dropped.
    const json served = lift->api().wait_event(
        "call_served", [](const json& d) { return d["floor"] == 0; }, 60s);
    EXPECT_TRUE(served.is_object()) << lift->log();
    EXPECT_EQ(lift->count_events("calls_dropped", [](const json&) { return true; }), 0);
    EXPECT_EQ(lift->count_events("call_served", [&](const json& d) { return d["floor"] == far; }),
              0);
  });
}

// docs/api.md `inputs`: the result is what the cycle sees; under --simulate, the simulated
// machine's (issue #44: it said the safety chain was open and the doors unlocked while the car
// travelled), with the shaft signals the API gives.
TEST_P(RuleParity, TheInputsResultIsWhatTheCycleSees) {
  judged_unless_stalled([this] {
    const auto lift = make_lift("inputs-seen");
    ASSERT_NO_FATAL_FAILURE(start_far_travel(*lift));
    const json seen = lift->call({{"cmd", "inputs"}, {"end_zone_top", false}});
    ASSERT_TRUE(seen.value("ok", false)) << seen.dump();
    EXPECT_EQ(seen["result"]["safety_chain"], true) << seen.dump();
    EXPECT_EQ(seen["result"]["doors_closed"], true) << seen.dump();
    EXPECT_EQ(seen["result"]["doors_locked"], true) << seen.dump();
    ASSERT_TRUE(lift->call({{"cmd", "stop"}}).value("ok", false));
    ASSERT_TRUE(lift->wait_travel_end(40s).is_object()) << lift->log();
  });
}

// docs/api.md `status` car.motion: the phases of a travel, read from the car's measured speed,
// the same on every kind (issue #44: a dispatcher had only the direction).
TEST_P(RuleParity, TheMotionPhaseFollowsTheTravel) {
  judged_unless_stalled([this] {
    const auto lift = make_lift("motion");
    ASSERT_TRUE(lift->wait_drive_state("ready")) << lift->status().dump();
    EXPECT_EQ(lift->status()["car"]["motion"], "standing");
    ASSERT_TRUE(
        lift->call({{"cmd", "travel"}, {"floor", GetParam().far_floor}}).value("ok", false));
    std::vector<std::string> seen;
    for (int i = 0; i < 1200; ++i) {  // 60 s at most
      const json status = lift->status();
      const std::string motion = status["car"]["motion"].get<std::string>();
      if (seen.empty() || seen.back() != motion) seen.push_back(motion);
      if (status["travel"]["state"] == "idle" && seen.size() > 2) break;
      std::this_thread::sleep_for(50ms);
    }
    std::string trail;
    for (const std::string& m : seen) trail += m + " ";
    std::printf("motion: %s\n", trail.c_str());
    const auto at = [&](const char* phase) {
      return std::find(seen.begin(), seen.end(), phase) - seen.begin();
    };
    const auto n = static_cast<std::ptrdiff_t>(seen.size());
    EXPECT_LT(at("accelerating"), n) << trail;
    EXPECT_LT(at("at_speed"), n) << trail;
    EXPECT_LT(at("decelerating"), n) << trail;
    EXPECT_LT(at("accelerating"), at("decelerating")) << trail;
    EXPECT_EQ(seen.back(), "standing") << trail;
  });
}

// docs/api.md `status`: service says whether the car takes work and why not, the same on every
// kind (issue #44: it was only in refusal texts); car.doors from the inputs.
TEST_P(RuleParity, ServiceSaysWhetherTheCarTakesWorkAndWhyNot) {
  judged_unless_stalled([this] {
    const auto lift = make_lift("service");
    ASSERT_TRUE(lift->wait_drive_state("ready")) << lift->status().dump();
    // The service object once it says `reason` (null: in service); the inputs reach the
    // controller's thread with its next step.
    const auto service_becomes = [&](const json& reason) {
      json service;
      for (int i = 0; i < 100; ++i) {
        service = lift->status()["service"];
        if (service["reason"] == reason) break;
        std::this_thread::sleep_for(50ms);
      }
      return service;
    };
    EXPECT_EQ(service_becomes(nullptr), (json{{"in_service", true}, {"reason", nullptr}}));
    EXPECT_TRUE(lift->status()["car"]["doors"].is_string()) << lift->status().dump();
    for (const char* mode : {"inspection", "recall"}) {
      ASSERT_TRUE(lift->call({{"cmd", "inputs"}, {mode, true}}).value("ok", false));
      EXPECT_EQ(service_becomes(mode), (json{{"in_service", false}, {"reason", mode}}));
      ASSERT_TRUE(lift->call({{"cmd", "inputs"}, {mode, false}}).value("ok", false));
      EXPECT_EQ(service_becomes(nullptr), (json{{"in_service", true}, {"reason", nullptr}}));
    }
    // A drive that lets no travel start.
    ASSERT_TRUE(
        lift->call({{"cmd", "sim"}, {"action", "not_ready"}, {"on", true}}).value("ok", false));
    EXPECT_EQ(service_becomes("not_ready"), (json{{"in_service", false}, {"reason", "not_ready"}}));
    ASSERT_TRUE(
        lift->call({{"cmd", "sim"}, {"action", "not_ready"}, {"on", false}}).value("ok", false));
    EXPECT_EQ(service_becomes(nullptr), (json{{"in_service", true}, {"reason", nullptr}}));
    // A fault: every state that shows one says so (the SCH001 card's bus-off at rest clears
    // within a step or two and may show in none; out_of_service's table is tests/host's).
    ASSERT_TRUE(lift->call(GetParam().link_fault).value("ok", false));
    ASSERT_TRUE(lift->api()
                    .wait_event(
                        "fault", [](const json& d) { return d.value("active", false); }, 10s)
                    .is_object())
        << lift->log();
    lift->api().drain(300ms);
    int faulted = 0;
    for (const json& e : lift->api().events()) {
      if (e["event"] != "state" || e["data"]["faults"].empty()) continue;
      ++faulted;
      EXPECT_EQ(e["data"]["service"], (json{{"in_service", false}, {"reason", "fault"}}))
          << e.dump();
    }
    std::printf("state events showing the fault: %d\n", faulted);
  });
}

// A travel to the floor the car stands at is the same refusal on every kind (issue #44: it was
// bad_request on DCP and not_ready on SCH001 and USS): docs/api.md `travel`, bad_request.
TEST_P(RuleParity, ATravelToTheFloorTheCarStandsAtIsABadRequest) {
  judged_unless_stalled([this] {
    const auto lift = make_lift("at-level");
    ASSERT_TRUE(lift->wait_drive_state("ready")) << lift->status().dump();
    const json r = lift->call({{"cmd", "travel"}, {"floor", 0}});
    EXPECT_EQ(error_of(r)["code"], "bad_request") << r.dump();
    EXPECT_EQ(error_of(r)["message"], "the car is already at that level") << r.dump();
  });
}

// `eta` (issue #44, docs/api.md): the same answer on every kind. Before any travel the configured
// profile, nothing learned; a travel between two floors is learned as the travels log measured
// it (from rest, the same pair again is predicted as that duration); a car out of service gives
// no times; a floor or queue position out of range is a bad request. How good the times are is
// tools/bench/eta_accuracy.py's (a benchmark, not a timed test).
TEST_P(RuleParity, EtaLearnsEachPairFromTheCarsOwnTravels) {
  judged_unless_stalled([this] {
    // No stop time configured: from rest a prediction is the measured start plus the travel,
    // however soon after an arrival it is asked.
    const auto lift = make_lift("eta", {{"eta", {{"stop_ms", 0}}}});
    ASSERT_TRUE(lift->wait_drive_state("ready")) << lift->status().dump();
    const int far = GetParam().far_floor;
    const auto eta = [&](const json& extra = json::object()) {
      json request = {{"cmd", "eta"}};
      request.update(extra);
      const json r = lift->call(request);
      EXPECT_TRUE(r.value("ok", false)) << r.dump();
      return r["result"];
    };
    json e = eta();
    const std::size_t floors = lift->call({{"cmd", "config"}})["result"]["config"]["floors"].size();
    ASSERT_EQ(e["floors"].size(), floors) << e.dump();
    EXPECT_EQ(e["floors"][0], (json{{"floor", 0}, {"s", 0.0}, {"learned", true}}));
    EXPECT_GT(e["floors"][static_cast<std::size_t>(far)]["s"].get<double>(), 0.0);
    EXPECT_FALSE(e["floors"][static_cast<std::size_t>(far)]["learned"].get<bool>());
    EXPECT_EQ(e["basis"]["pairs_learned"], 0);

    const auto travel_to = [&](int floor) {
      ASSERT_TRUE(lift->wait_drive_state("ready")) << lift->status().dump();
      ASSERT_TRUE(lift->call({{"cmd", "travel"}, {"floor", floor}}).value("ok", false));
      // Mid-travel: once the run started (the reply can come a step before status shows it).
      ASSERT_TRUE(lift->wait_travel("started").is_object()) << lift->log();
      const json mid = eta();
      ASSERT_FALSE(mid["stops"].empty()) << mid.dump();
      EXPECT_EQ(mid["stops"][0]["floor"], floor) << mid.dump();
      const json end = lift->wait_travel_end(60s);
      ASSERT_TRUE(end.is_object()) << lift->log();
      ASSERT_EQ(end["data"]["event"], "finished") << end.dump();
    };
    ASSERT_NO_FATAL_FAILURE(travel_to(far));
    ASSERT_NO_FATAL_FAILURE(travel_to(0));
    ASSERT_TRUE(lift->wait_drive_state("ready"));
    const json log = lift->call({{"cmd", "travels"}, {"last", 2}})["result"]["travels"];
    ASSERT_EQ(log.size(), 2U) << log.dump();
    e = eta();
    EXPECT_EQ(e["basis"]["pairs_learned"], 2) << e.dump();
    EXPECT_EQ(e["basis"]["up"]["travels_measured"], 1) << e.dump();
    EXPECT_EQ(e["basis"]["down"]["travels_measured"], 1) << e.dump();
    const json& there = e["floors"][static_cast<std::size_t>(far)];
    EXPECT_TRUE(there["learned"].get<bool>()) << e.dump();
    // Both travels were asked for at rest: the start they took is measured too.
    const double start = e["basis"]["start_s"].get<double>();
    EXPECT_GT(start, 0.0) << e.dump();
    EXPECT_NEAR(there["s"].get<double>(), start + log[0]["duration_ms"].get<double>() / 1000.0,
                0.003)
        << log.dump() << e.dump();
    // A floor added first: its time, and the cost to nothing queued.
    e = eta({{"floor", 1}});
    EXPECT_EQ(e["with"]["floor"], 1);
    EXPECT_EQ(e["with"]["delays"], json::array());

    const json bad_floor = lift->call({{"cmd", "eta"}, {"floor", static_cast<int>(floors)}});
    EXPECT_EQ(error_of(bad_floor)["code"], "bad_request") << bad_floor.dump();
    const json bad_position = lift->call({{"cmd", "eta"}, {"floor", 1}, {"position", 1}});
    EXPECT_EQ(error_of(bad_position)["code"], "bad_request") << bad_position.dump();

    ASSERT_TRUE(lift->call({{"cmd", "inputs"}, {"inspection", true}}).value("ok", false));
    for (int i = 0; i < 100 && eta()["in_service"] != false; ++i) {
      std::this_thread::sleep_for(50ms);
    }
    e = eta();
    EXPECT_EQ(e["reason"], "inspection") << e.dump();
    EXPECT_TRUE(e["floors"].is_null()) << e.dump();
  });
}

INSTANTIATE_TEST_SUITE_P(EveryDriveKind, RuleParity, ::testing::ValuesIn(drive_cases()),
                         drive_case_name);

}  // namespace
}  // namespace liftd::e2e
