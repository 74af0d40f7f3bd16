#include "uss/host/sim_actions.hpp"

namespace liftd::daemon {

const api::KindSimActions kUssSimActionTable = {drive::Kind::Uss, "USS",  api::kEverySimAction, {},
                                                nullptr,          nullptr};

}  // namespace liftd::daemon
