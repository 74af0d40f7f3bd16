// The registry of drive kinds: every kind's entry (lib/<kind>/registry_entry.hpp), in the order of
// drive::Kind (LIFTD_DRIVE_KINDS of the top CMakeLists.txt). The one file outside a kind's folders
// that includes a kind's header; the configuration schema (config_schema.cpp), the API commands
// (commands.cpp) and the lifts (lifts.cpp) read every kind from here, each linking the part of
// the entry it uses. A new kind: its folder, its name in LIFTD_DRIVE_KINDS and its line below.
#pragma once

#include <array>
#include <cstddef>

#include "dcp/registry_entry.hpp"
#include "drive/drive.hpp"
#include "sch001/registry_entry.hpp"
#include "uss/registry_entry.hpp"

namespace liftd::kinds {

template <typename... Entries>
struct EntryList {};

/// Every drive kind's entry.
using Registry = EntryList<dcp::RegistryEntry,     // DCP3/DCP4 drives on RS485
                           sch001::RegistryEntry,  // the SCH001 hydraulic card on CAN
                           uss::RegistryEntry>;    // Siemens USS drives on RS485

/// Floor names and levels follow the DCP display (appendix A) and I9 (DCP 5.12.9) on every kind,
/// so that a building's floors stay valid when its drive changes.
using FloorRulesOf = dcp::RegistryEntry;

/// An array of `row(Entry{})` for each entry, in the registry's order.
template <typename Row, typename... Entries>
constexpr auto rows_of(EntryList<Entries...>, Row row) {
  return std::array{row(Entries{})...};
}

/// `visit(Entry{})` for each entry, in the registry's order.
template <typename Visit, typename... Entries>
constexpr void for_each_entry(EntryList<Entries...>, Visit&& visit) {
  (visit(Entries{}), ...);
}

template <typename... Entries>
constexpr bool in_kind_order(EntryList<Entries...>) {
  constexpr std::array kinds{Entries::kKind...};
  if (kinds.size() != drive::kKindNames.size()) return false;
  for (std::size_t i = 0; i < kinds.size(); ++i) {
    if (static_cast<std::size_t>(kinds[i]) != i) return false;
  }
  return true;
}
static_assert(in_kind_order(Registry{}),
              "the registry holds one entry per drive::Kind (LIFTD_DRIVE_KINDS), in its order");

}  // namespace liftd::kinds
