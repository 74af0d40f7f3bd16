// Gating: every condition that forbids B0/B1/B2, for every travel type, at the start and in the
// middle of the travel; and a randomised property test over commands and injected faults.
#include <gtest/gtest.h>

#include <cstdio>
#include <random>
#include <string>

#include "fake_drive.hpp"

namespace liftd::travel::test {
namespace {

using dcp::Protocol;
using dcp::Speed;

constexpr std::uint8_t kMotion = 0x07;  // B0 | B1 | B2

/// A travel type as the gate table uses it.
enum class Scenario {
  Dcp4Distance,
  Dcp4Relevel,
  Dcp3Speed,
  Dcp3Crawl,
  Dcp4DriveDcp3Travel,
  Inspection,
  Recall,
  RelevelNoDistance,
  FastStartHold,
};

const char* name(Scenario s) {
  switch (s) {
    case Scenario::Dcp4Distance:
      return "Dcp4Distance";
    case Scenario::Dcp4Relevel:
      return "Dcp4Relevel";
    case Scenario::Dcp3Speed:
      return "Dcp3Speed";
    case Scenario::Dcp3Crawl:
      return "Dcp3Crawl";
    case Scenario::Dcp4DriveDcp3Travel:
      return "Dcp4DriveDcp3Travel";
    case Scenario::Inspection:
      return "Inspection";
    case Scenario::Recall:
      return "Recall";
    case Scenario::RelevelNoDistance:
      return "RelevelNoDistance";
    case Scenario::FastStartHold:
      return "FastStartHold";
  }
  return "?";
}

const std::vector<Scenario> kScenarios = {
    Scenario::Dcp4Distance, Scenario::Dcp4Relevel,         Scenario::Dcp3Speed,
    Scenario::Dcp3Crawl,    Scenario::Dcp4DriveDcp3Travel, Scenario::Inspection,
    Scenario::Recall,       Scenario::RelevelNoDistance,   Scenario::FastStartHold,
};

Protocol protocol_of(Scenario s) {
  switch (s) {
    case Scenario::Dcp3Speed:
    case Scenario::Dcp3Crawl:
    case Scenario::RelevelNoDistance:
    case Scenario::Recall:
      return Protocol::Dcp3;
    default:
      return Protocol::Dcp4;
  }
}

TravelConfig config_for() {
  TravelConfig config;
  config.use_i7 = false;
  config.auto_relevel = false;
  // DCP3 travels by shaft signals: none is ever met here, so the car runs on until a forbidding
  // condition comes (by position a target of 0 would be reached at once).
  config.dcp3_reference = Dcp3Reference::ShaftSignals;
  return config;
}

/// Starts the scenario's travel; returns whether the controller accepted it.
bool begin(Rig& rig, Scenario s) {
  TravelRequest request;
  switch (s) {
    case Scenario::Dcp4Distance:
      request.kind = TravelKind::Dcp4Distance;
      request.target_mm = 20000;
      break;
    case Scenario::Dcp4Relevel:
      request.kind = TravelKind::Dcp4Relevel;
      request.target_mm = 200;
      break;
    case Scenario::Dcp3Speed:
    case Scenario::Dcp4DriveDcp3Travel:
      request.kind = TravelKind::Dcp3Speed;
      request.speed = Speed::V4;
      request.direction = Direction::Up;
      break;
    case Scenario::Dcp3Crawl:
      request.kind = TravelKind::Dcp3Crawl;
      request.direction = Direction::Up;
      break;
    case Scenario::RelevelNoDistance:
      request.kind = TravelKind::Relevel;
      request.direction = Direction::Up;
      request.target_mm = 200;
      break;
    case Scenario::FastStartHold:
      rig.input.inputs.doors_locked = false;  // doors still closing
      request.kind = TravelKind::Dcp4Distance;
      request.target_mm = 20000;
      request.fast_start = true;
      break;
    case Scenario::Inspection:
    case Scenario::Recall:
      (s == Scenario::Inspection ? rig.input.inputs.inspection : rig.input.inputs.recall) = true;
      rig.input.inputs.button_up = true;
      return true;
  }
  return rig.controller.start(request) == StartResult::Accepted;
}

/// A forbidding condition, how to inject it and which scenarios it applies to.
struct Condition {
  const char* name;
  lift::Cause cause;
  void (*inject)(Rig&);
  bool (*applies)(Scenario);
};

bool always(Scenario) {
  return true;
}
bool needs_doors(Scenario s) {
  return s != Scenario::Inspection && s != Scenario::Recall && s != Scenario::FastStartHold;
}
bool needs_position(Scenario s) {
  return s == Scenario::Dcp4Distance || s == Scenario::Dcp4Relevel || s == Scenario::FastStartHold;
}

const std::vector<Condition> kConditions = {
    {"link down", lift::Cause::LinkDown, [](Rig& r) { r.input.link_up = false; }, always},
    {"no handshake", lift::Cause::NoHandshake, [](Rig& r) { r.input.handshake_done = false; },
     always},
    {"inputs lost", lift::Cause::InputsLost, [](Rig& r) { r.input.inputs.valid = false; }, always},
    {"S3 general fault", lift::Cause::DriveFault,
     [](Rig& r) { r.drive.status().general_fault = true; }, always},
    {"safety chain open", lift::Cause::SafetyChainOpen,
     [](Rig& r) { r.input.inputs.safety_chain_closed = false; }, always},
    {"doors unlocked", lift::Cause::DoorsNotLocked,
     [](Rig& r) {
       r.input.inputs.doors_locked = false;
       r.input.inputs.door_zone_bridge = false;
     },
     needs_doors},
    {"position lost", lift::Cause::PositionLost, [](Rig& r) { r.with_position = false; },
     needs_position},
};

bool saw_abort(const Rig& rig, lift::Cause cause) {
  for (const auto& e : rig.events) {
    if (e.type == Event::Type::Aborted && e.cause == cause) return true;
  }
  return false;
}

TEST(Gate, ForbiddingConditionMidTravelClearsB0B1B2AtOnce) {
  for (const Scenario s : kScenarios) {
    for (const Condition& c : kConditions) {
      if (!c.applies(s)) continue;
      SCOPED_TRACE(std::string(name(s)) + " / " + c.name);
      Rig rig(protocol_of(s), config_for());
      rig.with_position = true;
      rig.cycle();
      ASSERT_TRUE(begin(rig, s));
      ASSERT_TRUE(rig.run_until([&] {
        return (rig.records.back().command & kMotion) != 0 && rig.drive.status().brake_open;
      }));
      c.inject(rig);
      rig.cycle();
      EXPECT_EQ(rig.records.back().command & kMotion, 0);
      EXPECT_TRUE(saw_abort(rig, c.cause));
      for (int i = 0; i < 100; ++i) {
        rig.cycle();
        ASSERT_EQ(rig.records.back().command & kMotion, 0) << "cycle " << i;
      }
    }
  }
}

TEST(Gate, ForbiddingConditionAtStartNeverLetsB0Out) {
  for (const Scenario s : kScenarios) {
    for (const Condition& c : kConditions) {
      if (!c.applies(s)) continue;
      SCOPED_TRACE(std::string(name(s)) + " / " + c.name);
      Rig rig(protocol_of(s), config_for());
      rig.with_position = true;
      c.inject(rig);
      rig.cycle();
      const bool accepted = begin(rig, s);
      for (int i = 0; i < 100; ++i) rig.cycle();
      for (const auto& r : rig.records) {
        ASSERT_EQ(r.command & kMotion, 0);
      }
      if (accepted) {
        EXPECT_TRUE(saw_abort(rig, c.cause));
      }
    }
  }
}

TEST(Gate, DriveNotReadyOrAdvanceWarningBlockOnlyTheStart) {
  // Legend: S0, S2 at the start -> cause (DCP 9.1.3, 9.1.5).
  struct Case {
    bool ready;
    bool advance_warning;
    lift::Cause cause;
  };
  const std::vector<Case> cases = {{false, false, lift::Cause::DriveNotReady},
                                   {true, true, lift::Cause::AdvanceWarning}};
  for (const Scenario s : kScenarios) {
    for (const auto& c : cases) {
      SCOPED_TRACE(name(s));
      Rig rig(protocol_of(s), config_for());
      rig.with_position = true;
      rig.drive.status().ready = c.ready;
      rig.drive.status().advance_warning = c.advance_warning;
      rig.cycle();
      const bool accepted = begin(rig, s);
      for (int i = 0; i < 50; ++i) rig.cycle();
      for (const auto& r : rig.records) {
        ASSERT_EQ(r.command & kMotion, 0);
      }
      if (accepted) {
        EXPECT_TRUE(saw_abort(rig, c.cause));
      }
    }
  }
  // S2 during the travel does not stop it (DCP 9.1.5: the travel continues to the floor).
  Rig rig(Protocol::Dcp4, config_for());
  rig.cycle();
  ASSERT_TRUE(begin(rig, Scenario::Dcp4Distance));
  ASSERT_TRUE(rig.run_until([&] { return rig.drive.speed_mm_s() > 100; }));
  rig.drive.status().advance_warning = true;
  ASSERT_TRUE(rig.run_to_idle());
  EXPECT_EQ(rig.events.back().type, Event::Type::Finished);
}

TEST(Gate, BrakeOutputFollowsS6AndClosesWithoutLink) {
  CommandGate gate;
  CycleInput in;
  in.link_up = true;
  in.status.brake_open = true;
  EXPECT_TRUE(gate.apply({}, in).output.brake_open);
  in.status.brake_open = false;
  EXPECT_FALSE(gate.apply({}, in).output.brake_open);
  in.status.brake_open = true;
  in.link_up = false;
  EXPECT_FALSE(gate.apply({}, in).output.brake_open);
}

TEST(Gate, DoorBridgeStandsInForLockedDoorsOnlyWhereAllowed) {
  CycleInput in;
  in.link_up = in.handshake_done = true;
  in.status.ready = true;
  in.inputs.valid = in.inputs.safety_chain_closed = true;
  in.inputs.door_zone_bridge = true;
  GateProfile normal;
  GateProfile relevel;
  relevel.door_bridge_allowed = true;
  EXPECT_EQ(CommandGate::forbidding(in, normal, true), lift::Cause::DoorsNotLocked);
  EXPECT_EQ(CommandGate::forbidding(in, relevel, true), lift::Cause::None);
}

// Property: whatever the sequence of requests and injected faults, no frame carries B0/B1/B2
// while a gating condition forbids it. The check below is written independently of the gate.
TEST(GateProperty, RandomCommandsAndFaultsNeverLeakMotionBits) {
  std::size_t motion_frames = 0;
  std::size_t gate_aborts = 0;
  for (std::uint32_t seed = 1; seed <= 60; ++seed) {
    std::mt19937 rng(seed);
    auto chance = [&](int percent) {
      return std::uniform_int_distribution<int>(0, 99)(rng) < percent;
    };
    const Protocol protocol = chance(50) ? Protocol::Dcp4 : Protocol::Dcp3;
    TravelConfig config;
    config.use_i7 = chance(50);
    config.fast_start_timeout_ms = 2000;
    Rig rig(protocol, config);
    rig.with_position = protocol == Protocol::Dcp4 || chance(50);
    rig.controller.set_home_level(0);
    bool previous_enable = false;
    for (int cycle = 0; cycle < 1500; ++cycle) {
      // Requests.
      if (chance(3)) {
        TravelRequest request;
        const int pick = std::uniform_int_distribution<int>(0, 5)(rng);
        request.kind = pick == 0   ? TravelKind::Dcp4Distance
                       : pick == 1 ? TravelKind::Dcp4Relevel
                       : pick == 2 ? TravelKind::Dcp3Speed
                       : pick == 3 ? TravelKind::Dcp3Crawl
                       : pick == 4 ? TravelKind::Relevel
                                   : TravelKind::Dcp3Speed;
        request.speed = chance(50) ? Speed::V4 : Speed::V3;
        request.target_mm = std::uniform_int_distribution<std::int64_t>(-2000, 30000)(rng);
        request.direction = chance(50) ? Direction::Up : Direction::Down;
        request.fast_start = chance(30);
        if (chance(30)) request.load_percent = 50;
        static_cast<void>(rig.controller.start(request));
      }
      if (chance(1)) rig.controller.stop();
      if (chance(1)) rig.controller.fast_stop();
      if (chance(2)) {
        static_cast<void>(rig.controller.extend_target(
            std::uniform_int_distribution<std::int64_t>(0, 40000)(rng)));
      }
      // Faults and input changes (each flips with a small probability).
      auto flip = [&](bool& b, int percent) {
        if (chance(percent)) b = !b;
      };
      auto& in = rig.input;
      flip(in.link_up, in.link_up ? 1 : 20);
      flip(in.handshake_done, in.handshake_done ? 1 : 20);
      flip(in.inputs.valid, in.inputs.valid ? 1 : 20);
      flip(in.inputs.safety_chain_closed, in.inputs.safety_chain_closed ? 1 : 20);
      flip(in.inputs.doors_locked, 2);
      flip(in.inputs.door_reversal, 1);
      flip(in.inputs.door_zone_bridge, 1);
      flip(in.inputs.inspection, in.inputs.inspection ? 5 : 1);
      flip(in.inputs.recall, in.inputs.recall ? 5 : 1);
      flip(in.inputs.button_up, 5);
      flip(in.inputs.button_down, 5);
      flip(in.inputs.end_zone_top, 2);
      flip(in.inputs.end_zone_bottom, 2);
      flip(in.inputs.decel_up[3], 2);
      flip(in.inputs.decel_down[3], 2);
      flip(in.inputs.level_zone, 2);
      flip(rig.drive.status().general_fault, rig.drive.status().general_fault ? 20 : 1);
      flip(rig.drive.status().ready, rig.drive.status().ready ? 1 : 20);
      flip(rig.drive.status().advance_warning, 2);
      if (protocol == Protocol::Dcp4 && chance(1)) rig.with_position = !rig.with_position;

      const CycleOutput out = rig.cycle();
      const CycleInput& seen = rig.input;  // what the controller saw this cycle
      const bool motion = (out.command & kMotion) != 0;
      if (!motion) {
        previous_enable = false;
        continue;
      }
      ++motion_frames;
      const auto& status = rig.records.back().status;
      ASSERT_TRUE(seen.link_up) << "seed " << seed << " cycle " << cycle;
      ASSERT_TRUE(seen.handshake_done) << "seed " << seed << " cycle " << cycle;
      ASSERT_TRUE(seen.inputs.valid) << "seed " << seed << " cycle " << cycle;
      ASSERT_TRUE(seen.inputs.safety_chain_closed) << "seed " << seed << " cycle " << cycle;
      ASSERT_FALSE(status.general_fault) << "seed " << seed << " cycle " << cycle;
      const bool button_mode = seen.inputs.inspection || seen.inputs.recall;
      // Doors: locked, or bridged (relevelling), or inspection, or a fast start frame (DCP 12:
      // B0 while the doors close; no B1, and B2 only with remaining distance 0).
      const bool hold_frame =
          (out.command & 0x02) == 0 && ((out.command & 0x04) == 0 || out.data_word == 0);
      ASSERT_TRUE(seen.inputs.doors_locked || seen.inputs.door_zone_bridge || button_mode ||
                  hold_frame)
          << "seed " << seed << " cycle " << cycle << " command " << int{out.command};
      const TravelKind kind = rig.controller.active_kind();
      if (kind == TravelKind::Dcp4Distance || kind == TravelKind::Dcp4Relevel) {
        ASSERT_TRUE(seen.position_mm.has_value()) << "seed " << seed << " cycle " << cycle;
      }
      if (!previous_enable) {  // rising edge of B0: S0 = 1 and S2 = 0
        ASSERT_TRUE(status.ready) << "seed " << seed << " cycle " << cycle;
        ASSERT_FALSE(status.advance_warning) << "seed " << seed << " cycle " << cycle;
      }
      previous_enable = (out.command & 0x01) != 0;
    }
    for (const auto& e : rig.events) {
      gate_aborts += e.type == Event::Type::Aborted && e.cause <= lift::Cause::PositionLost ? 1 : 0;
    }
  }
  // Not vacuous: the random runs did travel, and the gate did step in.
  EXPECT_GT(motion_frames, 3000U);
  EXPECT_GT(gate_aborts, 50U);
  std::printf("motion frames %zu, gate aborts %zu\n", motion_frames, gate_aborts);
}

}  // namespace
}  // namespace liftd::travel::test
