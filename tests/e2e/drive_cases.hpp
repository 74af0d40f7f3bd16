// The drive kinds the parity suites run every lift scenario against: each kind's `liftd
// --simulate` configuration and what may differ between kinds (the refusal text of a drive that
// is not ready, its journal line, whether its fault latches, the sim action that breaks its link).
#pragma once

#include <gtest/gtest.h>

#include <cstddef>
#include <ostream>
#include <string>
#include <vector>

#include "drive/drive.hpp"

#include "e2e/harness.hpp"

namespace liftd::e2e {

struct DriveCase {
  const char* name;        ///< the test's name: the drive kind (and its journal component)
  json config;             ///< merged into the lift's config
  const char* refusal;     ///< what the refused travel's message says
  const char* journal;     ///< what the journal says of the drive not being ready ("" for nothing)
  bool fault_needs_reset;  ///< the drive latches its fault until `drive_reset` (USS C 5.2.1)
  int far_floor;           ///< a floor far enough for a stop mid-travel
  /// The `sim` request that breaks the drive's link at once: the DCP drive's and the USS drive's
  /// replies stop (DCP 7.3: ten in a row; USS: uss.telegram_failures), the SCH001 card's CAN
  /// controller reports bus-off (card document 3f does not wait its 10 s then).
  json link_fault;
};

inline void PrintTo(const DriveCase& c, std::ostream* out) {
  *out << c.name;
}

// Three floors 1200 mm apart for the hydraulic and USS cars, as in their own e2e tests.
inline const json kThreeFloors = json::array({{{"name", "0"}, {"level_mm", 0}},
                                              {{"name", "1"}, {"level_mm", 1200}},
                                              {{"name", "2"}, {"level_mm", 2400}}});

inline const json kNoReplies = {
    {"cmd", "sim"}, {"action", "reply_fault"}, {"fault", "no_reply"}, {"frames", 200}};

inline const DriveCase kDriveCases[] = {
    {"dcp", json::object(), "drive not ready (S0 = 0)", "", false, 4, kNoReplies},
    {"sch001",
     {{"drive", {{"kind", "sch001"}}},
      {"floors", kThreeFloors},
      {"sch001", {{"star_delta_ms", 500}, {"slowdown_up_mm", 300}, {"slowdown_down_mm", 350}}}},
     "RDY = 0",
     "[event=card_fault relays=",
     false,
     2,
     {{"cmd", "sim"}, {"action", "bus_off"}}},
    {"uss",
     {{"drive", {{"kind", "uss"}}},
      {"floors", kThreeFloors},
      {"travel", {{"dcp3_decel_distance_mm", {{"V4", 700}, {"V3", 500}}}}},
      {"uss", {{"speeds", {{"V0", 10}, {"VN", 3}, {"VI", 30}, {"V3", 63}, {"V4", 100}}}}}},
     "local control",
     "in local control (status word bit 9 = 0): no travel starts",
     true,
     2,
     kNoReplies},
};

/// Every registered drive kind (drive::kKindNames, the registry's order) has exactly one case in
/// `cases`, named `name_of(case)`: a kind added to the registry fails here until its cases are
/// written, instead of being skipped by every parametrised suite.
template <typename Case, std::size_t N, typename NameOf>
void expect_a_case_for_every_kind(const Case (&cases)[N], NameOf name_of) {
  std::vector<std::string> named;
  for (const Case& c : cases) named.emplace_back(name_of(c));
  std::vector<std::string> registered;
  for (const std::string_view kind : drive::kKindNames) registered.emplace_back(kind);
  EXPECT_EQ(named, registered);
}

/// The test's name of a case: its kind.
inline std::string drive_case_name(const ::testing::TestParamInfo<DriveCase>& param) {
  return param.param.name;
}

}  // namespace liftd::e2e
