// The DCP4 sequencer against the drive simulator (lib/dcp/sim): real frames through the codec, the
// I7 exchange over the communication channel, the simulator's own car and ramps.
#include <gtest/gtest.h>

#include <cmath>
#include <deque>
#include <string>

#include "dcp/frame.hpp"
#include "dcp/sim/drive_sim.hpp"
#include "dcp/travel/controller.hpp"

namespace liftd::travel {
namespace {

using namespace std::chrono_literals;

// DCP 5: channel framing bytes.
constexpr std::uint8_t kStx = 0x02;
constexpr std::uint8_t kEtx = 0x03;
constexpr std::uint8_t kExpandedData = 0x1C;

/// Parses "ftyp Sg1..5 Sv1..5" of an I7 reply body after "I7" (DCP 5.12.7.2).
std::optional<ChannelReply> parse_i7(const std::string& body) {
  if (body.size() != 13 || body[0] != 'I' || body[1] != '7') return std::nullopt;
  ChannelReply reply;
  reply.kind = ChannelRequest::Kind::StartParameters;
  reply.short_travel = body[2] == 's';
  reply.min_distance_cm = static_cast<std::uint32_t>(std::stoul(body.substr(3, 5)));
  reply.decel_distance_cm = static_cast<std::uint32_t>(std::stoul(body.substr(8, 5)));
  return reply;
}

/// A minimal master around the controller: frames, data bytes, and a channel that carries
/// I-messages both ways two bytes per cycle.
class SimRig {
 public:
  explicit SimRig(TravelConfig config, dcp::Protocol protocol = dcp::Protocol::Dcp4)
      : controller(config), sim(sim_config(protocol), now) {
    input.link_up = true;
    input.handshake_done = true;  // the simulator runs with require_init = false
    input.protocol = protocol;
    input.inputs.valid = input.inputs.safety_chain_closed = true;
    input.inputs.doors_closed = input.inputs.doors_locked = true;
  }

  static dcp::sim::DriveConfig sim_config(dcp::Protocol protocol) {
    dcp::sim::DriveConfig config;
    config.protocol = protocol;
    config.require_init = false;
    config.dcp3_decel_mm[7] = 2500;  // SV4 (index G7), used by the DCP3 test only
    return config;
  }

  void cycle() {
    now += 15ms;  // DCP 7.2
    sim.advance(now);
    input.now = now;
    input.position_mm = std::llround(sim.position_mm());
    input.channel_reply = reply_;
    reply_.reset();
    const CycleOutput out = controller.step(input);
    if (out.channel_request) {
      const ChannelText text = out.channel_request->body();
      tx_.push_back(kStx);
      tx_.push_back(kExpandedData);
      for (std::size_t i = 0; i < text.size; ++i)
        tx_.push_back(static_cast<std::uint8_t>(text.chars[i]));
      tx_.push_back(kEtx);
    }
    dcp::MasterFrame frame;
    frame.command = out.command;
    frame.set_data_word(out.data_word);
    frame.comm1 = next_tx();
    frame.comm2 = next_tx();
    const dcp::sim::Reply reply = sim.on_master_frame(dcp::encode(frame), now);
    ASSERT_EQ(reply.size, dcp::kFrameSize);
    const auto slave = dcp::decode_slave(
        std::span<const std::uint8_t, dcp::kFrameSize>(reply.bytes.data(), dcp::kFrameSize));
    ASSERT_TRUE(slave.has_value());
    input.status = dcp::Status::from_byte(slave->status);
    input.reply_fresh = !input.status.message_error;
    const auto data = dcp::decode_drive_data(slave->data_word(), dcp::DataInfoType::Alternating);
    if (data && data->kind == dcp::DriveData::Kind::DecelerationDistance) {
      input.decel_distance_mm = data->saturated
                                    ? std::nullopt
                                    : std::optional<std::uint32_t>(data->deceleration_distance_mm);
    }
    receive(slave->comm1);
    receive(slave->comm2);
    commands.push_back(out.command);
    while (auto event = controller.pop_event()) events.push_back(*event);
  }

  std::vector<std::uint8_t> command_runs() const {
    std::vector<std::uint8_t> runs;
    for (auto c : commands) {
      if (runs.empty() || runs.back() != c) runs.push_back(c);
    }
    return runs;
  }

  TravelController controller;
  MonoTime now{};
  dcp::sim::DriveSim sim;
  CycleInput input{};
  std::vector<std::uint8_t> commands;
  std::vector<Event> events;
  std::optional<ChannelReply> last_i7;

