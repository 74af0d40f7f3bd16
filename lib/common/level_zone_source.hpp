// Where the real-time side of a simulated lift reads the simulated shaft's level zone at the
// cycle's own instant (a level switch wired to an input the cycle reads with the encoder).
// Read on the real-time thread: must not block, lock or allocate.
#pragma once

#include "common/mono_time.hpp"

namespace liftd {

/// A level zone signal evaluated when asked.
class LevelZoneSource {
 public:
  virtual ~LevelZoneSource() = default;
  /// The car is inside a level zone now.
  virtual bool level_zone(MonoTime now) const noexcept = 0;
};

}  // namespace liftd
