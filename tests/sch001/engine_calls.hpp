// The calls the CAN runner (lib/rt/can_runner.hpp) makes on an rt::CanEngine, for tests that
// drive the SCH001 controller by hand: a frame fed with an empty outbox and the answer taken
// out of it, a tick that must send nothing (the card is only ever answered).
#pragma once

#include <gtest/gtest.h>

#include <optional>

#include "rt/can_runner.hpp"

namespace liftd::sch001::test {

/// Feeds `frame` as the runner does; the answer the engine queued, if any.
inline std::optional<can::Frame> feed_frame(rt::CanEngine& engine, const can::Frame& frame,
                                            MonoTime now) {
  rt::CanOutbox out;
  engine.on_frame(frame, now, out);
  EXPECT_LE(out.queued().size(), 1U) << "one answer per card frame (card document 3c)";
  if (out.queued().empty()) return std::nullopt;
  return out.queued().front();
}

/// Ticks the engine as the runner does between frames.
inline void feed_tick(rt::CanEngine& engine, MonoTime now) {
  rt::CanOutbox out;
  engine.on_tick(now, out);
  EXPECT_TRUE(out.queued().empty()) << "the SCH001 controller sends answers only";
}

}  // namespace liftd::sch001::test
