// Property test: random commands, card status frames, input changes, bus errors and silences
// against the real SCH001 controller, over many seeds. Every answer the controller sends is
// checked against what the rig fed it before, never against the controller's own state: no
// travel signal answering a status with ERR or without RDY (card document 3d, 3e), none after a
// bus fault until the bus is back, none while the safety chain is open or the inputs are stale,
// none but an inspection run's (MSP) while the doors are neither locked nor bridged, none but
// inspection without a position.
#include <gtest/gtest.h>

#include <random>
#include <string>
#include <vector>

#include "engine_calls.hpp"
#include "sch001/controller.hpp"

namespace liftd::sch001 {
namespace {

using namespace std::chrono_literals;

class FakePosition final : public PositionSource {
 public:
  std::optional<std::int64_t> position_mm(MonoTime) const noexcept override { return mm; }
  std::optional<std::int64_t> mm = 0;
};

struct Totals {
  std::uint64_t answers = 0;
  std::uint64_t with_travel_bits = 0;
  std::uint64_t forbidden_situations = 0;  ///< answers where a rule forbade travel bits
};

std::string run_seed(unsigned seed, Totals& totals) {
  std::mt19937 rng(seed);
  const auto chance = [&](int percent) {
    return std::uniform_int_distribution<int>(0, 99)(rng) < percent;
  };
  ControllerConfig config;
  config.floors_mm = {0, 3000, 6000, 9000};
  config.hydraulic.star_delta_ms = 200;
  FakePosition position;
  Sch001Controller controller(config, position, MonoTime{});
  MonoTime now{};
  controller.on_endpoint(true, now);
  bool endpoint_ok = true;
  lift::Inputs inputs;
  inputs.valid = inputs.safety_chain_closed = inputs.doors_closed = inputs.doors_locked = true;
  MonoTime inputs_at{};
  bool inputs_sent = false;
  std::uint8_t status = 0x02;  // RDY
  std::uint32_t tag = 0;
  for (int step = 0; step < 3000; ++step) {
    now += 10ms;
    // Commands from the API side.
    if (chance(3)) {
      controller.post({++tag, TravelCommand{static_cast<std::size_t>(rng() % 4), Speed::Fast}});
    }
    if (chance(1)) controller.post({++tag, StopCommand{}});
    if (chance(1)) controller.post({++tag, RelevelCommand{}});
    if (chance(1)) {
      controller.post({++tag, InspectionCommand{chance(50), chance(50) ? lift::Direction::Up
                                                                       : lift::Direction::Down}});
    }
    if (chance(1))
      controller.post({++tag, CallCommand::adding(static_cast<std::size_t>(rng() % 4))});
    // The machine.
    if (chance(2)) inputs.safety_chain_closed = !inputs.safety_chain_closed || chance(70);
    if (chance(2)) inputs.doors_locked = !inputs.doors_locked || chance(70);
    if (chance(1)) inputs.door_zone_bridge = !inputs.door_zone_bridge;
    if (chance(2)) position.mm = chance(20) ? std::nullopt : std::optional<std::int64_t>(0);
    if (!position.mm && chance(20)) position.mm = 0;
    if (!chance(3)) {  // sometimes the I/O provider misses its turn
      controller.post({0, InputsCommand{inputs}});
      inputs_at = now;
      inputs_sent = true;
    }
    // The bus.
    if (chance(1)) {
      can::ErrorReport e;
      e.bus_off = chance(50);
      e.error_passive = !e.bus_off && chance(50);
      e.restarted = !e.bus_off && !e.error_passive;
      controller.on_bus_error(e, now);
      if (e.is_fault()) endpoint_ok = false;
      if (e.restarted) endpoint_ok = true;
    }
    test::feed_tick(controller, now);
    // Every 100 ms the card's status frame, unless the card is silent for a while.
    if (step % 10 == 0 && !(step % 700 > 600)) {
      if (chance(10)) status = static_cast<std::uint8_t>(rng() & 0xFF);
      if (chance(10)) status = 0x02;
      const std::array<std::uint8_t, 2> bytes = {kStatusFrame, status};
      const bool after_bus_fault = !endpoint_ok;
      const auto answer = test::feed_frame(controller, can::make_frame(0x581, bytes), now);
      endpoint_ok = true;  // a frame from the card: the bus carries frames again
      if (!answer) return "seed " + std::to_string(seed) + ": a status frame got no answer";
      ++totals.answers;
      const CommandBits bits = CommandBits::from_byte(answer->data[1]);
      if (bits.any()) ++totals.with_travel_bits;
      // The rules, from what the rig fed.
      const CardStatus card = CardStatus::from_byte(status);
      const bool fresh = inputs_sent && now - inputs_at <= config.inputs_timeout;
      std::string broken;
      if (card.err) broken = "3d: travel bits answering ERR";
      if (!card.rdy) broken = "3e: travel bits answering RDY = 0";
      if (!fresh) broken = "travel bits with stale inputs";
      if (!inputs.safety_chain_closed) broken = "travel bits with the safety chain open";
      if (!bits.msp && !inputs.doors_locked && !inputs.door_zone_bridge) {
        broken = "travel bits with the doors neither locked nor bridged";
      }
      if (!bits.msp && !position.mm) broken = "travel bits without a position";
      if (after_bus_fault) broken = "travel bits answering the first frame after a bus fault";
      if (!broken.empty()) {
        ++totals.forbidden_situations;
        if (bits.any()) {
          return "seed " + std::to_string(seed) + " step " + std::to_string(step) + ": " + broken +
                 " (command byte " + std::to_string(bits.to_byte()) + ")";
        }
      }
    }
    // The car moves the way the bits of the last answer say (a coarse hydraulic car).
    if (position.mm) {
      const CommandBits sent = controller.link().command().bits;
      if (sent.up && sent.sfy) *position.mm += sent.hsp ? 5 : 1;
      if (sent.dw) *position.mm -= sent.hsp ? 5 : 1;
    }
    CommandReply reply;
    while (controller.poll_reply(reply)) {
    }
    ControllerEvent event;
    while (controller.poll_event(event)) {
    }
  }
  return {};
}

TEST(Sch001GatingProperty, NoTravelSignalWhileAnythingForbidsIt) {
  Totals totals;
  for (unsigned seed = 1; seed <= 40; ++seed) {
    const std::string broken = run_seed(seed, totals);
    ASSERT_EQ(broken, "");
  }
  // The property must have been put to the test: travels ran, and forbidding situations came.
  EXPECT_GT(totals.with_travel_bits, 500U);
  EXPECT_GT(totals.forbidden_situations, 500U);
  RecordProperty("answers", std::to_string(totals.answers));
}

}  // namespace
}  // namespace liftd::sch001
