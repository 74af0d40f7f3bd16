// The simulated shaft: a level zone of the configured length centred on each true level.
#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "sim/shaft.hpp"

namespace liftd::sim {
namespace {

TEST(SimulatedShaft, ZonesAreCentredOnTheTrueLevels) {
  const std::vector<std::int64_t> levels = {0, 3040, 5980};
  const SimulatedShaft shaft(levels, 100);
  ASSERT_EQ(shaft.size(), 3U);
  EXPECT_TRUE(shaft.level_zone(0.0));
  EXPECT_TRUE(shaft.level_zone(-50.0));
  EXPECT_FALSE(shaft.level_zone(-50.5));
  EXPECT_TRUE(shaft.level_zone(50.0));
  EXPECT_FALSE(shaft.level_zone(50.5));
  EXPECT_FALSE(shaft.level_zone(2989.0));
  EXPECT_TRUE(shaft.level_zone(2990.0));
  EXPECT_TRUE(shaft.level_zone(3090.0));
  EXPECT_TRUE(shaft.level_zone(6030.0));
  EXPECT_FALSE(shaft.level_zone(6031.0));
}

TEST(SimulatedShaft, NoLevelsNoZone) {
  const SimulatedShaft shaft;
  EXPECT_EQ(shaft.size(), 0U);
  EXPECT_FALSE(shaft.level_zone(0.0));
}

}  // namespace
}  // namespace liftd::sim
