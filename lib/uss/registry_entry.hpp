// The USS drive kind's entry in the registry of drive kinds (lib/kinds/registry.hpp); the form of
// an entry is host::RegistryEntry (lib/host/registry_entry.hpp).
#pragma once

#include "host/registry_entry.hpp"

namespace liftd::daemon {
class UssLift;
}  // namespace liftd::daemon

namespace liftd::uss {

struct RegistryEntry {
  static constexpr drive::Kind kKind = drive::Kind::Uss;

  // ---- liftd::uss_config (lib/uss/config/config_rules.cpp) ----
  /// The uss.* keys, the checks a USS lift needs across them (addresses, polling list, speeds,
  /// the position source) and the summary of a USS drive.
  static config::KindRules config_rules();

  // ---- liftd::uss_commands (lib/uss/host/commands.cpp, sim_actions.cpp) ----
  /// What the USS lift offers beyond the common commands: the parameter channel (PKW, USS C 4)
  /// and `drive_reset` (fault acknowledge by STW bit 7, USS C 5.2.1).
  static constexpr drive::Capabilities kOffers =
      drive::Capabilities{}.add(drive::Capability::Parameters).add(drive::Capability::DriveReset);
  /// Adds uss_read, uss_write and uss_mirror to `dispatcher`. They are served by `backend` when
  /// it is a daemon::UssCommandBackend (the USS lift); on another kind's lift the dispatcher
  /// refuses them as `not_offered` before they reach a handler.
  static void add_commands(api::Dispatcher& dispatcher, api::Backend& backend);
  /// The `sim` actions the simulated USS bus takes.
  static const api::KindSimActions& sim_actions() noexcept;

  // ---- liftd::uss_host (lib/uss/host/uss_lift.cpp instantiates host::make_lift<Lift>) ----
  using Lift = daemon::UssLift;
};

static_assert(host::RegistryEntry<RegistryEntry>,
              "the form of an entry: lib/host/registry_entry.hpp");

}  // namespace liftd::uss
