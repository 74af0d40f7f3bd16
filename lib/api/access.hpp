// Who may do what: group names resolved at start, peer credentials per connection.
#pragma once

#include <sys/types.h>

#include <optional>
#include <string>
#include <vector>

#include "api/dispatcher.hpp"

namespace liftd::api {

/// Groups named in the configuration, resolved to gids. An empty name means "nobody but root".
struct AccessPolicy {
  std::optional<gid_t> read_gid;     ///< may run read commands
  std::optional<gid_t> control_gid;  ///< may run control (and read) commands
  std::optional<gid_t> inputs_gid;   ///< may send inputs (and run read commands)
  /// The daemon's own user: a peer running as it could stop the daemon anyway, so it gets every
  /// right (this is also what lets `liftd --simulate` be driven by the user who started it).
  std::optional<uid_t> owner_uid;

  /// Resolves group names; throws std::runtime_error naming the group if one does not exist.
  static AccessPolicy resolve(const std::string& read_group, const std::string& control_group,
                              const std::string& inputs_group);
  /// Access of a peer with user `uid` and groups `gids` (primary and supplementary). Root (uid 0)
  /// and `owner_uid` may do everything.
  AccessSet access_for(uid_t uid, const std::vector<gid_t>& gids) const;
};

/// Resolves one group name to its gid; throws std::runtime_error with a clear message if unknown.
gid_t resolve_group(const std::string& name);

/// Credentials of the process at the other end of a Unix socket.
struct PeerCredentials {
  pid_t pid = 0;              ///< process id
  uid_t uid = 0;              ///< effective user id
  gid_t gid = 0;              ///< effective group id
  std::vector<gid_t> groups;  ///< primary and supplementary groups
};

/// SO_PEERCRED plus SO_PEERGROUPS (falls back to the primary group alone where the kernel lacks
/// SO_PEERGROUPS); nullopt if the socket gives no credentials.
std::optional<PeerCredentials> peer_credentials(int fd);

}  // namespace liftd::api
