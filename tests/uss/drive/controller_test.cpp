// The USS controller through a real uss::Master against the fake drive (the Bus of bus.hpp):
// travels, the drive profile on the wire, faults, parameters, calls, relevelling, inspection.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <functional>
#include <optional>
#include <string_view>
#include <vector>

#include "uss/drive/bus.hpp"
#include "uss/drive/controller.hpp"
#include "uss/telegram.hpp"
#include "uss/timing.hpp"

namespace liftd::uss {
namespace {

using namespace test;
using std::chrono::milliseconds;

TEST(UssController, IdleBusShowsTheDriveReadyInTheSnapshot) {
  Bus bus;
  const ControllerSnapshot s = bus.controller.snapshot();
  EXPECT_TRUE(s.port_up);
  EXPECT_TRUE(s.link_ok);
  ASSERT_EQ(s.slave_count, 1U);
  EXPECT_EQ(s.slaves[0].address, kDrive);
  EXPECT_TRUE(s.slaves[0].responding);
  EXPECT_EQ(s.slaves[0].good, 10U);
  EXPECT_EQ(s.stw_sent, 0x047E);
  EXPECT_EQ(s.drive_state, ProfileState::ReadyToSwitchOn);
  EXPECT_EQ(s.zsw, bus.drive.zsw());
  EXPECT_EQ(s.rx.good, 10U);
  EXPECT_EQ(s.cycles, 9U);
  EXPECT_GT(s.expected_cycle_time.count(), 0);
  EXPECT_EQ(s.floor, std::optional<std::size_t>(0));
  EXPECT_FALSE(s.brake_open);
  EXPECT_FALSE(s.quiesced);
  // The drive left its power-up inhibit on our OFF1: both states reported once.
  std::vector<ProfileState> states;
  for (const auto& e : bus.events) {
    if (e.kind == ControllerEvent::Kind::DriveState) states.push_back(e.drive_state);
  }
  EXPECT_EQ(states, (std::vector<ProfileState>{ProfileState::SwitchOnInhibit,
                                               ProfileState::ReadyToSwitchOn}));
  // The first telegram went out before any machine input had come: OFF2 (nothing may switch
  // the drive on while the safety chain is unknown), then OFF1.
  ASSERT_GE(bus.stw_sent.size(), 2U);
  EXPECT_EQ(bus.stw_sent[0], 0x0404);
  EXPECT_EQ(bus.stw_sent[1], 0x047E);
}

// status drive.state reads the snapshot's drive_allows_travel, the drive's side of the travel
// check: a drive in local control (ZSW bit 9 = 0, C 5.2.1) allows none, and a travel is refused
// exactly then.
TEST(UssController, TheSnapshotAllowsATravelExactlyWhenTheDriveTakesControl) {
  Bus bus;
  EXPECT_TRUE(bus.controller.snapshot().drive_allows_travel);
  bus.drive.plc_control = false;
  bus.exchange();
  bus.exchange();
  const ControllerSnapshot local = bus.controller.snapshot();
  EXPECT_FALSE(local.drive_allows_travel);
  EXPECT_TRUE(std::none_of(local.faults.begin(), local.faults.end(), [](bool f) { return f; }))
      << "local control is no fault";
  const auto control_told = [&] {
    std::vector<bool> out;
    for (const auto& e : bus.events) {
      if (e.kind == ControllerEvent::Kind::DriveState) out.push_back(e.plc_control);
    }
    return out;
  };
  ASSERT_FALSE(control_told().empty());
  EXPECT_FALSE(control_told().back()) << "the journal's drive_state line is told of it";
  const CommandReply refused = bus.command(1, TravelCommand{2, SpeedName::V4});
  EXPECT_EQ(refused.code, ReplyCode::NotReady);
  EXPECT_NE(refused.detail.find("local control"), std::string_view::npos) << refused.detail;
  EXPECT_FALSE(bus.controller.snapshot().drive_allows_travel);
  bus.drive.plc_control = true;
  bus.exchange();
  bus.exchange();
  EXPECT_TRUE(bus.controller.snapshot().drive_allows_travel);
  EXPECT_TRUE(control_told().back());
  EXPECT_EQ(bus.command(2, TravelCommand{2, SpeedName::V4}).code, ReplyCode::Ok);
}

TEST(UssController, TravelUpAndDownThroughTheMasterLandWithinTolerance) {
  Bus bus;
  ASSERT_EQ(bus.command(7, TravelCommand{2, SpeedName::V4}).code, ReplyCode::Ok);
  ASSERT_TRUE(bus.run_until([&] { return bus.idle(); }));
  EXPECT_LE(std::abs(bus.car.position_mm - 6000.0), 5.0) << bus.car.position_mm;
  // C 5.2.2: V4 = 100 % went out as 4000 hex.
  EXPECT_NE(std::find(bus.hsw_sent.begin(), bus.hsw_sent.end(), 0x4000), bus.hsw_sent.end());
  ASSERT_EQ(bus.command(8, TravelCommand{0, SpeedName::V3}).code, ReplyCode::Ok);
  ASSERT_TRUE(bus.run_until([&] { return bus.idle(); }));
  EXPECT_LE(std::abs(bus.car.position_mm), 5.0) << bus.car.position_mm;
  // V3 = -60 % downwards.
  EXPECT_NE(std::find(bus.hsw_sent.begin(), bus.hsw_sent.end(), bus.norm.to_raw(-60.0)),
            bus.hsw_sent.end());
  const auto travel = bus.travel_events();
  ASSERT_EQ(travel.size(), 4U);
  EXPECT_EQ(travel[1].travel.type, TravelEvent::Type::Finished);
  EXPECT_EQ(travel[1].travel.floor, 2U);
  EXPECT_EQ(travel[3].travel.type, TravelEvent::Type::Finished);
  EXPECT_EQ(travel[3].travel.floor, 0U);
  EXPECT_EQ(bus.controller.snapshot().floor, std::optional<std::size_t>(0));
  EXPECT_EQ(bus.stw_sent.back(), 0x047E);
}

TEST(UssController, SafetyChainOpenIsOff2InTheVeryNextTelegram) {
  Bus bus;
  bus.post(1, TravelCommand{3, SpeedName::V4});
  ASSERT_TRUE(bus.run_until([&] { return bus.car.position_mm > 2000.0; }));
  ASSERT_TRUE(bus.controller.snapshot().brake_open);
  ASSERT_EQ(bus.stw_sent.back(), 0x047F);
  bus.inputs.safety_chain_closed = false;
  bus.exchange();  // the controller learns it after this exchange
  bus.exchange();
  EXPECT_EQ(bus.stw_sent.back(), 0x0404) << "OFF2 in the next telegram";
  EXPECT_EQ(bus.hsw_sent.back(), 0);
  const ControllerSnapshot s = bus.controller.snapshot();
  EXPECT_FALSE(s.brake_open);
  EXPECT_FALSE(s.contactors_on);
  EXPECT_TRUE(s.faults[static_cast<std::size_t>(FaultCode::SafetyChain)]);
  EXPECT_EQ(bus.count(ControllerEvent::Kind::FaultRaised, FaultCode::SafetyChain), 1);
  const auto travel = bus.travel_events();
  ASSERT_EQ(travel.size(), 2U);
  EXPECT_EQ(travel[1].travel.cause, lift::Cause::SafetyChainOpen);
  EXPECT_EQ(bus.command(2, TravelCommand{0, SpeedName::V4}).code, ReplyCode::Fault);
}

TEST(UssController, ReplyFailuresEndTheTravelAtTheConfiguredCount) {
  Bus bus;
  bus.post(1, TravelCommand{3, SpeedName::V4});
  ASSERT_TRUE(bus.run_until([&] { return bus.car.position_mm > 2000.0; }));
  bus.drive_answers = false;
  bus.exchange();
  bus.exchange();
  EXPECT_EQ(bus.controller.snapshot().phase, Phase::Run) << "two failures: the travel goes on";
  EXPECT_FALSE(bus.controller.snapshot().slaves[0].responding) << "'sendet nicht' (A 5.2.1.1)";
  EXPECT_EQ(bus.travel_events().size(), 1U);
  bus.exchange();  // the third
  auto travel = bus.travel_events();
  ASSERT_EQ(travel.size(), 2U);
  EXPECT_EQ(travel[1].travel.cause, lift::Cause::LinkDown);
  EXPECT_EQ(to_string(travel[1].travel.cause), "link_down");
  EXPECT_EQ(bus.count(ControllerEvent::Kind::FaultRaised, FaultCode::LinkFault), 1);
  EXPECT_FALSE(bus.controller.snapshot().brake_open);
  bus.exchange();
  EXPECT_EQ(bus.stw_sent.back(), 0x0404) << "OFF2 for whenever the drive hears us again";
  bus.drive_answers = true;
  bus.exchange();
  bus.exchange();
  EXPECT_EQ(bus.count(ControllerEvent::Kind::FaultCleared, FaultCode::LinkFault), 1);
  ASSERT_TRUE(bus.run_until([&] { return bus.stw_sent.back() == 0x047E; }, 200));
  EXPECT_EQ(bus.travel_events().size(), 2U) << "reported once";
}

TEST(UssController, AfterALostPortOldStatusWordsStartNothingAndTheLossIsOneFault) {
  Bus bus;
  ASSERT_EQ(bus.controller.snapshot().faults[static_cast<std::size_t>(FaultCode::LinkFault)],
            false);
  // The port goes away and is reopened three times (a flaky adapter); the drive stays silent.
  bus.drive_answers = false;
  for (int i = 0; i < 3; ++i) {
    bus.master.reset_link(bus.now);  // what the runner does on a loss and on a reopen
    bus.controller.on_port(false, bus.now);
    bus.now += milliseconds(200);
    bus.master.reset_link(bus.now);
    bus.controller.on_port(true, bus.now);
    bus.exchange();
  }
  EXPECT_EQ(bus.controller.snapshot().zsw, 0) << "a status word from before the loss is read";
  const CommandReply refused = bus.command(7, TravelCommand{2, SpeedName::V4});
  EXPECT_NE(refused.code, ReplyCode::Ok) << refused.detail;
  EXPECT_EQ(bus.count(ControllerEvent::Kind::FaultRaised, FaultCode::LinkFault), 1);
  EXPECT_EQ(bus.count(ControllerEvent::Kind::FaultCleared, FaultCode::LinkFault), 0)
      << "a reopen without an answer ended the fault";
  // The drive answers on the new port: the fault ends once, a travel may start.
  bus.drive_answers = true;
  bus.exchange();
  bus.exchange();
  EXPECT_EQ(bus.count(ControllerEvent::Kind::FaultCleared, FaultCode::LinkFault), 1);
  ASSERT_TRUE(bus.run_until([&] { return bus.stw_sent.back() == 0x047E; }, 2000));
  EXPECT_EQ(bus.command(8, TravelCommand{2, SpeedName::V4}).code, ReplyCode::Ok);
}

TEST(UssController, DriveFaultEndsTheTravelAndDriveResetAcknowledgesOnARisingEdge) {
  Bus bus;
  bus.post(1, TravelCommand{3, SpeedName::V4});
  ASSERT_TRUE(bus.run_until([&] { return bus.car.position_mm > 2000.0; }));
  bus.drive.trip();
  bus.exchange();
  bus.exchange();
  auto travel = bus.travel_events();
  ASSERT_EQ(travel.size(), 2U);
  EXPECT_EQ(travel[1].travel.cause, lift::Cause::DriveFault);
  EXPECT_EQ(bus.count(ControllerEvent::Kind::FaultRaised, FaultCode::DriveFault), 1);
  EXPECT_EQ(bus.controller.snapshot().drive_state, ProfileState::Fault);
  EXPECT_EQ(bus.command(2, TravelCommand{0, SpeedName::V4}).code, ReplyCode::Fault);
  bus.drive.clear_fault_cause();
  bus.exchange();
  EXPECT_EQ(bus.controller.snapshot().drive_state, ProfileState::Fault) << "needs the edge";
  const std::size_t from = bus.stw_sent.size();
  EXPECT_EQ(bus.command(3, DriveResetCommand{}).code, ReplyCode::Ok);
  for (int i = 0; i < 5; ++i) bus.exchange();
  std::vector<std::uint16_t> words(bus.stw_sent.begin() + static_cast<std::ptrdiff_t>(from),
                                   bus.stw_sent.end());
  // On the wire: the 0 the drive had seen, the 0 once more after the command, the 1, then 0.
  ASSERT_GE(words.size(), 4U);
  EXPECT_EQ(words[0], 0x047E);
  EXPECT_EQ(words[1], 0x047E);
  EXPECT_EQ(words[2], 0x04FE);
  EXPECT_EQ(words[3], 0x047E);
  EXPECT_EQ(bus.count(ControllerEvent::Kind::FaultCleared, FaultCode::DriveFault), 1);
  ASSERT_EQ(bus.command(4, TravelCommand{0, SpeedName::V4}).code, ReplyCode::Ok);
  ASSERT_TRUE(bus.run_until([&] { return bus.idle(); }));
  EXPECT_LE(std::abs(bus.car.position_mm), 5.0);
}

TEST(UssController, ShutdownLandsTheTravelThenQuiesces) {
  Bus bus;
  bus.post(1, TravelCommand{3, SpeedName::V4});
  ASSERT_TRUE(bus.run_until([&] { return bus.car.position_mm > 1500.0; }));
  EXPECT_EQ(bus.command(2, ShutdownCommand{false}).code, ReplyCode::Ok);
  EXPECT_TRUE(bus.controller.snapshot().shutting_down);
  EXPECT_FALSE(bus.controller.snapshot().quiesced);
  ASSERT_TRUE(bus.run_until([&] { return bus.controller.snapshot().quiesced; }));
  EXPECT_LE(std::abs(bus.car.position_mm - 3000.0), 5.0) << "landed at the next floor ahead";
  EXPECT_EQ(bus.stw_sent.back(), 0x047E) << "OFF1";
  const auto travel = bus.travel_events();
  ASSERT_EQ(travel.size(), 2U);
  EXPECT_EQ(travel[1].travel.type, TravelEvent::Type::Finished);
  EXPECT_EQ(bus.command(3, TravelCommand{0, SpeedName::V4}).code, ReplyCode::NotReady);
  EXPECT_TRUE(bus.controller.snapshot().quiesced);
}

TEST(UssController, ForcedShutdownCoastsAtOnce) {
  Bus bus;
  bus.post(1, TravelCommand{3, SpeedName::V4});
  ASSERT_TRUE(bus.run_until([&] { return bus.car.position_mm > 1500.0; }));
  bus.post(2, ShutdownCommand{true});
  bus.exchange();
  bus.exchange();
  EXPECT_EQ(bus.stw_sent.back(), 0x0404);
  const auto travel = bus.travel_events();
  ASSERT_EQ(travel.size(), 2U);
  EXPECT_EQ(travel[1].travel.cause, lift::Cause::ShuttingDown);
  ASSERT_TRUE(bus.run_until([&] { return bus.controller.snapshot().quiesced; }, 500));
}

TEST(UssController, ParameterReadAndMirrorRepliesCarryTheirResults) {
  Bus bus;
  ParameterCommand read;
  read.address = kDrive;
  read.request.id = 1;  // C 4.2.1.1: request parameter value
  read.request.pnu = kParameter;
  bus.post(9, read);
  ASSERT_TRUE(bus.run_until(
      [&] {
        return std::any_of(bus.replies.begin(), bus.replies.end(),
                           [](const CommandReply& r) { return r.tag == 9; });
      },
      200));
  const CommandReply& r = bus.replies.back();
  EXPECT_EQ(r.code, ReplyCode::Ok);
  ASSERT_TRUE(r.pkw.has_value());
  EXPECT_EQ(r.pkw->outcome, PkwResult::Outcome::Done);
  EXPECT_EQ(value(r.pkw->reply, PkwLength::Four, PkwWidth::Word), kParameterValue);

  read.address = 5;
  EXPECT_EQ(bus.command(10, read).code, ReplyCode::BadRequest);

  bus.post(11, MirrorCommand{kDrive});
  ASSERT_TRUE(bus.run_until(
      [&] {
        return std::any_of(bus.replies.begin(), bus.replies.end(),
                           [](const CommandReply& c) { return c.tag == 11; });
      },
      200));
  ASSERT_TRUE(bus.replies.back().mirror.has_value());
  EXPECT_TRUE(bus.replies.back().mirror->ok);
}

TEST(UssController, CallsAreServedInOrder) {
  Bus bus;
  EXPECT_EQ(bus.command(1, CallCommand::adding(1)).code, ReplyCode::Ok);
  EXPECT_EQ(bus.command(2, CallCommand::adding(3)).code, ReplyCode::Ok);
  ASSERT_TRUE(
      bus.run_until([&] { return bus.controller.snapshot().call_count == 0 && bus.idle(); }));
  EXPECT_LE(std::abs(bus.car.position_mm - 9000.0), 5.0);
  std::vector<std::size_t> served;
  for (const auto& e : bus.events) {
    if (e.kind == ControllerEvent::Kind::CallServed) served.push_back(e.floor);
  }
  EXPECT_EQ(served, (std::vector<std::size_t>{1, 3}));
}

TEST(UssController, AutoRelevelBringsASinkingCarBack) {
  Bus bus;
  bus.car.position_mm = 3000.0;
  bus.exchange();
  bus.car.position_mm = 2980.0;  // 20 mm below floor 1: beyond the 15 mm threshold
  ASSERT_TRUE(bus.run_until(
      [&] { return bus.controller.snapshot().travel_kind == TravelKind::Relevel; }, 100));
  ASSERT_TRUE(bus.run_until([&] { return bus.idle(); }));
  EXPECT_LE(std::abs(bus.car.position_mm - 3000.0), 5.0);
}

TEST(UssController, InspectionFromTheApiIsHoldToRun) {
  Bus bus;
  bus.car.position_mm = 4000.0;
  // Held: the command repeats within inspection_hold_ms (500 ms).
  for (int i = 0; i < 150; ++i) {
    if (i % 20 == 0) bus.post(0, InspectionCommand{true, lift::Direction::Up});
    bus.exchange();
  }
  EXPECT_EQ(bus.controller.snapshot().travel_kind, TravelKind::Inspection);
  EXPECT_EQ(bus.hsw_sent.back(), bus.norm.to_raw(30.0)) << "VI";
  const double moved_to = bus.car.position_mm;
  EXPECT_GT(moved_to, 4100.0);
  // Not repeated: the hold runs out and the car stops on the drive's ramp.
  ASSERT_TRUE(bus.run_until([&] { return bus.idle(); }, 2000));
  EXPECT_LT(bus.car.position_mm - moved_to, 300.0 * 0.5 + 60.0);
  EXPECT_EQ(bus.stw_sent.back(), 0x047E);
  const auto travel = bus.travel_events();
  ASSERT_EQ(travel.size(), 2U);
  EXPECT_EQ(travel[1].travel.type, TravelEvent::Type::Finished);
  // A travel is refused while inspection is on.
  EXPECT_EQ(bus.command(5, TravelCommand{0, SpeedName::V4}).code, ReplyCode::NotReady);
}

TEST(UssController, RejectsAConfigItCannotRun) {
  Master master(master_config());
  Car car;
  CarPosition position(car);
  UssControllerConfig config = controller_config();
  config.drive_address = 2;
  EXPECT_THROW(UssController(config, master, position, MonoTime{}), std::invalid_argument);
  config = controller_config();
  config.travel.speed_percent[speed_index(SpeedName::V0)] = 0.0;
  EXPECT_THROW(UssController(config, master, position, MonoTime{}), std::invalid_argument);
  config = controller_config();
  config.floors_mm = {0};
  EXPECT_THROW(UssController(config, master, position, MonoTime{}), std::invalid_argument);
}

// ---- the learning travel ----

/// The shaft's true levels, off the floor table (0, 3000, 6000, 9000); their level zones are
/// 100 mm long and reach the controller as the machine input `zone_level`.
constexpr std::array<std::int64_t, 4> kTrueLevels = {-35, 3025, 6055, 8980};

/// Runs the bus with the level zone input following the car until `done` (fake time).
bool run_shaft(Bus& bus, const std::function<bool()>& done, int limit_ms = 400000) {
  return bus.run_until(
      [&] {
        bus.inputs.level_zone = false;
        for (const std::int64_t level : kTrueLevels) {
          const double at = bus.car.position_mm;
          if (at >= static_cast<double>(level) - 50.0 && at <= static_cast<double>(level) + 50.0) {
            bus.inputs.level_zone = true;
          }
        }
        return done();
      },
      limit_ms);
}

std::optional<CommandReply> reply_to(const Bus& bus, std::uint32_t tag) {
  for (const CommandReply& r : bus.replies) {
    if (r.tag == tag) return r;
  }
  return std::nullopt;
}

TEST(UssController, LearnsTheShaftsLevelsAtTheCrawlAndStopsJustAboveTheTopZone) {
  Bus bus;
  bus.post(7, LearnCommand{});
  ASSERT_TRUE(run_shaft(bus, [&] { return reply_to(bus, 7).has_value(); }));
  const CommandReply reply = *reply_to(bus, 7);
  EXPECT_EQ(reply.code, ReplyCode::Ok) << reply.detail;
  const lift::LearnRecord record = bus.controller.learn_record();
  EXPECT_EQ(record.tag, 7U);
  EXPECT_TRUE(record.judgement.ok());
  ASSERT_EQ(record.zone_count, 4U);
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_NEAR(static_cast<double>(record.zones[i].level_mm()),
                static_cast<double>(kTrueLevels[i]), 2.0)
        << "floor " << i;
  }
  EXPECT_NEAR(bus.car.position_mm, 9030.0 + 20.0, 5.0) << "20 mm beyond the top zone";
  const auto legs = bus.travel_events();
  ASSERT_EQ(legs.size(), 4U);
  for (const auto& e : legs) EXPECT_EQ(e.travel.kind, TravelKind::Learn);
  // At rest beyond the table's top level: no relevelling towards it.
  ASSERT_FALSE(run_shaft(
      bus, [&] { return bus.controller.travel().busy(); }, 2000));
}

TEST(UssController, StopOrAFaultMidLearningEndsItAndNothingIsLearned) {
  struct Case {
    const char* legend;
    std::function<void(Bus&)> act;
    ReplyCode code;
    std::string_view detail;
  };
  const Case cases[] = {
      {"stop", [](Bus& b) { b.post(8, StopCommand{}); }, ReplyCode::NotReady,
       "learning travel stopped: nothing learned"},
      {"safety chain", [](Bus& b) { b.inputs.safety_chain_closed = false; }, ReplyCode::Fault,
       "safety_chain_open"},
  };
  for (const Case& c : cases) {
    Bus bus;
    bus.post(7, LearnCommand{});
    // Past the approach and into the leg up.
    ASSERT_TRUE(run_shaft(bus, [&] {
      return bus.controller.travel().kind() == TravelKind::Learn &&
             bus.controller.travel().direction() == lift::Direction::Up &&
             bus.car.position_mm > 500.0;
    })) << c.legend;
    c.act(bus);
    ASSERT_TRUE(run_shaft(
        bus, [&] { return reply_to(bus, 7).has_value(); }, 10000))
        << c.legend;
    EXPECT_EQ(reply_to(bus, 7)->code, c.code) << c.legend;
    EXPECT_EQ(reply_to(bus, 7)->detail, c.detail) << c.legend;
    EXPECT_EQ(bus.controller.learn_record().tag, 0U) << c.legend << ": a record was published";
    ASSERT_TRUE(run_shaft(
        bus, [&] { return bus.idle(); }, 10000))
        << c.legend;
    EXPECT_LT(bus.car.position_mm, 1000.0) << c.legend << ": stopped, not run on";
  }
}

}  // namespace
}  // namespace liftd::uss
