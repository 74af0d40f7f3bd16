// status car.doors and service.reason (docs/api.md `status`): one table, the same for every
// drive kind, each condition alone and the order in which they win.
#include <gtest/gtest.h>

#include <string>

#include "host/lift_core.hpp"

namespace liftd::daemon {
namespace {

lift::Inputs valid_inputs() {
  lift::Inputs in;
  in.valid = true;
  in.safety_chain_closed = true;
  in.doors_closed = true;
  in.doors_locked = true;
  return in;
}

TEST(ServiceState, TheFirstReasonThatHoldsWins) {
  struct Case {
    const char* what;
    bool stopping;
    bool faulted;
    bool inspection;
    bool recall;
    bool learning;
    drive::State drive;
    const char* reason;
  };
  const Case cases[] = {
      {"in service", false, false, false, false, false, drive::State::Ready, ""},
      {"travelling is in service", false, false, false, false, false, drive::State::Travelling, ""},
      {"stopping", true, false, false, false, false, drive::State::Ready, "stopping"},
      {"stopping beats a fault", true, true, true, true, true, drive::State::Fault, "stopping"},
      {"a fault", false, true, false, false, false, drive::State::Fault, "fault"},
      {"a fault beats inspection", false, true, true, false, false, drive::State::Fault, "fault"},
      {"inspection", false, false, true, false, false, drive::State::Ready, "inspection"},
      {"inspection beats recall", false, false, true, true, false, drive::State::Ready,
       "inspection"},
      {"recall", false, false, false, true, false, drive::State::Ready, "recall"},
      {"learning", false, false, false, false, true, drive::State::Travelling, "learning"},
      {"not ready", false, false, false, false, false, drive::State::NotReady, "not_ready"},
      {"offline", false, false, false, false, false, drive::State::Offline, "not_ready"},
  };
  for (const Case& c : cases) {
    lift::Inputs in = valid_inputs();
    in.inspection = c.inspection;
    in.recall = c.recall;
    EXPECT_EQ(out_of_service(c.stopping, c.faulted, in, c.learning, c.drive), c.reason) << c.what;
  }
}

TEST(ServiceState, TheDoorsAsTheInputsShowThem) {
  lift::Inputs in = valid_inputs();
  EXPECT_EQ(door_state(in), "locked");
  in.doors_locked = false;
  EXPECT_EQ(door_state(in), "closed");
  in.doors_closed = false;
  EXPECT_EQ(door_state(in), "open");
  in.door_reversal = true;
  EXPECT_EQ(door_state(in), "reopening");
  in.valid = false;
  EXPECT_EQ(door_state(in), std::nullopt) << "no inputs yet: unknown";
}

}  // namespace
}  // namespace liftd::daemon
