// The SCH001 controller under attack, with a fake clock: a reopened CAN endpoint voids the old
// card status (no travel on a stale RDY), no reply is ever lost to a full queue, fault raises and
// clears stay paired when the event queue overflows, a lost endpoint is one fault however often
// it is reopened, and the link faults the card document implies (another node on our
// identifier, answers that cannot be sent) stop every travel command.
#include <gtest/gtest.h>

#include <map>
#include <vector>

#include "engine_calls.hpp"
#include "sch001/controller.hpp"

namespace liftd::sch001 {
namespace {

using namespace std::chrono_literals;

constexpr std::uint8_t kReady = 0x02;

class StillCar final : public PositionSource {
 public:
  std::optional<std::int64_t> position_mm(MonoTime) const noexcept override { return mm; }
  std::optional<std::int64_t> mm = 0;
};

class Sch001ControllerTest : public ::testing::Test {
 protected:
  Sch001ControllerTest() : controller_(make_config(), position_, MonoTime{}) {
    controller_.on_endpoint(true, now_);
    send_inputs();
  }
  static ControllerConfig make_config() {
    ControllerConfig config;
    config.floors_mm = {0, 3000, 6000, 9000};
    config.hydraulic.star_delta_ms = 200;
    return config;
  }
  void send_inputs(bool chain_closed = true) {
    lift::Inputs in;
    in.valid = in.doors_closed = in.doors_locked = true;
    in.safety_chain_closed = chain_closed;
    ASSERT_TRUE(controller_.post({0, InputsCommand{in}}));
  }
  /// The card's status frame at the current time; the answer's command byte.
  std::uint8_t status(std::uint8_t byte = kReady) {
    const std::array<std::uint8_t, 2> bytes = {kStatusFrame, byte};
    const auto answer = test::feed_frame(controller_, can::make_frame(0x581, bytes), now_);
    EXPECT_TRUE(answer);
    if (!answer) return 0xFF;
    controller_.on_sent(*answer, true, now_);
    return answer->data[1];
  }
  /// 100 ms of the card's life: ticks and one status frame.
  std::uint8_t run_100ms(std::uint8_t byte = kReady) {
    for (int i = 0; i < 9; ++i) {
      now_ += 10ms;
      test::feed_tick(controller_, now_);
    }
    now_ += 10ms;
    send_inputs();
    return status(byte);
  }
  std::vector<CommandReply> replies() {
    std::vector<CommandReply> out;
    CommandReply r;
    while (controller_.poll_reply(r)) out.push_back(r);
    return out;
  }
  std::vector<ControllerEvent> events() {
    std::vector<ControllerEvent> out;
    ControllerEvent e;
    while (controller_.poll_event(e)) out.push_back(e);
    return out;
  }
  int count(const std::vector<ControllerEvent>& es, ControllerEvent::Kind kind, FaultCode code) {
    int n = 0;
    for (const auto& e : es) n += e.kind == kind && e.fault == code;
    return n;
  }
  /// The reply to one command posted now.
  CommandReply ask(const CommandBody& body) {
    (void)replies();
    EXPECT_TRUE(controller_.post({++tag_, body}));
    now_ += 10ms;
    test::feed_tick(controller_, now_);
    const auto got = replies();
    EXPECT_EQ(got.size(), 1U);
    return got.empty() ? CommandReply{} : got.front();
  }

