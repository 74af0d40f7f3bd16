#include "kinds/lifts.hpp"

#include <array>
#include <cstddef>
#include <stdexcept>

#include "dcp/host/dcp_lift.hpp"
#include "sch001/host/hydraulic_lift.hpp"
#include "uss/host/uss_lift.hpp"

namespace liftd::kinds {

using namespace daemon;
namespace {

/// How one drive kind's lift is made (its commands and `sim` actions: commands.cpp).
struct DriveKindEntry {
  drive::Kind kind;
  std::unique_ptr<LiftRunner> (*make)(Host& host, const config::Config& config, bool simulate);
};

template <typename Lift>
std::unique_ptr<LiftRunner> make(Host& host, const config::Config& config, bool simulate) {
  return std::make_unique<Lift>(host, config, simulate);
}

/// Every drive kind, in the order of drive::Kind: the one place the daemon names a kind's lift.
constexpr std::array kDriveKinds = {
    DriveKindEntry{drive::Kind::Dcp, make<DcpLift>},
    DriveKindEntry{drive::Kind::Sch001, make<HydraulicLift>},
    DriveKindEntry{drive::Kind::Uss, make<UssLift>},
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

}  // namespace liftd::kinds
