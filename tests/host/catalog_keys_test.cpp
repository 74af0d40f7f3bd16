// The journal catalog key of every fault code (raised and cleared) and every abort cause, and
// that a record's MESSAGE_ID follows that key whatever the record's text fields say.
#include "host/catalog_keys.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "log/catalog.hpp"
#include "log/journal.hpp"

namespace liftd::daemon {
namespace {

using lift::Cause;
using lift::FaultCode;
using log::Catalogued;

struct FaultKeys {
  FaultCode code;
  std::optional<Catalogued> raised;
  std::optional<Catalogued> cleared;
};

// Every fault code in declaration order (systemd/liftd.catalog, docs/operations.md).
const std::array kFaultKeys = {
    FaultKeys{FaultCode::LinkFault, Catalogued::LinkLost, Catalogued::LinkRestored},
    FaultKeys{FaultCode::DriveFault, Catalogued::DriveFault, std::nullopt},
    FaultKeys{FaultCode::SafetyChain, Catalogued::SafetyChainOpen, std::nullopt},
    FaultKeys{FaultCode::InputsLost, Catalogued::InputsLost, std::nullopt},
    FaultKeys{FaultCode::PositionLost, Catalogued::PositionLost, std::nullopt},
    FaultKeys{FaultCode::AdvanceWarning, Catalogued::DriveAdvanceWarning, std::nullopt},
};

struct AbortKey {
  Cause cause;
  Catalogued key;
};

// Every cause in declaration order: only an opened safety chain has an entry of its own.
constexpr std::array kAbortKeys = {
    AbortKey{Cause::None, Catalogued::TravelAborted},
    AbortKey{Cause::LinkDown, Catalogued::TravelAborted},
    AbortKey{Cause::NoHandshake, Catalogued::TravelAborted},
    AbortKey{Cause::DriveNotReady, Catalogued::TravelAborted},
    AbortKey{Cause::AdvanceWarning, Catalogued::TravelAborted},
    AbortKey{Cause::DriveFault, Catalogued::TravelAborted},
    AbortKey{Cause::SafetyChainOpen, Catalogued::SafetyChainOpenedMidTravel},
    AbortKey{Cause::DoorsNotLocked, Catalogued::TravelAborted},
    AbortKey{Cause::PositionLost, Catalogued::TravelAborted},
    AbortKey{Cause::InputsLost, Catalogued::TravelAborted},
    AbortKey{Cause::DoorReversal, Catalogued::TravelAborted},
    AbortKey{Cause::FastStartTimeout, Catalogued::TravelAborted},
    AbortKey{Cause::StopRequested, Catalogued::TravelAborted},
    AbortKey{Cause::DriveDidNotStart, Catalogued::TravelAborted},
    AbortKey{Cause::DriveDidNotStop, Catalogued::TravelAborted},
    AbortKey{Cause::ModeChanged, Catalogued::TravelAborted},
    AbortKey{Cause::StoppedOffLevel, Catalogued::TravelAborted},
    AbortKey{Cause::LevelNotReached, Catalogued::TravelAborted},
    AbortKey{Cause::TargetRefused, Catalogued::TravelAborted},
    AbortKey{Cause::ShuttingDown, Catalogued::TravelAborted},
    AbortKey{Cause::CardSilent, Catalogued::TravelAborted},
    AbortKey{Cause::BusFault, Catalogued::TravelAborted},
    AbortKey{Cause::TravelTimeout, Catalogued::TravelAborted},
    AbortKey{Cause::SpeedNotConfigured, Catalogued::TravelAborted},
};

TEST(CatalogKeys, EveryFaultCodeRaisedAndClearedHasItsDecision) {
  ASSERT_EQ(kFaultKeys.size(), static_cast<std::size_t>(FaultCode::kCount))
      << "a fault code without a row in kFaultKeys: decide its catalog entries";
  for (std::size_t i = 0; i < kFaultKeys.size(); ++i) {
    const FaultKeys& row = kFaultKeys[i];
    const std::string name(lift::fault_code_name(row.code));
    EXPECT_EQ(static_cast<std::size_t>(row.code), i) << name << ": table out of order";
    EXPECT_EQ(fault_catalog_key(row.code, true), row.raised) << name << " raised";
    EXPECT_EQ(fault_catalog_key(row.code, false), row.cleared) << name << " cleared";
  }
  EXPECT_EQ(fault_catalog_key(FaultCode::kCount, true), std::nullopt);
  EXPECT_EQ(fault_catalog_key(FaultCode::kCount, false), std::nullopt);
}

TEST(CatalogKeys, EveryAbortCauseHasItsDecision) {
  for (std::size_t i = 0; i < kAbortKeys.size(); ++i) {
    const AbortKey& row = kAbortKeys[i];
    EXPECT_EQ(static_cast<std::size_t>(row.cause), i) << lift::to_string(row.cause);
    EXPECT_EQ(abort_catalog_key(row.cause), row.key) << lift::to_string(row.cause);
  }
  // The enumerator after the last row has no name of its own: a new cause needs a row here.
  const auto past_the_table = static_cast<Cause>(kAbortKeys.size());
  EXPECT_EQ(lift::to_string(past_the_table), "none") << "a cause without a row in kAbortKeys";
}

TEST(CatalogKeys, FaultRecordGetsTheIdOfItsKeyWhateverItsCodeText) {
  // Legend: the code text a fault record carries -> the MESSAGE_ID it gets, which follows the
  // typed fault alone (link_fault raised: link_lost).
  const auto key = fault_catalog_key(FaultCode::LinkFault, true);
  ASSERT_TRUE(key.has_value());
  for (const char* code_text : {"link_fault", "link_fault_renamed", "drive_fault", ""}) {
    const log::Fields fields{{"code", code_text}};
    log::Record record;
    record.level = log::Level::warn;
    record.component = "safety";
    record.event = "fault_raised";
    record.fields = &fields;
    record.text = "fault: link lost";
    record.catalogued = key;
    const auto journal = log::journal_fields(record, "liftd");
    std::vector<std::string> ids;
    for (const auto& [name, value] : journal) {
      if (name == "MESSAGE_ID") ids.push_back(value);
    }
    EXPECT_EQ(ids, std::vector<std::string>{"91c498ffaa7944c9a9ac4f8ca304a670"}) << code_text;
  }
}

}  // namespace
}  // namespace liftd::daemon