  StillCar position_;
  Sch001Controller controller_;
  MonoTime now_{};
  std::uint32_t tag_ = 0;
};

TEST_F(Sch001ControllerTest, AReopenedEndpointVoidsTheOldCardStatus) {
  for (int i = 0; i < 5; ++i) run_100ms();
  ASSERT_TRUE(controller_.snapshot().heard);
  // The card's connection drops and the endpoint reopens to a silent peer.
  controller_.on_endpoint(false, now_);
  now_ += 100ms;
  controller_.on_endpoint(true, now_);
  for (int i = 0; i < 10; ++i) {
    now_ += 10ms;
    test::feed_tick(controller_, now_);
  }
  const ControllerSnapshot s = controller_.snapshot();
  EXPECT_FALSE(s.heard) << "the old connection's status was kept";
  EXPECT_FALSE(s.card.has_value());
  const CommandReply r = ask(TravelCommand{2, Speed::Fast});
  EXPECT_EQ(r.code, ReplyCode::NotReady) << r.detail;
  // The new peer's first status (RDY) is answered without any travel bit: nothing was started.
  EXPECT_EQ(status(kReady), 0x00);
}

TEST_F(Sch001ControllerTest, ALostEndpointIsOneFaultHoweverOftenItIsReopened) {
  for (int i = 0; i < 5; ++i) run_100ms();
  (void)events();
  for (int i = 0; i < 20; ++i) {  // an interface that is down: opens, then fails at once
    controller_.on_endpoint(false, now_);
    now_ += 100ms;
    controller_.on_endpoint(true, now_);
    now_ += 10ms;
    test::feed_tick(controller_, now_);
  }
  auto es = events();
  EXPECT_EQ(count(es, ControllerEvent::Kind::FaultRaised, FaultCode::LinkFault), 1);
  EXPECT_EQ(count(es, ControllerEvent::Kind::FaultCleared, FaultCode::LinkFault), 0);
  EXPECT_TRUE(controller_.snapshot().endpoint_lost);
  run_100ms();  // the card is heard on the new endpoint
  es = events();
  EXPECT_EQ(count(es, ControllerEvent::Kind::FaultCleared, FaultCode::LinkFault), 1);
  EXPECT_FALSE(controller_.snapshot().endpoint_lost);
}

// status drive.state reads the snapshot's drive_allows_travel, the card's side of the travel
// check: for each card status, what the snapshot says and what a travel is answered agree.
TEST_F(Sch001ControllerTest, TheSnapshotAllowsATravelExactlyWhenTheCardDoes) {
  struct Case {
    const char* legend;
    std::uint8_t status;  ///< ERR PNP2 AVV T1 P1 P2 RDY PNP1 (3b)
    bool allows;
    ReplyCode travel;
  };
  const Case cases[] = {
      {"RDY = 0: not ready (3e)", 0x00, false, ReplyCode::NotReady},
      {"ERR with RDY: a fault (3d)", 0x82, false, ReplyCode::Fault},
      {"RDY with T1 and P1: only reported", 0x1A, true, ReplyCode::Ok},
      {"RDY = 0 again", 0x00, false, ReplyCode::NotReady},
      {"RDY: ready", kReady, true, ReplyCode::Ok},
  };
  for (const Case& c : cases) {
    for (int i = 0; i < 3; ++i) run_100ms(c.status);
    EXPECT_EQ(controller_.snapshot().drive_allows_travel, c.allows) << c.legend;
    const CommandReply r = ask(TravelCommand{2, Speed::Fast});
    EXPECT_EQ(r.code, c.travel) << c.legend << ": " << r.detail;
    if (r.code == ReplyCode::Ok) {
      // RDY dropping ends the travel (3e): back at rest for the next case.
      for (int i = 0; i < 3; ++i) run_100ms(0x00);
      EXPECT_EQ(controller_.snapshot().travel_kind, TravelKind::None) << c.legend;
    }
  }
}

TEST_F(Sch001ControllerTest, NoReplyIsLostWhenCommandsComeFasterThanRepliesAreRead) {
  run_100ms();
  // Clients pipeline calls while the io thread does not read replies: every command the
  // controller took gets its reply; the rest are refused before they are queued.
  int accepted = 0;
  int refused = 0;
  std::map<std::uint32_t, int> answered;
  for (int round = 0; round < 40; ++round) {
    for (int i = 0; i < 20; ++i) {
      const bool add = (i % 2) == 0;
      if (controller_.post({++tag_, (add ? CallCommand::adding : CallCommand::cancelling)(
                                        static_cast<std::size_t>(1 + i % 3))})) {
        ++accepted;
      } else {
        ++refused;
      }
    }
    now_ += 10ms;
    test::feed_tick(controller_, now_);
    if (round % 8 == 7) {
      for (const auto& r : replies()) ++answered[r.tag];
    }
  }
  now_ += 10ms;
  test::feed_tick(controller_, now_);
  for (const auto& r : replies()) ++answered[r.tag];
  EXPECT_GT(refused, 0) << "the test never filled the queues";
  EXPECT_EQ(static_cast<int>(answered.size()), accepted);
  for (const auto& [tag, n] : answered) EXPECT_EQ(n, 1) << "tag " << tag;
  EXPECT_EQ(controller_.lost_replies(), 0U);
  EXPECT_EQ(controller_.replies_owed(), 0U);
}

TEST_F(Sch001ControllerTest, ACallToAFloorAlreadyQueuedIsOkAsOnEveryLift) {
  run_100ms();
  ASSERT_EQ(ask(CallCommand::adding(2)).code, ReplyCode::Ok);
  const CommandReply again = ask(CallCommand::adding(2));
  EXPECT_EQ(again.code, ReplyCode::Ok) << again.detail;
  EXPECT_EQ(again.detail, "already queued");
}

TEST_F(Sch001ControllerTest, FaultRaisesAndClearsStayPairedWhenTheEventQueueOverflows) {
  run_100ms();
  (void)events();
  // The safety chain flaps 1000 times while nobody reads events.
  for (int i = 0; i < 1000; ++i) {
    send_inputs(i % 2 == 1);
    now_ += 1ms;
    test::feed_tick(controller_, now_);
  }
  send_inputs(false);  // ends open
  now_ += 1ms;
  test::feed_tick(controller_, now_);
  // Drain as the io thread would, with the controller stepping between polls.
  std::vector<ControllerEvent> all;
  for (int i = 0; i < 50; ++i) {
    const auto es = events();
    all.insert(all.end(), es.begin(), es.end());
    now_ += 1ms;
    send_inputs(false);
    test::feed_tick(controller_, now_);
  }
  bool active = false;
  int raises = 0;
  for (const auto& e : all) {
    if (e.fault != FaultCode::SafetyChain) continue;
    if (e.kind == ControllerEvent::Kind::FaultRaised) {
      EXPECT_FALSE(active) << "raised twice in a row";
      active = true;
      ++raises;
    } else if (e.kind == ControllerEvent::Kind::FaultCleared) {
      EXPECT_TRUE(active) << "cleared without a raise";
      active = false;
    }
  }
  EXPECT_GE(raises, 1);
  EXPECT_TRUE(active) << "the last report must be the truth: the chain is open";
}

TEST_F(Sch001ControllerTest, AnotherNodeOnOurIdentifierStopsTravelCommands) {
  run_100ms();
  const CommandReply started = ask(TravelCommand{2, Speed::Fast});
  ASSERT_EQ(started.code, ReplyCode::Ok) << started.detail;
  std::uint8_t bits = 0;
  for (int i = 0; i < 5; ++i) bits = run_100ms();
  ASSERT_NE(bits, 0) << "the travel should be running";
  (void)events();
  // A frame on 0x551, our identifier (card document 1.6).
  const std::array<std::uint8_t, 4> foreign = {0x68, 0x01, 0x00, 0x03};
  EXPECT_FALSE(test::feed_frame(controller_, can::make_frame(0x551, foreign), now_));
  EXPECT_EQ(run_100ms(), 0x00) << "travel bits while another node commands the card";
  EXPECT_TRUE(controller_.snapshot().foreign_sender);
  EXPECT_EQ(count(events(), ControllerEvent::Kind::FaultRaised, FaultCode::LinkFault), 1);
  EXPECT_EQ(controller_.snapshot().counters.own_id, 1U);
  for (int i = 0; i < 100; ++i) run_100ms();  // 10 s without another such frame
  EXPECT_FALSE(controller_.snapshot().foreign_sender);
  EXPECT_EQ(count(events(), ControllerEvent::Kind::FaultCleared, FaultCode::LinkFault), 1);
}

TEST_F(Sch001ControllerTest, AnswersThatCannotBeSentAreALinkFaultAndNotShownAsSent) {
  run_100ms();
  ASSERT_EQ(ask(TravelCommand{2, Speed::Fast}).code, ReplyCode::Ok);
  for (int i = 0; i < 5; ++i) run_100ms();
  const CommandBits delivered = controller_.snapshot().bits_sent;
  ASSERT_TRUE(delivered.any());
  (void)events();
  // Nobody takes our frames: each answer fails to go out.
  for (std::uint32_t i = 0; i < kSendFailuresForFault; ++i) {
    now_ += 100ms;
    const std::array<std::uint8_t, 2> bytes = {kStatusFrame, kReady};
    const auto answer = test::feed_frame(controller_, can::make_frame(0x581, bytes), now_);
    ASSERT_TRUE(answer);
    controller_.on_sent(*answer, false, now_);
  }
  const ControllerSnapshot s = controller_.snapshot();
  EXPECT_TRUE(s.send_failing);
  EXPECT_EQ(s.bits_sent, delivered) << "status shows bits that were never delivered";
  const auto es = events();
  EXPECT_EQ(count(es, ControllerEvent::Kind::FaultRaised, FaultCode::LinkFault), 1);
  EXPECT_EQ(controller_.snapshot().travel_kind, TravelKind::None) << "the travel went on";
  EXPECT_EQ(status(kReady), 0x00);  // delivered again: no travel bit
  EXPECT_FALSE(controller_.snapshot().send_failing);
}

// ---- the learning travel ----

/// A shaft whose true levels are off the floor table: its level switch reads the test's car.
class ShaftSwitch final : public LevelZoneSource {
 public:
  explicit ShaftSwitch(const StillCar& car) : car_(car) {}
  bool level_zone(MonoTime) const noexcept override {
    if (!car_.mm) return false;
    for (const std::int64_t level : kTrueLevels) {
      if (*car_.mm >= level - 50 && *car_.mm <= level + 50) return true;  // 100 mm zones
    }
    return false;
  }
  static constexpr std::array<std::int64_t, 4> kTrueLevels = {-35, 3025, 6055, 8980};

