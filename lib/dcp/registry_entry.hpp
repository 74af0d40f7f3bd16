// The DCP drive kind's entry in the registry of drive kinds (lib/kinds/registry.hpp); the form of
// an entry is host::RegistryEntry (lib/host/registry_entry.hpp).
#pragma once

#include "host/registry_entry.hpp"

namespace liftd::daemon {
class DcpLift;
}  // namespace liftd::daemon

namespace liftd::dcp {

struct RegistryEntry {
  static constexpr drive::Kind kKind = drive::Kind::Dcp;

  // ---- liftd::dcp_config (lib/dcp/config/config_rules.cpp) ----
  /// The dcp.* keys and the summary of a DCP drive (no cross-check: each dcp.* key stands alone).
  static config::KindRules config_rules();
  /// Floor names in the display character set (DCP appendix A), the same name where the display
  /// shows two alike, and levels within I9's six digits of mm (DCP 5.12.9).
  static config::FloorRules floor_rules();

  // ---- liftd::dcp_commands (lib/dcp/host/commands.cpp, sim_actions.cpp) ----
  /// What the DCP lift offers beyond the common commands: its own (display, keypad, power,
  /// load, fast start and fast stop) and `drive_reset` (I2 'R'), not the USS parameter channel.
  static constexpr drive::Capabilities kOffers = drive::Capabilities{}
                                                     .add(drive::Capability::Keypad)
                                                     .add(drive::Capability::Display)
                                                     .add(drive::Capability::Power)
                                                     .add(drive::Capability::Load)
                                                     .add(drive::Capability::DriveReset)
                                                     .add(drive::Capability::FastStart)
                                                     .add(drive::Capability::FastStop);
  /// Adds display, key, power, load, fast_stop and fast_start to `dispatcher`. They are served
  /// by `backend` when it is a daemon::DcpCommandBackend (the DCP lift); on another kind's lift
  /// the dispatcher refuses them as `not_offered` before they reach a handler.
  static void add_commands(api::Dispatcher& dispatcher, api::Backend& backend);
  /// The `sim` actions the simulated DCP drive takes.
  static const api::KindSimActions& sim_actions() noexcept;

  // ---- liftd::dcp_host (lib/dcp/host/dcp_lift.cpp instantiates host::make_lift<Lift>) ----
  using Lift = daemon::DcpLift;
};

static_assert(host::RegistryEntry<RegistryEntry>,
              "the form of an entry: lib/host/registry_entry.hpp");

}  // namespace liftd::dcp
