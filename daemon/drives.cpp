#include "daemon/drives.hpp"

#include <stdexcept>

#include "dcp/host/lift_app.hpp"
#include "sch001/host/hydraulic_lift.hpp"
#include "uss/host/uss_lift.hpp"

namespace liftd::daemon {

std::unique_ptr<LiftRunner> make_lift(Host& host, const config::Config& config, bool simulate) {
  switch (config.drive.kind) {
    case drive::Kind::Dcp:
      return std::make_unique<LiftApp>(host, config, simulate);
    case drive::Kind::Sch001:
      return std::make_unique<HydraulicLift>(host, config, simulate);
    case drive::Kind::Uss:
      return std::make_unique<UssLift>(host, config, simulate);
  }
  throw std::invalid_argument("drive.kind \"" + std::string(drive::to_string(config.drive.kind)) +
                              "\" is not available in this build");
}

}  // namespace liftd::daemon