 private:
  const StillCar& car_;
};

class Sch001LearnTest : public ::testing::Test {
 protected:
  Sch001LearnTest() : zone_(position_), controller_(make_config(zone_), position_, MonoTime{}) {
    controller_.on_endpoint(true, now_);
    send_inputs();
  }
  static ControllerConfig make_config(const LevelZoneSource& zone) {
    ControllerConfig config;
    config.floors_mm = {0, 3000, 6000, 9000};
    config.hydraulic.star_delta_ms = 200;
    config.level_zone_source = &zone;
    return config;
  }
  void send_inputs() { ASSERT_TRUE(controller_.post({0, InputsCommand{inputs_}})); }
  /// 10 ms: the car moves as the last answer's signals say (slow 2 mm, fast 10 mm per 10 ms),
  /// the controller ticks, every 100 ms the card's status frame is answered.
  void run_10ms() {
    const CommandBits b = CommandBits::from_byte(sent_);
    const std::int64_t step = b.hsp || b.sp3 ? 10 : 2;
    if (b.up && b.sfy) *position_.mm += step;
    if (b.dw) *position_.mm -= step;
    now_ += 10ms;
    if (++ticks_ % 10 == 0) {
      send_inputs();
      const std::array<std::uint8_t, 2> bytes = {kStatusFrame, kReady};
      const auto answer = test::feed_frame(controller_, can::make_frame(0x581, bytes), now_);
      ASSERT_TRUE(answer);
      controller_.on_sent(*answer, true, now_);
      sent_ = answer->data[1];
    } else {
      test::feed_tick(controller_, now_);
    }
  }
  /// Runs until the learn command (tag 1) is answered, at most `limit` of fake time.
  std::optional<CommandReply> run_until_answered(MonoTime limit = 200s) {
    const MonoTime end = now_ + limit;
    CommandReply r;
    while (now_ < end) {
      run_10ms();
      while (controller_.poll_reply(r)) {
        if (r.tag == 1) return r;
      }
    }
    return std::nullopt;
  }

