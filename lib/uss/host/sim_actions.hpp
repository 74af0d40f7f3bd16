// The shared `sim` actions the simulated USS bus takes; it has no actions of its own.
#pragma once

#include "api/sim.hpp"

namespace liftd::daemon {

/// The USS kind's part of `sim`, for the registry of drive kinds.
extern const api::KindSimActions kUssSimActionTable;

}  // namespace liftd::daemon
