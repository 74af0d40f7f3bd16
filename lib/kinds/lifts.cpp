#include "kinds/lifts.hpp"

#include <array>
#include <cstddef>
#include <stdexcept>

#include "kinds/registry.hpp"

namespace liftd::kinds {

using namespace daemon;
namespace {

/// How each drive kind's lift is made, in the order of drive::Kind.
constexpr auto kMakeLift = rows_of(
    Registry{}, [](auto entry) { return &host::make_lift<typename decltype(entry)::Lift>; });

}  // namespace

std::unique_ptr<LiftRunner> make_lift(Host& host, const config::Config& config, bool simulate) {
  const auto index = static_cast<std::size_t>(config.drive.kind);
  if (index < kMakeLift.size()) return kMakeLift[index](host, config, simulate);
  throw std::invalid_argument("drive.kind \"" + std::string(drive::to_string(config.drive.kind)) +
                              "\" is not available in this build");
}

}  // namespace liftd::kinds
