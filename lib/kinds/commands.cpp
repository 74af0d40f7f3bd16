#include "kinds/commands.hpp"

#include <array>
#include <cstddef>
#include <vector>

#include "api/commands.hpp"
#include "kinds/registry.hpp"

namespace liftd::kinds {
namespace {

/// Which API commands only a drive kind has and which `sim` actions its simulator takes.
struct KindCommandsEntry {
  /// Adds the kind's own commands (served when `backend` is the kind's).
  void (*add_commands)(api::Dispatcher& dispatcher, api::Backend& backend);
  /// The shared `sim` actions its simulator takes and its own.
  const api::KindSimActions& (*sim_actions)() noexcept;
  /// The commands beyond the common ones its lift offers (api::Dispatcher refuses the others).
  drive::Capabilities offers;
};

/// Every drive kind's row, in the order of drive::Kind.
constexpr auto kKindCommands = rows_of(Registry{}, [](auto entry) {
  using Entry = decltype(entry);
  return KindCommandsEntry{&Entry::add_commands, &Entry::sim_actions, Entry::kOffers};
});

}  // namespace

void add_drive_kind_commands(api::Dispatcher& dispatcher, api::Backend& backend) {
  dispatcher.set_drive_kind(
      backend.drive_kind(),
      kKindCommands.at(static_cast<std::size_t>(backend.drive_kind())).offers);
  std::vector<const api::KindSimActions*> sim_actions;
  for (const auto& entry : kKindCommands) {
    entry.add_commands(dispatcher, backend);
    sim_actions.push_back(&entry.sim_actions());
  }
  api::add_sim_command(dispatcher, backend, sim_actions);
}

const api::KindSimActions& sim_actions_of(drive::Kind kind) noexcept {
  return kKindCommands.at(static_cast<std::size_t>(kind)).sim_actions();
}

}  // namespace liftd::kinds
