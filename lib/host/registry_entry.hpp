// What a drive kind's entry in the registry (lib/kinds/registry.hpp) gives: its kind, its
// configuration rules, the commands it offers beyond the common ones, its `sim` actions and its
// lift. Each kind declares its entry in lib/<kind>/registry_entry.hpp with the names below only
// declared, not defined there: each part is defined in the library that builds it, so a user of
// one part (the configuration reference, the API tests) links that part only.
#pragma once

#include <concepts>
#include <memory>

#include "drive/drive.hpp"

namespace liftd::config {
struct Config;
struct KindRules;
struct FloorRules;
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

namespace liftd::host {

/// A drive kind's registry entry: a struct of static members. (Their types are compared as
/// function types: a call would need the complete types this header only declares.)
template <typename Entry>
concept RegistryEntry =
    /// Its enumerator of drive::Kind.
    std::same_as<decltype(Entry::kKind), const drive::Kind> &&
    /// Its `<kind>.*` keys, the checks across them and the summary of its drive
    /// (lib/<kind>/config/config_rules.cpp).
    std::same_as<decltype(Entry::config_rules), config::KindRules()> &&
    /// The commands it offers beyond the common ones (api::Dispatcher answers the others
    /// `not_offered`).
    std::same_as<decltype(Entry::kOffers), const drive::Capabilities> &&
    /// Adds its own commands to a lift's dispatcher, served when the backend is its lift's
    /// (lib/<kind>/host/commands.cpp; a kind without commands of its own adds none).
    std::same_as<decltype(Entry::add_commands), void(api::Dispatcher&, api::Backend&)> &&
    /// The `sim` actions its simulator takes (lib/<kind>/host/sim_actions.cpp).
    std::same_as<decltype(Entry::sim_actions), const api::KindSimActions&() noexcept> &&
    /// Its lift (a daemon::LiftRunner), made by make_lift<Entry::Lift>.
    requires {
  typename Entry::Lift;
};

/// Makes a lift of type `Lift` by its constructor (host, configuration, --simulate); throws as
/// the constructor does. Declared here only: the lift's own file instantiates it (`template ...
/// host::make_lift<DcpLift>(...)` in lib/dcp/host/dcp_lift.cpp), so the registry makes every
/// kind's lift without including its header. The definition is in host/controller_lift.hpp.
template <class Lift>
std::unique_ptr<daemon::LiftRunner> make_lift(daemon::Host& host, const config::Config& config,
                                              bool simulate);

}  // namespace liftd::host
