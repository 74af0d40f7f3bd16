// The machine inputs on their way from the API (and the simulated machine) to the sequencers:
// every input docs/api.md lists must reach lift::Inputs, and under --simulate the API adds the
// shaft signals without its defaults overriding the simulated machine.
#include <gtest/gtest.h>

#include "host/lift_common.hpp"

namespace liftd::daemon {
namespace {

/// Index of the API input `name` in kInputFlags (and InputUpdate::flags).
std::size_t flag(std::string_view name) {
  for (std::size_t i = 0; i < api::kInputFlags.size(); ++i) {
    if (api::kInputFlags[i].name == name) return i;
  }
  ADD_FAILURE() << name << " is not an API input";
  return 0;
}

api::InputUpdate set_only(std::size_t flag, bool value) {
  api::InputUpdate update;
  update.flags[flag] = value;
  return update;
}

TEST(MachineInputs, EveryApiInputReachesTheSequencersInputs) {
  const config::Config config;
  for (std::size_t i = 0; i < api::kInputFlags.size(); ++i) {
    MachineInputs inputs(config, nullptr, false);
    const lift::Inputs before = *inputs.current();
    ASSERT_EQ(inputs.update(set_only(i, true)), std::nullopt);
    EXPECT_NE(*inputs.current(), before)
        << api::kInputFlags[i].name << " is accepted by the API but never reaches the logic";
  }
}

TEST(MachineInputs, EachSpeedsDecelerationPointArrivesForItsOwnSpeedAndDirection) {
  const config::Config config;
  struct DecelCase {
    std::string_view name;
    int speed;
    lift::Direction direction;
  };
  const DecelCase cases[] = {
      {"decel_v1_up", 1, lift::Direction::Up}, {"decel_v1_down", 1, lift::Direction::Down},
      {"decel_v2_up", 2, lift::Direction::Up}, {"decel_v2_down", 2, lift::Direction::Down},
      {"decel_v3_up", 3, lift::Direction::Up}, {"decel_v3_down", 3, lift::Direction::Down},
      {"decel_v4_up", 4, lift::Direction::Up}, {"decel_v4_down", 4, lift::Direction::Down},
      {"decel_v5_up", 5, lift::Direction::Up}, {"decel_v5_down", 5, lift::Direction::Down},
      {"decel_v6_up", 6, lift::Direction::Up}, {"decel_v6_down", 6, lift::Direction::Down},
      {"decel_v7_up", 7, lift::Direction::Up}, {"decel_v7_down", 7, lift::Direction::Down},
  };
  for (const DecelCase& c : cases) {
    MachineInputs inputs(config, nullptr, false);
    ASSERT_EQ(inputs.update(set_only(flag(c.name), true)), std::nullopt);
    const lift::Inputs in = *inputs.current();
    for (int speed = 0; speed <= 8; ++speed) {
      for (const auto d : {lift::Direction::Up, lift::Direction::Down, lift::Direction::None}) {
        EXPECT_EQ(in.decel_point(speed, d), speed == c.speed && d == c.direction)
            << c.name << " seen as V" << speed << " direction " << static_cast<int>(d);
      }
    }
  }
}

TEST(MachineInputs, DoorReversalAndRelevelSignalsArrive) {
  const config::Config config;
  MachineInputs inputs(config, nullptr, false);
  ASSERT_EQ(inputs.update(set_only(flag("door_reversal"), true)), std::nullopt);
  EXPECT_TRUE(inputs.current()->door_reversal);
  EXPECT_TRUE(inputs.seen().door_reversal);
  ASSERT_EQ(inputs.update(set_only(flag("relevel_up"), true)), std::nullopt);
  EXPECT_TRUE(inputs.current()->relevel_up);
  EXPECT_TRUE(inputs.current()->relevel_towards(lift::Direction::Up));
  EXPECT_FALSE(inputs.current()->relevel_towards(lift::Direction::Down));
}

TEST(MachineInputs, APositionIsRefusedUnlessTheApiIsThePositionSource) {
  config::Config config;
  config.position.source = config::PositionSource::sim;
  MachineInputs inputs(config, nullptr, false);
  api::InputUpdate update;
  update.position_mm = 1200;
  update.flags[flag("safety_chain")] = true;
  const auto refused = inputs.update(update);
  ASSERT_TRUE(refused.has_value());
  EXPECT_FALSE(inputs.seen().safety_chain) << "a refused update changes nothing";
  EXPECT_EQ(inputs.seen().position_mm, std::nullopt);
}

TEST(MachineInputs, UnderSimulateTheApiAddsShaftSignalsAndNeverOverridesTheMachine) {
  const config::Config config;
  MachineInputs inputs(config, nullptr, true);
  EXPECT_EQ(inputs.current(), std::nullopt) << "nothing goes out before the machine's sample";
  lift::Inputs machine;
  machine.valid = true;
  machine.safety_chain_closed = true;
  machine.doors_closed = true;
  machine.doors_locked = true;
  machine.end_zone_bottom = true;
  inputs.simulated_sample(machine);
  // An update naming only shaft signals and a door reversal: the API's default "safety chain
  // open" and "doors open" must not reach the cycle.
  api::InputUpdate update;
  for (const auto* name : {"zone_level", "decel_v3_down", "door_reversal", "relevel_down"}) {
    update.flags[flag(name)] = true;
  }
  ASSERT_EQ(inputs.update(update), std::nullopt);
  const lift::Inputs out = *inputs.current();
  EXPECT_TRUE(out.safety_chain_closed);
  EXPECT_TRUE(out.doors_closed);
  EXPECT_TRUE(out.doors_locked);
  EXPECT_TRUE(out.end_zone_bottom) << "the machine's end zone stays";
  EXPECT_TRUE(out.level_zone);
  EXPECT_TRUE(out.relevel_down);
  EXPECT_TRUE(out.decel_point(3, lift::Direction::Down));
  EXPECT_TRUE(out.door_reversal);
  // A door reversal of the simulated machine counts as well.
  ASSERT_EQ(inputs.update(set_only(flag("door_reversal"), false)), std::nullopt);
  machine.door_reversal = true;
  inputs.simulated_sample(machine);
  EXPECT_TRUE(inputs.current()->door_reversal);
}

TEST(MachineInputs, EveryApiInputReadsBackAsTheCycleSeesIt) {
  // from_lift is to_lift's inverse for every input the API names: the `inputs` result under
  // --simulate (MachineInputs::seen) shows each one as the cycle took it.
  for (const api::InputFlag& f : api::kInputFlags) {
    api::Inputs one;
    one.*(f.member) = true;
    const api::Inputs back = from_lift(to_lift(one));
    for (const api::InputFlag& g : api::kInputFlags) {
      EXPECT_EQ(back.*(g.member), &g == &f) << f.name << " read back as " << g.name;
    }
  }
  const config::Config config;
  MachineInputs inputs(config, nullptr, true);
  lift::Inputs machine;
  machine.valid = true;
  machine.safety_chain_closed = true;
  machine.doors_locked = true;
  inputs.simulated_sample(machine);
  ASSERT_EQ(inputs.update(set_only(flag("zone_level"), true)), std::nullopt);
  EXPECT_TRUE(inputs.seen().safety_chain) << "the machine's chain, not the API's default";
  EXPECT_TRUE(inputs.seen().doors_locked);
  EXPECT_TRUE(inputs.seen().zone_level) << "the API's shaft signal";
}

}  // namespace
}  // namespace liftd::daemon
