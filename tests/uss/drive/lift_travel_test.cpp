// The USS travel sequencing against a small fake drive (fake_drive.hpp, written from C 5.2.1)
// and a car model, with a fake clock: one exchange every 10 ms, the STW/HSW of each tick go to
// the drive, its reply is what the next tick sees (as the runner does it).
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <functional>
#include <vector>

#include "uss/drive/fake_drive.hpp"
#include "uss/drive/lift_travel.hpp"

namespace liftd::uss {
namespace {

using std::chrono::milliseconds;
using test::Car;
using test::FakeDrive;

constexpr MonoTime kPeriod = milliseconds(10);

LiftTravelConfig test_config() {
  LiftTravelConfig c;
  c.slowdown_mm[speed_index(SpeedName::V4)] = 700;
  c.slowdown_mm[speed_index(SpeedName::V3)] = 400;
  // The fake drive stops from V0 (5 % = 50 mm/s) on its 100 %/s ramp in 0.05 s: 1.25 mm.
  c.stop_lead_mm = 2;
  return c;
}

class Rig {
 public:
  explicit Rig(const LiftTravelConfig& config = test_config()) : travel(config) {
    const std::vector<std::int64_t> levels = {0, 3000, 6000, 9000};
    floors.assign(levels);
    inputs.valid = inputs.safety_chain_closed = true;
    inputs.doors_closed = inputs.doors_locked = true;
    // A few idle exchanges: the drive leaves its power-up inhibit on our OFF1.
    for (int i = 0; i < 3; ++i) exchange();
  }

  DriveInput input() const {
    DriveInput in;
    in.now = now;
    if (position_known) in.position_mm = std::llround(car.position_mm);
    in.inputs = inputs;
    in.link_ok = link_ok;
    in.zsw = zsw;
    in.actual_percent = actual;
    in.replies = replies;
    return in;
  }

  /// One exchange: tick, the telegram reaches the drive (when the link works), the reply comes
  /// back, the car moves.
  DriveOutput exchange() {
    const DriveInput in = input();
    const DriveOutput out = travel.tick(floors, in);
    seen_positions.push_back(in.position_mm);
    outputs.push_back(out);
    phases.push_back(travel.phase());
    if (drive_hears) drive.receive(out.stw, out.setpoint_percent, kPeriod);
    if (link_ok) {
      zsw = drive.zsw();
      actual = drive.actual();
      ++replies;
    }
    car.advance(drive.actual(), out.brake_open, kPeriod);
    now += kPeriod;
    TravelEvent e;
    while (travel.poll_event(e)) events.push_back(e);
    check_rules(in, out);
    return out;
  }

  /// Exchanges until `done` or `limit_ms` of fake time; false on the limit.
  bool run_until(const std::function<bool()>& done, int limit_ms = 60000) {
    const MonoTime end = now + milliseconds(limit_ms);
    while (now < end) {
      exchange();
      if (done()) return true;
    }
    return false;
  }
  bool run_idle() {
    return run_until([&] { return !travel.busy(); });
  }

  /// The rules that hold after every tick, whatever the state.
  void check_rules(const DriveInput& in, const DriveOutput& out) {
    // Every STW carries bit 10 (C 5.2.1 table 5.4: without it the process data are invalid).
    EXPECT_NE(out.stw & stw::kControlByPlc, 0) << "t=" << now.count();
    // The brake is open only while the drive reported operation enabled (documented mapping).
    if (out.brake_open) {
      EXPECT_NE(in.zsw & zsw::kOperationEnabled, 0) << "t=" << now.count();
      EXPECT_TRUE(out.contactors_on);
    }
    // No ON while the safety chain is open.
    if (!inputs.safety_chain_closed) {
      EXPECT_EQ(out.stw & stw::kOn, 0);
    }
    if (out.setpoint_percent != 0.0) {
      EXPECT_EQ(out.stw, control::kRun);
    }
  }

  /// The STW values in order with repeats collapsed, from output `from` on.
  std::vector<std::uint16_t> stw_runs(std::size_t from = 0) const {
    std::vector<std::uint16_t> runs;
    for (std::size_t i = from; i < outputs.size(); ++i) {
      if (runs.empty() || runs.back() != outputs[i].stw) runs.push_back(outputs[i].stw);
    }
    return runs;
  }
  std::vector<TravelEvent> take_events() {
    std::vector<TravelEvent> out;
    out.swap(events);
    return out;
  }

