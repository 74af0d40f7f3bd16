// Which configuration keys a reload may change while the drive link runs, and the plan for one
// reload: pure, so every class of key is table-tested without a daemon.
#pragma once

#include <string>
#include <vector>

#include "config/config.hpp"

namespace liftd::daemon {

/// One changed key.
struct KeyChange {
  std::string key;        ///< key path, e.g. "drive.device" or "floors"
  std::string running;    ///< the value in effect (JSON text)
  std::string requested;  ///< the value in the file (JSON text)
  /// Field-wise equality.
  friend bool operator==(const KeyChange&, const KeyChange&) = default;
};

/// The outcome of comparing the running configuration with a newly read, valid one.
struct ReloadPlan {
  config::Config effective;             ///< running, with every live key taken from the file
  std::vector<KeyChange> applied;       ///< live keys that changed
  std::vector<KeyChange> need_restart;  ///< other keys that changed; they keep running values
};

/// The keys a reload applies at once: none of them touches the drive link or the cycle.
const std::vector<std::string>& live_keys();

/// Compares `running` with `next` key by key (objects recursively; a list such as floors is
/// one key) and plans the reload; both lists are in alphabetical order of the key path.
ReloadPlan plan_reload(const config::Config& running, const config::Config& next);

}  // namespace liftd::daemon
