// Each drive kind's rules: its keys are checked for type and range whatever the kind, its
// cross-check and its summary apply only when `drive.kind` names it, and the floor rules are the
// ones the schema was given.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <vector>

#include "config/config.hpp"
#include "config/schema.hpp"
#include "drive/drive.hpp"
#include "kinds/config_schema.hpp"

namespace liftd::config {
namespace {

using nlohmann::json;
using ::testing::HasSubstr;

std::string problems_of(const LoadResult& result) {
  std::string out;
  for (const auto& p : result.problems) out += to_string(p) + "\n";
  return out;
}

// A USS section whose keys each have a good type and range but which disagree with each other
// (and with position.source): only a USS lift is refused for it.
std::string uss_mismatch(std::string_view kind) {
  return R"({"drive": {"kind": ")" + std::string(kind) + R"("},
             "position": {"source": "can"},
             "uss": {"slaves": [{"address": 0}], "polling_list": [4],
                     "speeds": {"V0": 5, "VN": 2, "VI": 30, "V3": 63, "V4": 200.5}}})";
}

// The top CMakeLists.txt's LIFTD_DRIVE_KINDS (what the registry, the API tests and the layer
// check link and read) names the registry's kinds in its order: a kind in one and not the other
// would be built without being run, or run without its libraries.
TEST(KindRules, TheBuildsKindsAreTheRegistrysKinds) {
  std::vector<std::string> registered;
  for (const std::string_view kind : drive::kKindNames) registered.emplace_back(kind);
  std::vector<std::string> built;
  std::string list = LIFTD_DRIVE_KINDS;
  for (std::size_t at = 0; at <= list.size();) {
    const std::size_t comma = std::min(list.find(',', at), list.size());
    built.push_back(list.substr(at, comma - at));
    at = comma + 1;
  }
  EXPECT_EQ(built, registered);
}

TEST(KindRules, UssCrossCheckRunsOnlyForAUssLift) {
  const LoadResult uss = kinds::parse_config(uss_mismatch("uss"), "test.json");
  const std::string refused = problems_of(uss);
  EXPECT_THAT(refused, HasSubstr("position.source: \"can\" is not available with drive.kind"));
  EXPECT_THAT(refused, HasSubstr("uss.slaves[0].address: 0 is uss.drive_address"));
  EXPECT_THAT(refused, HasSubstr("uss.polling_list[0]: 4 is neither uss.drive_address"));
  EXPECT_THAT(refused, HasSubstr("uss.polling_list: never polls the drive"));
  EXPECT_THAT(refused, HasSubstr("uss.speeds.V4: 200.5 does not fit the signed setpoint word"));
  EXPECT_EQ(uss.problems.size(), 5U) << refused;
  for (const char* other : {"dcp", "sch001"}) {
    const LoadResult r = kinds::parse_config(uss_mismatch(other), "test.json");
    EXPECT_TRUE(r.ok()) << other << ": " << problems_of(r);
  }
}

TEST(KindRules, EveryKindsKeysAreCheckedForTypeAndRangeWhateverTheKind) {
  // Legend: the drive kind in use -> a bad key of another kind's section, refused all the same.
  const std::vector<std::pair<std::string, std::string>> cases = {
      {R"({"drive": {"kind": "dcp"}, "uss": {"baud": 12345}})", "uss.baud"},
      {R"({"drive": {"kind": "dcp"}, "sch001": {"controller_node": 0}})", "sch001.controller_node"},
      {R"({"drive": {"kind": "uss"}, "dcp": {"manufacturer": "ZA"}})", "dcp.manufacturer"},
      {R"({"drive": {"kind": "sch001"}, "uss": {"slaves": [{"address": 32}]}})",
       "uss.slaves[0].address"},
  };
  for (const auto& [text, where] : cases) {
    const LoadResult r = kinds::parse_config(text, "test.json");
    ASSERT_EQ(r.problems.size(), 1U) << text << "\n" << problems_of(r);
    EXPECT_EQ(r.problems[0].where, where) << text;
  }
}

// A schema of the framework alone: two made-up kinds whose cross-checks say that they ran.
Schema schema_with_recording_kinds() {
  Schema recording;
  recording.add(drive_keys());
  for (const DriveKind kind : {DriveKind::Dcp, DriveKind::Uss}) {
    KindRules rules;
    rules.kind = kind;
    rules.check = [kind](const Config&, const json&, Problems& problems) {
      problems.push_back({"check", std::string(drive::to_string(kind))});
    };
    rules.summary = [kind](const Config&) {
      return "kind:     " + std::string(drive::to_string(kind)) + "\n";
    };
    recording.add(std::move(rules));
  }
  return recording;
}

TEST(KindRules, OnlyTheCrossCheckOfTheKindInUseRuns) {
  const Schema recording = schema_with_recording_kinds();
  // Legend: drive.kind -> the checks that ran ("" for a kind the schema has no rules for).
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"dcp", "check: dcp\n"}, {"uss", "check: uss\n"}, {"sch001", ""}};
  for (const auto& [kind, ran] : cases) {
    const LoadResult r = parse(R"({"drive": {"kind": ")" + kind + R"("}})", "test.json", recording);
    EXPECT_EQ(problems_of(r), ran) << kind;
  }
}

TEST(KindRules, TheSummaryDescribesTheDriveAsItsKindSays) {
  const Schema recording = schema_with_recording_kinds();
  Config config;
  config.drive.kind = DriveKind::Uss;
  EXPECT_THAT(summary(config, recording), HasSubstr("kind:     uss\n"));
  // A kind without rules in the schema gets the plain drive line.
  config.drive.kind = DriveKind::Sch001;
  EXPECT_THAT(summary(config, recording),
              HasSubstr("drive:    sch001 on /dev/ttyS1 (rs485 auto)\n"));
}

TEST(KindRules, FloorsFollowTheRulesTheSchemaWasGiven) {
  FloorRules digits;
  digits.charset_name = "the digits";
  digits.charset_details = "0-9";
  digits.shown_as = [](std::string_view name) -> std::optional<std::string> {
    if (name.find_first_not_of("0123456789") != std::string_view::npos) return std::nullopt;
    return std::string(name);
  };
  digits.max_level_mm = 10000;
  Schema floors_only;
  floors_only.add(floors_keys(digits));
  const LoadResult letter =
      parse(R"({"floors": [{"name": "0", "level_mm": 0}, {"name": "A", "level_mm": 3000}]})", "f",
            floors_only);
  ASSERT_EQ(letter.problems.size(), 1U) << problems_of(letter);
  EXPECT_EQ(letter.problems[0].where, "floors[1].name");
  EXPECT_THAT(letter.problems[0].message,
              HasSubstr("1..16 printable characters of the digits (0-9), no space"));
  const LoadResult high =
      parse(R"({"floors": [{"name": "0", "level_mm": 0}, {"name": "1", "level_mm": 10001}]})", "f",
            floors_only);
  ASSERT_EQ(high.problems.size(), 1U) << problems_of(high);
  EXPECT_THAT(high.problems[0].message, HasSubstr("allowed -10000..10000"));
  EXPECT_THAT(reference_markdown(floors_only),
              HasSubstr("name 1..16 characters of the digits, unique, no space at either end; "
                        "level_mm -10000..10000, strictly increasing"));
}

}  // namespace
}  // namespace liftd::config
