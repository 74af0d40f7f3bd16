#include "api/access.hpp"

#include <grp.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <stdexcept>

namespace liftd::api {

gid_t resolve_group(const std::string& name) {
  std::vector<char> buf(16384);
  group entry{};
  group* found = nullptr;
  int rc = 0;
  while ((rc = getgrnam_r(name.c_str(), &entry, buf.data(), buf.size(), &found)) == ERANGE) {
    buf.resize(buf.size() * 2);
  }
  if (rc != 0 || found == nullptr) {
    throw std::runtime_error("api: unknown group \"" + name +
                             "\" in the access configuration (create it or change the setting)");
  }
  return found->gr_gid;
}

AccessPolicy AccessPolicy::resolve(const std::string& read_group, const std::string& control_group,
                                   const std::string& inputs_group) {
  AccessPolicy policy;
  if (!read_group.empty()) policy.read_gid = resolve_group(read_group);
  if (!control_group.empty()) policy.control_gid = resolve_group(control_group);
  if (!inputs_group.empty()) policy.inputs_gid = resolve_group(inputs_group);
  policy.owner_uid = geteuid();
  return policy;
}

AccessSet AccessPolicy::access_for(uid_t uid, const std::vector<gid_t>& gids) const {
  if (uid == 0 || (owner_uid && uid == *owner_uid)) return AccessSet{true, true, true};
  const auto member = [&gids](const std::optional<gid_t>& gid) {
    return gid && std::find(gids.begin(), gids.end(), *gid) != gids.end();
  };
  AccessSet set;
  set.control = member(control_gid);
  set.inputs = member(inputs_gid);
  set.read = member(read_gid) || set.control || set.inputs;
  return set;
}

std::optional<PeerCredentials> peer_credentials(int fd) {
  ucred cred{};
  socklen_t len = sizeof cred;
  if (getsockopt(fd, SOL_SOCKET, SO_PEERCRED, &cred, &len) != 0) return std::nullopt;
  PeerCredentials out;
  out.pid = cred.pid;
  out.uid = cred.uid;
  out.gid = cred.gid;
  out.groups.push_back(cred.gid);
#ifdef SO_PEERGROUPS
  std::vector<gid_t> groups(64);
  for (int attempt = 0; attempt < 4; ++attempt) {
    auto bytes = static_cast<socklen_t>(groups.size() * sizeof(gid_t));
    if (getsockopt(fd, SOL_SOCKET, SO_PEERGROUPS, groups.data(), &bytes) == 0) {
      groups.resize(bytes / sizeof(gid_t));
      out.groups.insert(out.groups.end(), groups.begin(), groups.end());
      break;
    }
    if (errno != ERANGE) break;
    groups.resize(std::max<std::size_t>(bytes / sizeof(gid_t), groups.size() * 2));
  }
#endif
  return out;
}

}  // namespace liftd::api
