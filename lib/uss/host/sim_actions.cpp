#include "uss/host/sim_actions.hpp"

#include "uss/registry_entry.hpp"

namespace liftd::daemon {

const api::KindSimActions kUssSimActionTable = {drive::Kind::Uss, "USS",  api::kEverySimAction, {},
                                                nullptr,          nullptr};

}  // namespace liftd::daemon

namespace liftd::uss {

const api::KindSimActions& RegistryEntry::sim_actions() noexcept {
  return daemon::kUssSimActionTable;
}

}  // namespace liftd::uss
