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

}  // namespace
}  // namespace liftd::lift
