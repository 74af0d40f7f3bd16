// Monotonic time as passed into every sans-I/O engine.
#pragma once

#include <chrono>

namespace liftd {

/// A point on the monotonic clock: nanoseconds since an arbitrary epoch. Production code reads
/// CLOCK_MONOTONIC; tests pass a fake clock. Engines never read a clock themselves.
using MonoTime = std::chrono::nanoseconds;

/// CLOCK_MONOTONIC now.
MonoTime mono_now() noexcept;

}  // namespace liftd