 private:
  std::uint8_t next_tx() {
    if (tx_.empty()) return 0x00;  // DCP 5: idle
    const std::uint8_t b = tx_.front();
    tx_.pop_front();
    return b;
  }
  void receive(std::uint8_t b) {
    if (b == 0x00) return;
    if (b == kStx) {
      rx_.clear();
      in_message_ = true;
      return;
    }
    if (!in_message_) return;
    if (b != kEtx) {
      rx_.push_back(static_cast<char>(b));
      return;
    }
    in_message_ = false;
    if (rx_.empty() || static_cast<std::uint8_t>(rx_[0]) != kExpandedData) return;
    const std::string body = rx_.substr(1);
    if (auto i7 = parse_i7(body)) {
      reply_ = i7;
      last_i7 = i7;
    } else if (body.size() >= 2 && body[0] == 'I') {
      ChannelReply ack;
      ack.kind = body[1] == '8' ? ChannelRequest::Kind::Load : ChannelRequest::Kind::Position;
      reply_ = ack;
    }
  }

  std::deque<std::uint8_t> tx_;
  std::string rx_;
  bool in_message_ = false;
  std::optional<ChannelReply> reply_;
};

TEST(SimTravel, Dcp4LongTravelWithI7AndExtension) {
  TravelConfig config;
  SimRig rig(config);
  for (int i = 0; i < 100 && !rig.input.status.ready; ++i) rig.cycle();
  ASSERT_TRUE(rig.input.status.ready);
  TravelRequest request;
  request.kind = TravelKind::Dcp4Distance;
  request.speed = dcp::Speed::V4;
  request.target_mm = 10000;
  ASSERT_EQ(rig.controller.start(request), StartResult::Accepted);
  bool extended = false;
  for (int i = 0; i < 4000; ++i) {
    rig.cycle();
    if (!extended && rig.sim.velocity_mps() > 1.0) {
      ASSERT_EQ(rig.controller.extend_target(15000), ExtendResult::Pending);
      extended = true;
    }
    if (rig.controller.active_kind() == TravelKind::None && !rig.input.status.travel_active &&
        extended) {
      break;
    }
  }
  // DCP 11.1.2.1 example 2: 1000 cm at V4 -> long travel, Sg 520 cm, Sv 250 cm.
  ASSERT_TRUE(rig.last_i7.has_value());
  EXPECT_FALSE(rig.last_i7->short_travel);
  EXPECT_EQ(rig.last_i7->min_distance_cm, 520U);
  EXPECT_EQ(rig.last_i7->decel_distance_cm, 250U);
  EXPECT_EQ(rig.command_runs(), (std::vector<std::uint8_t>{0x00, 0x09, 0x05, 0x01, 0x00}));
  EXPECT_NEAR(rig.sim.position_mm(), 15000.0, 10.0);
  EXPECT_EQ(rig.sim.counters().travels, 1U);
  EXPECT_EQ(rig.sim.counters().refused_extensions, 0U);
  EXPECT_EQ(rig.sim.counters().violations, 0U);
  ASSERT_FALSE(rig.events.empty());
  EXPECT_EQ(rig.events.back().type, Event::Type::Finished);
  // DCP 4.1: reported once the drive's S5 confirmed the new distance.
  EXPECT_EQ(std::count_if(rig.events.begin(), rig.events.end(),
                          [](const Event& e) { return e.type == Event::Type::TargetExtended; }),
            1);
}

bool run_to_idle(SimRig& rig, int limit = 4000) {
  for (int i = 0; i < limit; ++i) {
    rig.cycle();
    if (rig.controller.active_kind() == TravelKind::None && !rig.input.status.travel_active) {
      return true;
    }
  }
  return false;
}

void wait_ready(SimRig& rig) {
  for (int i = 0; i < 100 && !rig.input.status.ready; ++i) rig.cycle();
  ASSERT_TRUE(rig.input.status.ready);
}

TEST(SimTravel, Dcp4ShortTravelI7Figures) {
  SimRig rig(TravelConfig{});
  wait_ready(rig);
  TravelRequest request;
  request.target_mm = 3000;
  ASSERT_EQ(rig.controller.start(request), StartResult::Accepted);
  rig.cycle();
  ASSERT_TRUE(run_to_idle(rig));
  // DCP 11.1.2.1 example 1: 300 cm at V4 -> short travel, Sg 300 cm, Sv 143 cm.
  ASSERT_TRUE(rig.last_i7.has_value());
  EXPECT_TRUE(rig.last_i7->short_travel);
  EXPECT_EQ(rig.last_i7->min_distance_cm, 300U);
  EXPECT_EQ(rig.last_i7->decel_distance_cm, 143U);
  EXPECT_NEAR(rig.sim.position_mm(), 3000.0, 10.0);
  EXPECT_EQ(rig.events.back().type, Event::Type::Finished);
}

TEST(SimTravel, Dcp4FastStartThenTravel) {
  TravelConfig config;
  config.use_i7 = false;
  SimRig rig(config);
  wait_ready(rig);
  rig.input.inputs.doors_locked = rig.input.inputs.doors_closed = false;
  TravelRequest request;
  request.target_mm = 6000;
  request.fast_start = true;
  ASSERT_EQ(rig.controller.start(request), StartResult::Accepted);
  for (int i = 0; i < 60; ++i) rig.cycle();
  EXPECT_EQ(rig.sim.phase(), dcp::sim::Phase::FastStartHold);
  EXPECT_NEAR(rig.sim.position_mm(), 0.0, 1.0);
  rig.input.inputs.doors_locked = rig.input.inputs.doors_closed = true;
  ASSERT_TRUE(run_to_idle(rig));
  EXPECT_NEAR(rig.sim.position_mm(), 6000.0, 10.0);
  EXPECT_EQ(rig.events.back().type, Event::Type::Finished);
}

TEST(SimTravel, Dcp4FastStartDoorReversalControlledAbort) {
  TravelConfig config;
  config.use_i7 = false;
  SimRig rig(config);
  wait_ready(rig);
  rig.input.inputs.doors_locked = rig.input.inputs.doors_closed = false;
  TravelRequest request;
  request.target_mm = 6000;
  request.fast_start = true;
  ASSERT_EQ(rig.controller.start(request), StartResult::Accepted);
  for (int i = 0; i < 60; ++i) rig.cycle();
  rig.input.inputs.door_reversal = true;
  ASSERT_TRUE(run_to_idle(rig));
  EXPECT_NEAR(rig.sim.position_mm(), 0.0, 1.0);
  EXPECT_EQ(rig.events.back().cause, lift::Cause::DoorReversal);
  EXPECT_FALSE(rig.input.status.general_fault);
}

TEST(SimTravel, Dcp4FastStopDuringTravel) {
  TravelConfig config;
  config.use_i7 = false;
  SimRig rig(config);
  wait_ready(rig);
  TravelRequest request;
  request.target_mm = 20000;
  ASSERT_EQ(rig.controller.start(request), StartResult::Accepted);
  for (int i = 0; i < 4000 && rig.sim.velocity_mps() < 1.5; ++i) rig.cycle();
  rig.controller.fast_stop();
  ASSERT_TRUE(run_to_idle(rig));
  EXPECT_LT(rig.sim.position_mm(), 19000.0);
  EXPECT_EQ(rig.events.back().cause, lift::Cause::StopRequested);
}

TEST(SimTravel, Dcp4AutoRelevel) {
  TravelConfig config;
  SimRig rig(config);
  rig.sim.set_position_mm(-40.0);
  rig.controller.set_home_level(0);
  wait_ready(rig);
  ASSERT_TRUE(run_to_idle(rig));
  for (int i = 0; i < 2000 && rig.controller.active_kind() == TravelKind::None; ++i) rig.cycle();
  ASSERT_EQ(rig.controller.active_kind(), TravelKind::Dcp4Relevel);
  ASSERT_TRUE(run_to_idle(rig));
  EXPECT_NEAR(rig.sim.position_mm(), 0.0, 3.0);
}

TEST(SimTravel, Dcp3V4TravelByPosition) {
  // DCP 10.1.1 with the deceleration point from the position: SV4 = 2500 mm on both sides.
  TravelConfig config;
  config.dcp3_reference = Dcp3Reference::Position;
  config.dcp3_speed_count = 1;
  config.dcp3_decel_distance_mm[speed_index(dcp::Speed::V4)] = 2500;
  SimRig rig(config, dcp::Protocol::Dcp3);
  wait_ready(rig);
  TravelRequest request;
  request.kind = TravelKind::Dcp3Speed;
  request.speed = dcp::Speed::V4;
  request.target_mm = 12000;
  ASSERT_EQ(rig.controller.start(request), StartResult::Accepted);
  rig.cycle();
  ASSERT_TRUE(run_to_idle(rig));
  EXPECT_EQ(rig.command_runs(), (std::vector<std::uint8_t>{0x00, 0x09, 0x07, 0x05, 0x01, 0x00}));
  EXPECT_NEAR(rig.sim.position_mm(), 12000.0, 15.0);
  EXPECT_EQ(rig.events.back().type, Event::Type::Finished);
}

}  // namespace
}  // namespace liftd::travel
