// The SCH001 drive kind's entry in the registry of drive kinds (lib/kinds/registry.hpp); the form
// of an entry is host::RegistryEntry (lib/host/registry_entry.hpp).
#pragma once

#include "host/registry_entry.hpp"

namespace liftd::daemon {
class HydraulicLift;
}  // namespace liftd::daemon

namespace liftd::sch001 {

struct RegistryEntry {
  static constexpr drive::Kind kKind = drive::Kind::Sch001;

  // ---- liftd::sch001_config (lib/sch001/config/config_rules.cpp) ----
  /// The sch001.* keys, the checks a SCH001 lift needs (the floor count its frames carry) and
  /// the summary of a SCH001 card. The CAN endpoint (can.*) is shared: the CAN encoder uses it.
  static config::KindRules config_rules();

  // ---- liftd::sch001_commands (lib/sch001/host/sim_actions.cpp) ----
  /// The card's frames carry travel signals and floors only; its status frame has no keypad,
  /// display, supply or load: nothing beyond the common commands, and no commands of its own.
  static constexpr drive::Capabilities kOffers{};
  static void add_commands(api::Dispatcher&, api::Backend&) {}
  /// The `sim` actions the simulated card and hydraulic unit take.
  static const api::KindSimActions& sim_actions() noexcept;

  // ---- liftd::sch001_host (lib/sch001/host/hydraulic_lift.cpp instantiates host::make_lift<Lift>)
  // ----
  using Lift = daemon::HydraulicLift;
};

static_assert(host::RegistryEntry<RegistryEntry>,
              "the form of an entry: lib/host/registry_entry.hpp");

}  // namespace liftd::sch001
