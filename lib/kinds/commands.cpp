#include "kinds/commands.hpp"

#include <array>
#include <cstddef>
#include <vector>

#include "api/commands.hpp"

#include "dcp/host/commands.hpp"
#include "dcp/host/sim_actions.hpp"
#include "sch001/host/sim_actions.hpp"
#include "uss/host/commands.hpp"
#include "uss/host/sim_actions.hpp"

namespace liftd::kinds {
namespace {

using namespace daemon;

/// Which API commands only a drive kind has and which `sim` actions its simulator takes.
struct KindCommandsEntry {
  drive::Kind kind;
  /// Adds the kind's own commands (served when `backend` is the kind's); nullptr: none.
  void (*add_commands)(api::Dispatcher& dispatcher, api::Backend& backend);
  /// The shared `sim` actions its simulator takes and its own.
  const api::KindSimActions* sim_actions;
  /// The commands beyond the common ones its lift offers (api::Dispatcher refuses the others).
  drive::Capabilities offers;
};

/// Every drive kind, in the order of drive::Kind.
constexpr std::array kKindCommands = {
    KindCommandsEntry{drive::Kind::Dcp, add_dcp_commands, &kDcpSimActionTable, kDcpOffers},
    // The SCH001 card's frames carry travel signals and floors only; its status frame has no
    // keypad, display, supply or load: nothing beyond the common commands.
    KindCommandsEntry{drive::Kind::Sch001, nullptr, &kSch001SimActionTable, {}},
    KindCommandsEntry{drive::Kind::Uss, add_uss_commands, &kUssSimActionTable, kUssOffers},
};

constexpr bool in_kind_order() {
  for (std::size_t i = 0; i < kKindCommands.size(); ++i) {
    if (static_cast<std::size_t>(kKindCommands[i].kind) != i) return false;
  }
  return true;
}
static_assert(kKindCommands.size() == drive::kKindNames.size(),
              "a drive kind without its row of commands and sim actions");
static_assert(in_kind_order(), "kKindCommands follows the order of drive::Kind");

}  // namespace

void add_drive_kind_commands(api::Dispatcher& dispatcher, api::Backend& backend) {
  dispatcher.set_drive_kind(
      backend.drive_kind(),
      kKindCommands.at(static_cast<std::size_t>(backend.drive_kind())).offers);
  std::vector<const api::KindSimActions*> sim_actions;
  for (const auto& entry : kKindCommands) {
    if (entry.add_commands != nullptr) entry.add_commands(dispatcher, backend);
    sim_actions.push_back(entry.sim_actions);
  }
  api::add_sim_command(dispatcher, backend, sim_actions);
}

const api::KindSimActions& sim_actions_of(drive::Kind kind) noexcept {
  return *kKindCommands.at(static_cast<std::size_t>(kind)).sim_actions;
}

}  // namespace liftd::kinds