  StillCar position_;
  ShaftSwitch zone_;
  Sch001Controller controller_;
  lift::Inputs inputs_ = [] {
    lift::Inputs in;
    in.valid = in.doors_closed = in.doors_locked = in.safety_chain_closed = true;
    return in;
  }();
  MonoTime now_{};
  std::uint8_t sent_ = 0;
  int ticks_ = 0;
};

TEST_F(Sch001LearnTest, LearnsTheShaftsLevelsAndStopsJustAboveTheTopZone) {
  for (int i = 0; i < 50; ++i) run_10ms();  // the card is heard
  ASSERT_TRUE(controller_.post({1, LearnCommand{}}));
  const auto reply = run_until_answered();
  ASSERT_TRUE(reply);
  EXPECT_EQ(reply->code, ReplyCode::Ok) << reply->detail;
  const lift::LearnRecord record = controller_.learn_record();
  EXPECT_EQ(record.tag, 1U);
  EXPECT_TRUE(record.judgement.ok());
  ASSERT_EQ(record.zone_count, 4U);
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_NEAR(static_cast<double>(record.zones[i].level_mm()),
                static_cast<double>(ShaftSwitch::kTrueLevels[i]), 2.0)
        << "floor " << i;
  }
  // 20 mm beyond the top zone's end (9030) the signals drop; the car coasts one answer on.
  EXPECT_GE(*position_.mm, 9030 + 20);
  EXPECT_LE(*position_.mm, 9030 + 20 + 30);
  EXPECT_EQ(controller_.snapshot().travel_kind, TravelKind::None);
  // No relevelling towards the table's top level the car now stands 70 mm beyond.
  for (int i = 0; i < 100; ++i) run_10ms();
  EXPECT_EQ(controller_.snapshot().travel_kind, TravelKind::None);
}

TEST_F(Sch001LearnTest, StopMidLearningEndsItAndNothingIsLearned) {
  for (int i = 0; i < 50; ++i) run_10ms();
  ASSERT_TRUE(controller_.post({1, LearnCommand{}}));
  for (int i = 0; i < 500; ++i) run_10ms();  // the approach, then well into the leg up
  ASSERT_EQ(controller_.snapshot().travel_kind, TravelKind::Learn);
  ASSERT_EQ(controller_.snapshot().direction, lift::Direction::Up);
  ASSERT_TRUE(controller_.post({2, StopCommand{}}));
  const auto reply = run_until_answered(5s);
  ASSERT_TRUE(reply);
  EXPECT_EQ(reply->code, ReplyCode::NotReady);
  EXPECT_EQ(reply->detail, "learning travel stopped: nothing learned");
  EXPECT_EQ(controller_.learn_record().tag, 0U) << "a record was published";
  for (int i = 0; i < 10; ++i) run_10ms();  // the card's next status frame is answered
  EXPECT_EQ(sent_, 0) << "every signal dropped";
}

TEST_F(Sch001LearnTest, AFaultMidLearningEndsItWithItsCause) {
  for (int i = 0; i < 50; ++i) run_10ms();
  ASSERT_TRUE(controller_.post({1, LearnCommand{}}));
  for (int i = 0; i < 500; ++i) run_10ms();
  ASSERT_EQ(controller_.snapshot().travel_kind, TravelKind::Learn);
  inputs_.safety_chain_closed = false;
  send_inputs();
  const auto reply = run_until_answered(5s);
  ASSERT_TRUE(reply);
  EXPECT_EQ(reply->code, ReplyCode::Fault);
  EXPECT_EQ(reply->detail, "safety_chain_open");
  EXPECT_EQ(controller_.learn_record().tag, 0U);
  for (int i = 0; i < 10; ++i) run_10ms();
  EXPECT_EQ(sent_, 0);
}

TEST_F(Sch001LearnTest, IsRefusedAsATravelIs) {
  for (int i = 0; i < 50; ++i) run_10ms();
  inputs_.doors_locked = false;
  send_inputs();
  ASSERT_TRUE(controller_.post({1, LearnCommand{}}));
  const auto reply = run_until_answered(1s);
  ASSERT_TRUE(reply);
  EXPECT_EQ(reply->code, ReplyCode::NotReady);
  EXPECT_EQ(reply->detail, "doors not locked");
  EXPECT_EQ(controller_.snapshot().travel_kind, TravelKind::None);
}

}  // namespace
}  // namespace liftd::sch001
