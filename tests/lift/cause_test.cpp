// The one cause enum of every drive kind and its API names (docs/api.md, "Abort causes").
#include <gtest/gtest.h>

#include <array>
#include <cstddef>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <string_view>

#include "lift/cause.hpp"
#include "lift/faults.hpp"

namespace liftd::lift {
namespace {

struct CauseName {
  Cause cause;
  std::string_view name;
};

// Every enumerator in declaration order with the name the API and the journal show.
constexpr std::array kCauseNames = {
    CauseName{Cause::None, "none"},
    CauseName{Cause::LinkDown, "link_down"},
    CauseName{Cause::NoHandshake, "no_handshake"},
    CauseName{Cause::DriveNotReady, "drive_not_ready"},
    CauseName{Cause::AdvanceWarning, "advance_warning"},
    CauseName{Cause::DriveFault, "drive_fault"},
    CauseName{Cause::SafetyChainOpen, "safety_chain_open"},
    CauseName{Cause::DoorsNotLocked, "doors_not_locked"},
    CauseName{Cause::PositionLost, "position_lost"},
    CauseName{Cause::InputsLost, "inputs_lost"},
    CauseName{Cause::DoorReversal, "door_reversal"},
    CauseName{Cause::FastStartTimeout, "fast_start_timeout"},
    CauseName{Cause::StopRequested, "stop_requested"},
    CauseName{Cause::DriveDidNotStart, "drive_did_not_start"},
    CauseName{Cause::DriveDidNotStop, "drive_did_not_stop"},
    CauseName{Cause::ModeChanged, "mode_changed"},
    CauseName{Cause::StoppedOffLevel, "stopped_off_level"},
    CauseName{Cause::LevelNotReached, "level_not_reached"},
    CauseName{Cause::TargetRefused, "target_refused"},
    CauseName{Cause::ShuttingDown, "shutting_down"},
    CauseName{Cause::CardSilent, "card_silent"},
    CauseName{Cause::BusFault, "bus_fault"},
    CauseName{Cause::TravelTimeout, "travel_timeout"},
    CauseName{Cause::SpeedNotConfigured, "speed_not_configured"},
};

std::string read_docs() {
  std::ifstream in(API_DOCS_PATH);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

TEST(Cause, EveryEnumeratorHasItsApiName) {
  for (std::size_t i = 0; i < kCauseNames.size(); ++i) {
    const auto& row = kCauseNames[i];
    EXPECT_EQ(static_cast<std::size_t>(row.cause), i) << row.name << ": table out of order";
    EXPECT_EQ(to_string(row.cause), row.name);
  }
  // The enumerator after the last row has no name of its own: a new cause needs a row here.
  const auto past_the_table = static_cast<Cause>(kCauseNames.size());
  EXPECT_EQ(to_string(past_the_table), "none") << "a cause without a row in kCauseNames";
}

TEST(Cause, NamesAreUnique) {
  std::set<std::string_view> names;
  for (const auto& row : kCauseNames) {
    EXPECT_TRUE(names.insert(to_string(row.cause)).second) << "twice: " << to_string(row.cause);
  }
}

TEST(Cause, EveryCauseHasARowInTheApiDocs) {
  const std::string docs = read_docs();
  ASSERT_FALSE(docs.empty()) << API_DOCS_PATH;
  const auto section = docs.find("Abort causes (`cause`):");
  ASSERT_NE(section, std::string::npos) << "docs/api.md has no abort cause table";
  for (const auto& row : kCauseNames) {
    if (row.cause == Cause::None) continue;  // the API shows null, not "none"
    const std::string cell = "| `" + std::string(to_string(row.cause)) + "` |";
    EXPECT_NE(docs.find(cell, section), std::string::npos)
        << to_string(row.cause) << " has no row in the abort cause table of docs/api.md";
  }
}

// A kind words its drive's faults; the machine's are worded once, and a kind without a text
// of its own for a fault falls back to the shared one.
TEST(DriveFaultTexts, TheKindsTextsForItsDriveAndTheSharedOnesForTheRest) {
  constexpr DriveFaultTexts kWithAll{
      .link_fault = "L", .drive_fault = "D", .advance_warning = "W", .position_lost = "P"};
  constexpr DriveFaultTexts kWithout{
      .link_fault = "L", .drive_fault = "D", .advance_warning = {}, .position_lost = {}};
  struct Row {
    FaultCode code;
    std::string_view with_all;
    std::string_view without;
  };
  const std::array rows{
      Row{FaultCode::LinkFault, "L", "L"},
      Row{FaultCode::DriveFault, "D", "D"},
      Row{FaultCode::AdvanceWarning, "W", "internal"},
      Row{FaultCode::PositionLost, "P", "the car position is unknown or stale: no travel possible"},
      Row{FaultCode::SafetyChain, "safety chain open; drive enable is off",
          "safety chain open; drive enable is off"},
      Row{FaultCode::InputsLost, "no input update from the I/O provider within inputs.timeout_ms",
          "no input update from the I/O provider within inputs.timeout_ms"},
  };
  ASSERT_EQ(rows.size(), static_cast<std::size_t>(FaultCode::kCount)) << "a row per fault";
  for (const Row& row : rows) {
    EXPECT_EQ(kWithAll.of(row.code), row.with_all) << fault_code_name(row.code);
    EXPECT_EQ(kWithout.of(row.code), row.without) << fault_code_name(row.code);
  }
}

}  // namespace
}  // namespace liftd::lift
