#include "sch001/host/sim_actions.hpp"

#include "sch001/registry_entry.hpp"

namespace liftd::daemon {

// The simulated card and hydraulic unit take no reply faults and no advance warning.
const api::KindSimActions kSch001SimActionTable = {
    drive::Kind::Sch001,
    "SCH001 (hydraulic)",
    api::kEverySimAction & ~(api::sim_action_bit(api::SimAction::AdvanceWarning) |
                             api::sim_action_bit(api::SimAction::ReplyFault) |
                             api::sim_action_bit(api::SimAction::ClearReplyFaults)),
    kSch001SimActions,
    nullptr,
    nullptr};

}  // namespace liftd::daemon

namespace liftd::sch001 {

const api::KindSimActions& RegistryEntry::sim_actions() noexcept {
  return daemon::kSch001SimActionTable;
}

}  // namespace liftd::sch001
