// The drive kinds the parity suites run every lift scenario against, one case per registered kind
// (drive::kKindNames), each read from its kind's own test folder: tests/<kind>/e2e_case.json. A
// kind added to the registry is run by every suite below without an edit here; until its file is
// written `EveryRegisteredDriveKindHasItsCase` fails and names the file.
//
// The file's fields:
//   config               merged into the lift's configuration for `liftd --simulate`
//   refusal              what the message of a travel refused while the drive is not ready says
//   journal              what the journal says of the drive not being ready ("" for nothing)
//   fault_needs_reset    the drive latches its fault until `drive_reset` (USS C 5.2.1)
//   far_floor            a floor far enough from floor 0 for a stop mid-travel
//   link_fault           the `sim` request that breaks the drive's link at once (the DCP and USS
//                        drives' replies stop: DCP 7.3 ten in a row, USS uss.telegram_failures;
//                        the SCH001 card's CAN controller reports bus-off, so the card document's
//                        3f does not wait its 10 s)
//   learn_slow_mm_per_s  the simulated car's learning speed in the learning parity suite
//   learn_config         merged after `config` for the learning travel (optional)
//   status_keys          the keys of the kind's own object in `status` (any order)
//   stats_keys           the keys of the kind's own object in `stats` (any order)
// A key that starts with "_" is a note for the reader; any other key is refused.
#pragma once

#include <gtest/gtest.h>

#include <ostream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace liftd::e2e {

struct DriveCase {
  std::string name;  ///< the drive kind (and its journal component), the test's name
  nlohmann::json config;
  std::string refusal;
  std::string journal;
  bool fault_needs_reset = false;
  int far_floor = 0;
  nlohmann::json link_fault;
  int learn_slow_mm_per_s = 0;
  nlohmann::json learn_config = nlohmann::json::object();
  std::vector<std::string> status_keys;
  std::vector<std::string> stats_keys;
  /// The `sim` actions its simulator takes (tests/daemon/sim_actions_test.cpp): the shared
  /// ones, its own, and how the refusal of another kind's action names this lift.
  std::vector<std::string> sim_shared;
  std::vector<std::string> sim_own;
  std::string sim_lift_name;
};

inline void PrintTo(const DriveCase& c, std::ostream* out) {
  *out << c.name;
}

/// The case of every registered kind whose file reads well, in the registry's order.
const std::vector<DriveCase>& drive_cases();
/// What was wrong with the files (a missing file, a missing or mistyped field), one line each.
const std::vector<std::string>& drive_case_problems();

/// Fails the test unless every registered kind has its case.
void expect_a_case_for_every_kind();

/// The test's name of a case: its kind.
inline std::string drive_case_name(const ::testing::TestParamInfo<DriveCase>& param) {
  return param.param.name;
}

}  // namespace liftd::e2e
