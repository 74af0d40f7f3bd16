// The USS drive kind's entry in the registry of drive kinds (lib/kinds/registry.hpp): what the
// daemon, the configuration and the API need of the kind. Each part is declared here and defined
// in the library that builds it, so that a user of one part links that part only.
#pragma once

#include <memory>

#include "drive/drive.hpp"

namespace liftd::config {
struct Config;
struct KindRules;
}  // namespace liftd::config
namespace liftd::api {
class Backend;
class Dispatcher;
struct KindSimActions;
}  // namespace liftd::api
namespace liftd::daemon {
class Host;
class LiftRunner;
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

  // ---- liftd::uss_host (lib/uss/host/uss_lift.cpp) ----
  /// The USS lift (daemon::UssLift). Throws as its constructor does.
  static std::unique_ptr<daemon::LiftRunner> make_lift(daemon::Host& host,
                                                       const config::Config& config,
                                                       bool simulate);
};

}  // namespace liftd::uss