  LiftTravel travel;
  lift::FloorTable floors;
  FakeDrive drive;
  Car car;
  lift::Inputs inputs;
  bool position_known = true;
  bool link_ok = true;
  bool drive_hears = true;
  MonoTime now{milliseconds(1000)};
  std::uint16_t zsw = 0;
  double actual = 0.0;
  std::uint64_t replies = 0;
  std::vector<DriveOutput> outputs;
  std::vector<Phase> phases;
  std::vector<std::optional<std::int64_t>> seen_positions;  ///< what each tick saw
  std::vector<TravelEvent> events;
};

TEST(LiftTravel, IdleSendsOff1AndTakesTheDriveOutOfItsInhibit) {
  Rig rig;
  EXPECT_EQ(rig.outputs.back().stw, 0x047E);
  EXPECT_EQ(decode_status(rig.zsw), ProfileState::ReadyToSwitchOn);
  EXPECT_FALSE(rig.outputs.back().brake_open);
  EXPECT_FALSE(rig.outputs.back().contactors_on);
}

TEST(LiftTravel, TravelUpRunsThroughEveryPhaseAndLandsWithinTolerance) {
  Rig rig;
  const std::size_t from = rig.outputs.size();
  ASSERT_EQ(rig.travel.start_travel(rig.floors, 2, SpeedName::V4, rig.input()), lift::Cause::None);
  ASSERT_TRUE(rig.run_idle());
  EXPECT_LE(std::abs(rig.car.position_mm - 6000.0), 5.0) << rig.car.position_mm;
  // Contactors and OFF1, then the run word until the brake is applied, then OFF1 again.
  EXPECT_EQ(rig.stw_runs(from), (std::vector<std::uint16_t>{0x047E, 0x047F, 0x047E}));
  // Phases in order.
  std::vector<Phase> seen;
  for (std::size_t i = from; i < rig.phases.size(); ++i) {
    if (seen.empty() || seen.back() != rig.phases[i]) seen.push_back(rig.phases[i]);
  }
  EXPECT_EQ(seen, (std::vector<Phase>{Phase::Contactors, Phase::SwitchOn, Phase::BrakeRelease,
                                      Phase::Run, Phase::Crawl, Phase::Stopping, Phase::BrakeApply,
                                      Phase::SwitchOff, Phase::Idle}));
  // Setpoints: V4 (100 %) while running, V0 (5 %) crawling, 0 otherwise.
  for (std::size_t i = from; i < rig.outputs.size(); ++i) {
    const double expected = rig.phases[i] == Phase::Run     ? 100.0
                            : rig.phases[i] == Phase::Crawl ? 5.0
                                                            : 0.0;
    EXPECT_EQ(rig.outputs[i].setpoint_percent, expected) << i;
  }
  // The brake fell before OFF1: no output with OFF1 and the brake open.
  for (std::size_t i = from; i < rig.outputs.size(); ++i) {
    if (rig.outputs[i].stw == 0x047E) {
      EXPECT_FALSE(rig.outputs[i].brake_open) << i;
    }
  }
  const auto ev = rig.take_events();
  ASSERT_EQ(ev.size(), 2U);
  EXPECT_EQ(ev[0].type, TravelEvent::Type::Started);
  EXPECT_EQ(ev[0].direction, lift::Direction::Up);
  EXPECT_EQ(ev[1].type, TravelEvent::Type::Finished);
  EXPECT_EQ(ev[1].floor, 2U);
  EXPECT_EQ(rig.travel.current_floor(), 2U);
  EXPECT_EQ(rig.outputs.back().stw, 0x047E);
  EXPECT_FALSE(rig.outputs.back().contactors_on);
}

TEST(LiftTravel, TravelDownLandsWithinToleranceWithANegativeSetpoint) {
  Rig rig;
  rig.car.position_mm = 9000.0;
  rig.travel.set_current_floor(3);
  const std::size_t from = rig.outputs.size();
  ASSERT_EQ(rig.travel.start_travel(rig.floors, 1, SpeedName::V4, rig.input()), lift::Cause::None);
  ASSERT_TRUE(rig.run_idle());
  EXPECT_LE(std::abs(rig.car.position_mm - 3000.0), 5.0) << rig.car.position_mm;
  bool saw_run = false;
  for (std::size_t i = from; i < rig.outputs.size(); ++i) {
    if (rig.phases[i] == Phase::Run) {
      EXPECT_EQ(rig.outputs[i].setpoint_percent, -100.0);
      saw_run = true;
    }
  }
  EXPECT_TRUE(saw_run);
  const auto ev = rig.take_events();
  ASSERT_EQ(ev.size(), 2U);
  EXPECT_EQ(ev[1].type, TravelEvent::Type::Finished);
  EXPECT_EQ(ev[1].floor, 1U);
}

TEST(LiftTravel, SlowdownToCrawlAtEachSpeedsDistance) {
  struct Case {
    SpeedName speed;
    double percent;
    std::uint32_t slowdown_mm;
  };
  for (const Case c : {Case{SpeedName::V4, 100.0, 700}, Case{SpeedName::V3, 60.0, 400}}) {
    Rig rig;
    ASSERT_EQ(rig.travel.start_travel(rig.floors, 3, c.speed, rig.input()), lift::Cause::None);
    ASSERT_TRUE(rig.run_until([&] { return rig.travel.phase() == Phase::Crawl; }));
    // The crawl starts in the first exchange that sees the car within the slowdown distance,
    // at the travel's full speed until then.
    const std::size_t i = rig.phases.size() - 1;
    const std::int64_t remaining = 9000 - rig.seen_positions[i].value();
    const std::int64_t before = 9000 - rig.seen_positions[i - 1].value();
    EXPECT_LE(remaining, c.slowdown_mm) << to_string(c.speed);
    EXPECT_GT(before, c.slowdown_mm) << to_string(c.speed);
    EXPECT_LE(before - remaining, std::llround(c.percent / 100.0 * 1000.0 * 0.010) + 1);
    EXPECT_EQ(rig.outputs[i - 1].setpoint_percent, c.percent);
    EXPECT_EQ(rig.outputs[i].setpoint_percent, 5.0);
    ASSERT_TRUE(rig.run_idle());
    EXPECT_LE(std::abs(rig.car.position_mm - 9000.0), 5.0) << to_string(c.speed);
  }
}

TEST(LiftTravel, ShaftSignalsGiveTheDecelerationPointAndTheLevel) {
  LiftTravelConfig config = test_config();
  config.reference = Reference::ShaftSignals;
  Rig rig(config);
  rig.position_known = false;
  ASSERT_EQ(rig.travel.start_travel(rig.floors, 1, SpeedName::V3, rig.input()), lift::Cause::None);
  ASSERT_TRUE(rig.run_until([&] { return rig.travel.phase() == Phase::Run; }));
  // The V3 point of another speed does not count; the travel's own does.
  rig.inputs.decel_up[3] = true;  // V4
  rig.exchange();
  EXPECT_EQ(rig.travel.phase(), Phase::Run);
  rig.inputs.decel_up[2] = true;  // V3
  rig.exchange();
  EXPECT_EQ(rig.travel.phase(), Phase::Crawl);
  EXPECT_EQ(rig.outputs.back().setpoint_percent, 5.0);
  for (int i = 0; i < 20; ++i) rig.exchange();
  EXPECT_EQ(rig.travel.phase(), Phase::Crawl);
  rig.inputs.level_zone = true;
  rig.exchange();
  EXPECT_EQ(rig.travel.phase(), Phase::Stopping);
  EXPECT_EQ(rig.outputs.back().setpoint_percent, 0.0);
  ASSERT_TRUE(rig.run_idle());
  EXPECT_EQ(rig.travel.current_floor(), 1U);
}

TEST(LiftTravel, InspectionIsHoldToRunAtViBothWaysWithV0InTheEndZone) {
  Rig rig;
  rig.car.position_mm = 4000.0;
  rig.inputs.inspection = true;
  rig.inputs.doors_locked = false;  // inspection: the safety chain holds the door contacts
  ASSERT_EQ(rig.travel.inspect(rig.floors, lift::Direction::Up, rig.input()), lift::Cause::None);
  ASSERT_TRUE(rig.run_until([&] { return rig.travel.phase() == Phase::Run; }));
  rig.exchange();
  EXPECT_EQ(rig.outputs.back().setpoint_percent, 30.0) << "VI";
  rig.inputs.end_zone_top = true;
  rig.exchange();
  EXPECT_EQ(rig.outputs.back().setpoint_percent, 5.0) << "V0 in the top end zone";
  rig.inputs.end_zone_top = false;
  for (int i = 0; i < 50; ++i) {
    ASSERT_EQ(rig.travel.inspect(rig.floors, lift::Direction::Up, rig.input()), lift::Cause::None);
    rig.exchange();
  }
  const double moved_to = rig.car.position_mm;
  EXPECT_GT(moved_to, 4000.0);
  // Released: the normal stop (setpoint 0, standstill, brake, OFF1).
  ASSERT_EQ(rig.travel.inspect(rig.floors, lift::Direction::None, rig.input()), lift::Cause::None);
  rig.exchange();
  EXPECT_EQ(rig.travel.phase(), Phase::Stopping);
  EXPECT_EQ(rig.outputs.back().setpoint_percent, 0.0);
  ASSERT_TRUE(rig.run_idle());
  // From VI (300 mm/s) on the 100 %/s ramp: 0.3 s, about 45 mm.
  EXPECT_LT(rig.car.position_mm - moved_to, 55.0) << "stopped on the drive's ramp";
  // Down, at -VI.
  ASSERT_EQ(rig.travel.inspect(rig.floors, lift::Direction::Down, rig.input()), lift::Cause::None);
  ASSERT_TRUE(rig.run_until([&] { return rig.travel.phase() == Phase::Run; }));
  rig.exchange();
  EXPECT_EQ(rig.outputs.back().setpoint_percent, -30.0);
  ASSERT_EQ(rig.travel.inspect(rig.floors, lift::Direction::None, rig.input()), lift::Cause::None);
  ASSERT_TRUE(rig.run_idle());
  const auto ev = rig.take_events();
  ASSERT_EQ(ev.size(), 4U);
  EXPECT_EQ(ev[1].type, TravelEvent::Type::Finished);
  EXPECT_EQ(ev[2].direction, lift::Direction::Down);
  EXPECT_EQ(ev[3].type, TravelEvent::Type::Finished);
}

TEST(LiftTravel, InspectionStopsAtTheTerminalLevelAndDoesNotRestartThere) {
  Rig rig;
  rig.car.position_mm = 8800.0;
  rig.inputs.inspection = true;
  ASSERT_TRUE(rig.run_until([&] {
    (void)rig.travel.inspect(rig.floors, lift::Direction::Up, rig.input());
    return rig.car.position_mm >= 9000.0 && !rig.travel.busy();
  }));
  // VI (300 mm/s) ramps down in 0.3 s: about 45 mm past the level (the limit switch's margin).
  EXPECT_LT(rig.car.position_mm, 9060.0);
  const std::size_t n = rig.events.size();
  for (int i = 0; i < 100; ++i) {
    (void)rig.travel.inspect(rig.floors, lift::Direction::Up, rig.input());
    rig.exchange();
  }
  EXPECT_EQ(rig.events.size(), n) << "held at the top: no new run";
  EXPECT_FALSE(rig.travel.busy());
}

TEST(LiftTravel, RelevellingAtVnBackIntoTheLevel) {
  Rig rig;
  rig.car.position_mm = 6030.0;  // sank... or rose: 30 mm above floor 2
  rig.travel.set_current_floor(2);
  rig.inputs.doors_locked = false;
  rig.inputs.door_zone_bridge = true;  // relevelling with open doors, door zone bridged
  ASSERT_EQ(rig.travel.start_relevel(rig.floors, 2, lift::Direction::None, rig.input()),
            lift::Cause::None);
  ASSERT_TRUE(rig.run_until([&] { return rig.travel.phase() == Phase::Run; }));
  rig.exchange();
  EXPECT_EQ(rig.outputs.back().setpoint_percent, -3.0) << "VN down";
  ASSERT_TRUE(rig.run_idle());
  EXPECT_LE(std::abs(rig.car.position_mm - 6000.0), 5.0) << rig.car.position_mm;
  const auto ev = rig.take_events();
  ASSERT_EQ(ev.size(), 2U);
  EXPECT_EQ(ev[0].kind, TravelKind::Relevel);
  EXPECT_EQ(ev[1].type, TravelEvent::Type::Finished);
}

TEST(LiftTravel, SafetyChainOpenIsOff2InTheVeryNextTelegramWithTheBrakeFalling) {
  Rig rig;
  ASSERT_EQ(rig.travel.start_travel(rig.floors, 3, SpeedName::V4, rig.input()), lift::Cause::None);
  ASSERT_TRUE(rig.run_until([&] { return rig.car.position_mm > 2000.0; }));
  ASSERT_TRUE(rig.outputs.back().brake_open);
  rig.take_events();
  rig.inputs.safety_chain_closed = false;
  const DriveOutput out = rig.exchange();
  EXPECT_EQ(out.stw, 0x0404) << "OFF2, C 5.2.1 table 5.2";
  EXPECT_FALSE(out.brake_open);
  EXPECT_FALSE(out.contactors_on);
  EXPECT_EQ(out.setpoint_percent, 0.0);
  EXPECT_EQ(rig.drive.stw_log.back(), 0x0404);
  for (int i = 0; i < 50; ++i) EXPECT_EQ(rig.exchange().stw, 0x0404) << "held while open";
  const auto ev = rig.take_events();
  ASSERT_EQ(ev.size(), 1U) << "reported once";
  EXPECT_EQ(ev[0].type, TravelEvent::Type::Aborted);
  EXPECT_EQ(ev[0].cause, lift::Cause::SafetyChainOpen);
  EXPECT_EQ(rig.travel.start_travel(rig.floors, 0, SpeedName::V4, rig.input()),
            lift::Cause::SafetyChainOpen);
  // Closed again: OFF1, the drive goes from inhibit to ready to switch on, a travel runs.
  rig.inputs.safety_chain_closed = true;
  EXPECT_EQ(rig.exchange().stw, 0x047E);
  rig.exchange();
  ASSERT_EQ(rig.travel.start_travel(rig.floors, 3, SpeedName::V4, rig.input()), lift::Cause::None);
  ASSERT_TRUE(rig.run_idle());
  EXPECT_LE(std::abs(rig.car.position_mm - 9000.0), 5.0);
}

TEST(LiftTravel, DoorsUnlockedIsOff2AndInputsLostIsAQuickStopOnTheBrake) {
  {
    Rig rig;
    ASSERT_EQ(rig.travel.start_travel(rig.floors, 3, SpeedName::V4, rig.input()),
              lift::Cause::None);
    ASSERT_TRUE(rig.run_until([&] { return rig.car.position_mm > 2000.0; }));
    rig.inputs.doors_locked = false;
    const DriveOutput out = rig.exchange();
    EXPECT_EQ(out.stw, 0x0404);
    EXPECT_FALSE(out.brake_open);
    ASSERT_FALSE(rig.events.empty());
    EXPECT_EQ(rig.events.back().cause, lift::Cause::DoorsNotLocked);
  }
  {
    Rig rig;
    ASSERT_EQ(rig.travel.start_travel(rig.floors, 3, SpeedName::V4, rig.input()),
              lift::Cause::None);
    ASSERT_TRUE(rig.run_until([&] { return rig.car.position_mm > 2000.0; }));
    rig.inputs.valid = false;
    DriveOutput out = rig.exchange();
    EXPECT_EQ(out.stw, 0x040A) << "OFF3";
    EXPECT_TRUE(out.brake_open) << "the drive brakes the car on its quick-stop ramp";
    ASSERT_FALSE(rig.events.empty());
    EXPECT_EQ(rig.events.back().cause, lift::Cause::InputsLost);
    // The brake falls at standstill; the halt ends when the drive reports its pulses off.
    ASSERT_TRUE(rig.run_until([&] { return !rig.outputs.back().brake_open; }));
    EXPECT_LE(std::abs(rig.actual), 0.5) << "standstill";
    ASSERT_TRUE(rig.run_idle());
    EXPECT_EQ(rig.events.size(), 2U) << "reported once";
  }
}

TEST(LiftTravel, PositionLostIsAQuickStop) {
  Rig rig;
  ASSERT_EQ(rig.travel.start_travel(rig.floors, 2, SpeedName::V4, rig.input()), lift::Cause::None);
  ASSERT_TRUE(rig.run_until([&] { return rig.travel.phase() == Phase::Run; }));
  rig.position_known = false;
  EXPECT_EQ(rig.exchange().stw, 0x040A);
  EXPECT_EQ(rig.events.back().cause, lift::Cause::PositionLost);
}

TEST(LiftTravel, LinkFaultEndsTheTravelAndHoldsOff2UntilTheDriveIsSeenOff) {
  Rig rig;
  ASSERT_EQ(rig.travel.start_travel(rig.floors, 3, SpeedName::V4, rig.input()), lift::Cause::None);
  ASSERT_TRUE(rig.run_until([&] { return rig.car.position_mm > 2000.0; }));
  rig.link_ok = false;  // the controller's verdict after link_fault_replies failures
  rig.drive_hears = false;
  DriveOutput out = rig.exchange();
  EXPECT_EQ(out.stw, 0x0404);
  EXPECT_FALSE(out.brake_open);
  EXPECT_EQ(rig.events.back().cause, lift::Cause::LinkDown);
  for (int i = 0; i < 10; ++i) EXPECT_EQ(rig.exchange().stw, 0x0404);
  // The link returns: the first telegram the drive hears is OFF2.
  rig.drive_hears = true;
  rig.link_ok = true;
  EXPECT_EQ(rig.exchange().stw, 0x0404);
  EXPECT_EQ(rig.drive.stw_log.back(), 0x0404);
  EXPECT_EQ(rig.exchange().stw, 0x047E) << "pulses off reported: back to OFF1";
}

TEST(LiftTravel, DriveFaultEndsTheTravelAndNeedsTheAcknowledgeEdge) {
  Rig rig;
  ASSERT_EQ(rig.travel.start_travel(rig.floors, 3, SpeedName::V4, rig.input()), lift::Cause::None);
  ASSERT_TRUE(rig.run_until([&] { return rig.car.position_mm > 2000.0; }));
  rig.drive.trip();
  rig.exchange();  // the telegram whose reply shows the fault
  const DriveOutput out = rig.exchange();
  EXPECT_FALSE(out.brake_open);
  EXPECT_FALSE(out.contactors_on);
  ASSERT_FALSE(rig.events.empty());
  EXPECT_EQ(rig.events.back().type, TravelEvent::Type::Aborted);
  EXPECT_EQ(rig.events.back().cause, lift::Cause::DriveFault);
  EXPECT_EQ(rig.travel.start_travel(rig.floors, 0, SpeedName::V4, rig.input()),
            lift::Cause::DriveFault);
  // The cause goes, but the drive stays in fault until acknowledged (table 5.5 bit 3).
  rig.drive.clear_fault_cause();
  for (int i = 0; i < 10; ++i) rig.exchange();
  EXPECT_EQ(rig.travel.start_travel(rig.floors, 0, SpeedName::V4, rig.input()),
            lift::Cause::DriveFault);
  const std::size_t from = rig.drive.stw_log.size();
  rig.travel.acknowledge();
  for (int i = 0; i < 10; ++i) rig.exchange();
  // The drive saw bit 7 at 0, then 1 (the rising edge), then 0 again.
  std::vector<bool> bit7;
  for (std::size_t i = from; i < rig.drive.stw_log.size(); ++i) {
    const bool b = (rig.drive.stw_log[i] & stw::kFaultAcknowledge) != 0;
    if (bit7.empty() || bit7.back() != b) bit7.push_back(b);
  }
  EXPECT_EQ(bit7, (std::vector<bool>{false, true, false}));
  EXPECT_EQ(rig.zsw & zsw::kFault, 0);
  ASSERT_EQ(rig.travel.start_travel(rig.floors, 0, SpeedName::V4, rig.input()), lift::Cause::None);
  ASSERT_TRUE(rig.run_idle());
  EXPECT_LE(std::abs(rig.car.position_mm), 5.0);
}

TEST(LiftTravel, DriveThatDoesNotSwitchOnEndsTheStartAndIsAFaultUntilAcknowledged) {
  Rig rig;
  rig.drive.never_enables = true;
  ASSERT_EQ(rig.travel.start_travel(rig.floors, 1, SpeedName::V4, rig.input()), lift::Cause::None);
  ASSERT_TRUE(rig.run_idle());
  const auto ev = rig.take_events();
  ASSERT_EQ(ev.size(), 2U);
  EXPECT_EQ(ev[1].cause, lift::Cause::DriveDidNotStart);
  EXPECT_EQ(rig.car.position_mm, 0.0);
  for (const DriveOutput& out : rig.outputs) EXPECT_FALSE(out.brake_open);
  EXPECT_EQ(rig.travel.profile().supervision(), Supervision::NotSwitchedOn);
  EXPECT_EQ(rig.travel.start_travel(rig.floors, 1, SpeedName::V4, rig.input()),
            lift::Cause::DriveFault);
  rig.travel.acknowledge();
  rig.drive.never_enables = false;
  rig.exchange();
  ASSERT_EQ(rig.travel.start_travel(rig.floors, 1, SpeedName::V4, rig.input()), lift::Cause::None);
  ASSERT_TRUE(rig.run_idle());
  EXPECT_LE(std::abs(rig.car.position_mm - 3000.0), 5.0);
}

TEST(LiftTravel, MotorRunTimeLimiterCoasts) {
  LiftTravelConfig config = test_config();
  config.max_travel_ms = 2000;
  Rig rig(config);
  ASSERT_EQ(rig.travel.start_travel(rig.floors, 3, SpeedName::V4, rig.input()), lift::Cause::None);
  ASSERT_TRUE(rig.run_idle());
  ASSERT_EQ(rig.events.size(), 2U);
  EXPECT_EQ(rig.events[1].cause, lift::Cause::TravelTimeout);
  EXPECT_EQ(rig.events[1].at - rig.events[0].at, milliseconds(2010));
  EXPECT_EQ(rig.drive.stw_log.back(), 0x047E);
  bool coasted = false;
  for (std::uint16_t stw : rig.drive.stw_log) coasted = coasted || stw == 0x0404;
  EXPECT_TRUE(coasted);
}

TEST(LiftTravel, CrawlThatFindsNoLevelEndsWithAQuickStop) {
  LiftTravelConfig config = test_config();
  config.reference = Reference::ShaftSignals;
  config.crawl_timeout_ms = 1000;
  Rig rig(config);
  rig.position_known = false;
  ASSERT_EQ(rig.travel.start_travel(rig.floors, 1, SpeedName::V4, rig.input()), lift::Cause::None);
  ASSERT_TRUE(rig.run_until([&] { return rig.travel.phase() == Phase::Run; }));
  rig.inputs.decel_up[3] = true;  // V4's point; the level zone never comes
  ASSERT_TRUE(rig.run_until([&] { return rig.travel.phase() == Phase::Crawl; }));
  const MonoTime crawl_from = rig.now - kPeriod;
  ASSERT_TRUE(rig.run_until([&] { return rig.travel.phase() == Phase::Halt; }));
  EXPECT_EQ(rig.now - kPeriod - crawl_from, milliseconds(1000));
  EXPECT_EQ(rig.outputs.back().stw, 0x040A) << "OFF3";
  EXPECT_EQ(rig.events.back().cause, lift::Cause::LevelNotReached);
  ASSERT_TRUE(rig.run_idle());
}

TEST(LiftTravel, TheRunTimeLimiterDoesNotActOnInspection) {
  LiftTravelConfig config = test_config();
  config.max_travel_ms = 1000;
  Rig rig(config);
  rig.inputs.inspection = true;
  for (int i = 0; i < 300; ++i) {
    ASSERT_EQ(rig.travel.inspect(rig.floors, lift::Direction::Up, rig.input()), lift::Cause::None);
    rig.exchange();
  }
  EXPECT_EQ(rig.travel.kind(), TravelKind::Inspection);
  EXPECT_EQ(rig.travel.phase(), Phase::Run);
  EXPECT_EQ(rig.events.size(), 1U);
}

TEST(LiftTravel, StopRetargetsTheNextReachableFloorAhead) {
  Rig rig;
  ASSERT_EQ(rig.travel.start_travel(rig.floors, 3, SpeedName::V4, rig.input()), lift::Cause::None);
  ASSERT_TRUE(rig.run_until([&] { return rig.car.position_mm > 1500.0; }));
  // Floor 1 (3000) is still beyond V4's 700 mm: the car stops there.
  EXPECT_EQ(rig.travel.stop(rig.floors, rig.input()), std::optional<std::size_t>(1));
  ASSERT_TRUE(rig.run_idle());
  EXPECT_LE(std::abs(rig.car.position_mm - 3000.0), 5.0);
  EXPECT_EQ(rig.events.back().type, TravelEvent::Type::Finished);
  EXPECT_EQ(rig.events.back().floor, 1U);
}

TEST(LiftTravel, StopBeforeTheCarMovesSwitchesOffAtOnce) {
  Rig rig;
  ASSERT_EQ(rig.travel.start_travel(rig.floors, 3, SpeedName::V4, rig.input()), lift::Cause::None);
  rig.exchange();
  EXPECT_EQ(rig.travel.stop(rig.floors, rig.input()), std::nullopt);
  EXPECT_EQ(rig.exchange().stw, 0x047E);
  EXPECT_EQ(rig.events.back().cause, lift::Cause::StopRequested);
  EXPECT_FALSE(rig.travel.busy());
}

TEST(LiftTravel, RefusalsAtStart) {
  Rig rig;
  EXPECT_EQ(rig.travel.start_travel(rig.floors, 1, SpeedName::V7, rig.input()),
            lift::Cause::SpeedNotConfigured);
  EXPECT_EQ(rig.travel.start_travel(rig.floors, 1, SpeedName::V0, rig.input()),
            lift::Cause::SpeedNotConfigured);
  rig.drive.warning = true;
  rig.exchange();
  EXPECT_EQ(rig.travel.start_travel(rig.floors, 1, SpeedName::V4, rig.input()),
            lift::Cause::AdvanceWarning);
  rig.drive.warning = false;
  rig.drive.plc_control = false;
  rig.exchange();
  EXPECT_EQ(rig.travel.start_travel(rig.floors, 1, SpeedName::V4, rig.input()),
            lift::Cause::DriveNotReady);
  rig.drive.plc_control = true;
  rig.exchange();
  rig.link_ok = false;
  EXPECT_EQ(rig.travel.start_travel(rig.floors, 1, SpeedName::V4, rig.input()),
            lift::Cause::LinkDown);
  rig.link_ok = true;
  rig.position_known = false;
  EXPECT_EQ(rig.travel.start_travel(rig.floors, 1, SpeedName::V4, rig.input()),
            lift::Cause::PositionLost);
  rig.position_known = true;
  rig.inputs.doors_locked = false;
  EXPECT_EQ(rig.travel.start_travel(rig.floors, 1, SpeedName::V4, rig.input()),
            lift::Cause::DoorsNotLocked);
  EXPECT_TRUE(rig.events.empty());
}

// ---- the learning travel's legs (lift/learning_travel.hpp) ----

/// The phases a run went through from output `from` on, repeats collapsed.
std::vector<Phase> phase_runs(const Rig& rig, std::size_t from) {
  std::vector<Phase> seen;
  for (std::size_t i = from; i < rig.phases.size(); ++i) {
    if (seen.empty() || seen.back() != rig.phases[i]) seen.push_back(rig.phases[i]);
  }
  return seen;
}

TEST(LiftTravel, LearningLegUpCrawlsAtV0ThroughTheZonesAndEndsByPosition) {
  // The issue: "the crawl setpoint on a USS drive", whatever the reference; a level zone or a
  // deceleration point on the way stops no learning leg.
  for (const Reference reference : {Reference::Position, Reference::ShaftSignals}) {
    LiftTravelConfig config = test_config();
    config.reference = reference;
    Rig rig(config);
    rig.car.position_mm = -300.0;
    const std::size_t from = rig.outputs.size();
    ASSERT_EQ(rig.travel.start_learning(1100, lift::Direction::Up, SpeedName::V4, rig.input()),
              lift::Cause::None);
    EXPECT_EQ(rig.travel.kind(), TravelKind::Learn);
    EXPECT_EQ(rig.travel.target(), std::nullopt) << "a leg goes to no floor";
    rig.inputs.level_zone = true;
    rig.inputs.decel_up[3] = true;
    ASSERT_TRUE(rig.run_idle());
    // Stops on the stop lead (2 mm) before the leg's end: within the fake drive's 1.25 mm ramp.
    EXPECT_LE(std::abs(rig.car.position_mm - 1100.0), 2.0) << rig.car.position_mm;
    EXPECT_EQ(
        phase_runs(rig, from),
        (std::vector<Phase>{Phase::Contactors, Phase::SwitchOn, Phase::BrakeRelease, Phase::Run,
                            Phase::Stopping, Phase::BrakeApply, Phase::SwitchOff, Phase::Idle}));
    for (std::size_t i = from; i < rig.outputs.size(); ++i) {
      const double expected = rig.phases[i] == Phase::Run ? 5.0 : 0.0;  // V0 = 5 %
      EXPECT_EQ(rig.outputs[i].setpoint_percent, expected) << i;
    }
    const auto ev = rig.take_events();
    ASSERT_EQ(ev.size(), 2U);
    EXPECT_EQ(ev[0].kind, TravelKind::Learn);
    EXPECT_EQ(ev[1].type, TravelEvent::Type::Finished);
    EXPECT_EQ(rig.travel.current_floor(), 0U) << "the floor nearest where the leg ended";
  }
}

TEST(LiftTravel, LearningLegDownApproachesAtTheFastestSpeedThenCrawls) {
  Rig rig;
  rig.car.position_mm = 3000.0;
  const std::size_t from = rig.outputs.size();
  ASSERT_EQ(rig.travel.start_learning(-300, lift::Direction::Down, SpeedName::V4, rig.input()),
            lift::Cause::None);
  ASSERT_TRUE(rig.run_idle());
  EXPECT_LE(std::abs(rig.car.position_mm + 300.0), 2.0) << rig.car.position_mm;
  EXPECT_EQ(phase_runs(rig, from),
            (std::vector<Phase>{Phase::Contactors, Phase::SwitchOn, Phase::BrakeRelease, Phase::Run,
                                Phase::Crawl, Phase::Stopping, Phase::BrakeApply, Phase::SwitchOff,
                                Phase::Idle}));
  for (std::size_t i = from; i < rig.outputs.size(); ++i) {
    const double expected = rig.phases[i] == Phase::Run     ? -100.0
                            : rig.phases[i] == Phase::Crawl ? -5.0
                                                            : 0.0;
    EXPECT_EQ(rig.outputs[i].setpoint_percent, expected) << i;
    // V4's slowdown distance (700 mm) before the leg's end: the crawl, by position.
    if (rig.phases[i] == Phase::Run && rig.seen_positions[i]) {
      EXPECT_GT(*rig.seen_positions[i], -300 + 700) << i;
    }
  }
}

TEST(LiftTravel, LearningLegUpEndsWhereTheRunOutSays) {
  Rig rig;
  rig.car.position_mm = -300.0;
  ASSERT_EQ(rig.travel.start_learning(1100, lift::Direction::Up, SpeedName::V4, rig.input()),
            lift::Cause::None);
  ASSERT_TRUE(rig.run_until([&] { return rig.car.position_mm > 500.0; }));
  EXPECT_TRUE(rig.travel.end_learning_at(620));
  ASSERT_TRUE(rig.run_idle());
  EXPECT_LE(std::abs(rig.car.position_mm - 620.0), 2.0) << rig.car.position_mm;
  EXPECT_FALSE(rig.travel.end_learning_at(700)) << "no leg runs";
  ASSERT_EQ(rig.travel.start_travel(rig.floors, 3, SpeedName::V4, rig.input()), lift::Cause::None);
  EXPECT_FALSE(rig.travel.end_learning_at(700)) << "a travel has its floor";
}

TEST(LiftTravel, AFaultMidLegEndsItAsItEndsATravel) {
  struct Case {
    const char* legend;
    std::function<void(Rig&)> fault;
    std::uint16_t stw;  // the next telegram (C 5.2.1 table 5.2)
    lift::Cause cause;
  };
  const Case cases[] = {
      {"safety chain: OFF2", [](Rig& r) { r.inputs.safety_chain_closed = false; }, 0x0404,
       lift::Cause::SafetyChainOpen},
      {"doors: OFF2", [](Rig& r) { r.inputs.doors_locked = false; }, 0x0404,
       lift::Cause::DoorsNotLocked},
      {"inputs lost: OFF3", [](Rig& r) { r.inputs.valid = false; }, 0x040A,
       lift::Cause::InputsLost},
      {"position lost: OFF3", [](Rig& r) { r.position_known = false; }, 0x040A,
       lift::Cause::PositionLost},
  };
  for (const Case& c : cases) {
    // The position is needed even where travels read the shaft signals: the leg ends by it.
    LiftTravelConfig config = test_config();
    config.reference = Reference::ShaftSignals;
    Rig rig(config);
    rig.car.position_mm = -300.0;
    ASSERT_EQ(rig.travel.start_learning(1100, lift::Direction::Up, SpeedName::V4, rig.input()),
              lift::Cause::None)
        << c.legend;
    ASSERT_TRUE(rig.run_until([&] { return rig.car.position_mm > 0.0; })) << c.legend;
    rig.take_events();
    c.fault(rig);
    EXPECT_EQ(rig.exchange().stw, c.stw) << c.legend;
    EXPECT_EQ(rig.outputs.back().setpoint_percent, 0.0) << c.legend;
    ASSERT_EQ(rig.events.size(), 1U) << c.legend;
    EXPECT_EQ(rig.events[0].type, TravelEvent::Type::Aborted) << c.legend;
    EXPECT_EQ(rig.events[0].cause, c.cause) << c.legend;
    EXPECT_EQ(rig.travel.start_learning(1100, lift::Direction::Up, SpeedName::V4, rig.input()),
              c.cause)
        << c.legend << ": the same condition refuses a new leg";
  }
}

TEST(LiftTravel, StopEndsALearningLegByTheDrivesRamp) {
  Rig rig;
  rig.car.position_mm = -300.0;
  ASSERT_EQ(rig.travel.start_learning(1100, lift::Direction::Up, SpeedName::V4, rig.input()),
            lift::Cause::None);
  ASSERT_TRUE(rig.run_until([&] { return rig.car.position_mm > 0.0; }));
  EXPECT_EQ(rig.travel.stop(rig.floors, rig.input()), std::nullopt) << "no floor to land at";
  EXPECT_EQ(rig.exchange().setpoint_percent, 0.0);
  EXPECT_EQ(rig.travel.phase(), Phase::Stopping);
  ASSERT_TRUE(rig.run_idle());
  EXPECT_LT(rig.car.position_mm, 10.0) << "stopped on the ramp from V0";
  ASSERT_EQ(rig.events.size(), 2U);
  EXPECT_EQ(rig.events[1].type, TravelEvent::Type::Finished);
}

TEST(LiftTravel, TheLimitsOfALearningLegAllowACrawlThroughIt) {
  // 1400 mm at V0 (50 mm/s) take 28 s: far beyond the crawl's 1 s and the limiter's 2 s, within
  // their learning allowance of 40 ms per mm (56 s) on top.
  LiftTravelConfig config = test_config();
  config.crawl_timeout_ms = 1000;
  config.max_travel_ms = 2000;
  Rig rig(config);
  rig.car.position_mm = -300.0;
  ASSERT_EQ(rig.travel.start_learning(1100, lift::Direction::Up, SpeedName::V4, rig.input()),
            lift::Cause::None);
  ASSERT_TRUE(rig.run_idle());
  ASSERT_EQ(rig.events.size(), 2U);
  EXPECT_EQ(rig.events[1].type, TravelEvent::Type::Finished);
  EXPECT_GT(rig.events[1].at - rig.events[0].at, milliseconds(28000));
  // A car that does not move runs into the limit: the crawl's (1 s + 56 s) first.
  Rig stuck(config);
  stuck.car.rated_mm_per_s = 0.0;
  ASSERT_EQ(stuck.travel.start_learning(1100, lift::Direction::Up, SpeedName::V4, stuck.input()),
            lift::Cause::None);
  ASSERT_TRUE(stuck.run_until([&] { return stuck.travel.phase() == Phase::Halt; }, 70000));
  EXPECT_EQ(stuck.events.back().cause, lift::Cause::LevelNotReached);
}

TEST(LiftTravelConfig, ValidateNamesTheBadField) {
  EXPECT_EQ(validate(LiftTravelConfig{}), std::nullopt);
  LiftTravelConfig c;
  c.speed_percent[speed_index(SpeedName::V0)] = 0.0;
  EXPECT_EQ(validate(c), std::optional<std::string_view>("speeds.V0"));
  c = {};
  c.speed_percent[speed_index(SpeedName::V2)] = 40.0;  // no slowdown distance for it
  EXPECT_EQ(validate(c), std::optional<std::string_view>("slowdown_mm"));
  c.reference = Reference::ShaftSignals;
  EXPECT_EQ(validate(c), std::nullopt);
  c = {};
  c.stop_lead_mm = 1200;
  EXPECT_EQ(validate(c), std::optional<std::string_view>("stop_lead_mm"));
  c = {};
  c.speed_percent[speed_index(SpeedName::V4)] = 250.0;
  EXPECT_EQ(validate(c), std::optional<std::string_view>("speeds"));
}

TEST(SpeedNames, RoundTrip) {
  for (std::size_t i = 0; i < kSpeedCount; ++i) {
    const auto speed = static_cast<SpeedName>(i);
    EXPECT_EQ(parse_speed(to_string(speed)), speed);
  }
  EXPECT_EQ(parse_speed("VF"), std::nullopt);
  EXPECT_EQ(speed_number(SpeedName::V4), 4);
  EXPECT_EQ(speed_number(SpeedName::VN), 0);
}

}  // namespace
}  // namespace liftd::uss
