#include "kinds/lifts.hpp"

#include <array>
#include <cstddef>
#include <stdexcept>
#include <vector>

#include "api/commands.hpp"

#include "dcp/host/commands.hpp"
#include "dcp/host/dcp_lift.hpp"
#include "dcp/host/sim_actions.hpp"
#include "sch001/host/hydraulic_lift.hpp"
#include "sch001/host/sim_actions.hpp"
#include "uss/host/commands.hpp"
#include "uss/host/sim_actions.hpp"
#include "uss/host/uss_lift.hpp"

namespace liftd::kinds {

using namespace daemon;
namespace {

/// How one drive kind's lift is made, which API commands only it has and which `sim` actions its
/// simulator takes.
struct DriveKindEntry {
  drive::Kind kind;
  std::unique_ptr<LiftRunner> (*make)(Host& host, const config::Config& config, bool simulate);
  /// Adds the kind's own commands (served when `backend` is the kind's); nullptr: none.
  void (*add_commands)(api::Dispatcher& dispatcher, api::Backend& backend);
  /// The shared `sim` actions its simulator takes and its own.
  const api::KindSimActions* sim_actions;
};

template <typename Lift>
std::unique_ptr<LiftRunner> make(Host& host, const config::Config& config, bool simulate) {
  return std::make_unique<Lift>(host, config, simulate);
}

/// Every drive kind, in the order of drive::Kind: the one place the daemon names a kind's lift.
constexpr std::array kDriveKinds = {
    DriveKindEntry{drive::Kind::Dcp, make<DcpLift>, add_dcp_commands, &kDcpSimActionTable},
    DriveKindEntry{drive::Kind::Sch001, make<HydraulicLift>, nullptr, &kSch001SimActionTable},
    DriveKindEntry{drive::Kind::Uss, make<UssLift>, add_uss_commands, &kUssSimActionTable},
};

constexpr bool in_kind_order() {
  for (std::size_t i = 0; i < kDriveKinds.size(); ++i) {
    if (static_cast<std::size_t>(kDriveKinds[i].kind) != i) return false;
  }
  return true;
}
static_assert(kDriveKinds.size() == drive::kKindNames.size(), "a drive kind without its lift");
static_assert(in_kind_order(), "kDriveKinds follows the order of drive::Kind");

}  // namespace

std::unique_ptr<LiftRunner> make_lift(Host& host, const config::Config& config, bool simulate) {
  const auto index = static_cast<std::size_t>(config.drive.kind);
  if (index < kDriveKinds.size()) return kDriveKinds[index].make(host, config, simulate);
  throw std::invalid_argument("drive.kind \"" + std::string(drive::to_string(config.drive.kind)) +
                              "\" is not available in this build");
}

void add_drive_kind_commands(api::Dispatcher& dispatcher, api::Backend& backend) {
  std::vector<const api::KindSimActions*> sim_actions;
  for (const auto& entry : kDriveKinds) {
    if (entry.add_commands != nullptr) entry.add_commands(dispatcher, backend);
    sim_actions.push_back(entry.sim_actions);
  }
  api::add_sim_command(dispatcher, backend, sim_actions);
}

}  // namespace liftd::kinds
