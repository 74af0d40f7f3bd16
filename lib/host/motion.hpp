// The car's motion phase for a dispatcher (docs/api.md `status` car.motion): standing, starting,
// accelerating, at speed, decelerating, levelling. Read from the running travel's own samples
// (the car's measured speed), so it means the same on every drive kind whatever its drive
// reports: the building systems' lift object names these phases (drive status: stationary,
// accelerating, at rated speed, decelerating).
#pragma once

#include <string_view>

#include "common/mono_time.hpp"
#include "host/travel_log.hpp"

namespace liftd::daemon {

/// The motion phase at the newest sample of `running`, the travel log's newest travel (nullptr:
/// none yet); `travelling`: the controller runs a travel now (one the log may not show yet).
std::string_view motion_phase(bool travelling, const RecordedTravel* running);

}  // namespace liftd::daemon
