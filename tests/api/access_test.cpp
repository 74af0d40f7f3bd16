// Access control: group resolution, root, and real unprivileged peers (forked children that
// drop to another uid; only possible when the test runs as root).
#include <grp.h>
#include <sys/wait.h>

#include <vector>

#include "api/access.hpp"
#include "api/test_support.hpp"

namespace liftd::api::testing {
namespace {

using nlohmann::json;

TEST(AccessPolicy, RootMayDoEverything) {
  const AccessPolicy policy;  // no groups configured at all
  const AccessSet root = policy.access_for(0, {0});
  EXPECT_TRUE(root.read && root.control && root.inputs);
  const AccessSet other = policy.access_for(1000, {1000});
  EXPECT_FALSE(other.read || other.control || other.inputs);
}

TEST(AccessPolicy, GroupsGrantTheirLevelAndRead) {
  AccessPolicy policy;
  policy.read_gid = 10;
  policy.control_gid = 20;
  policy.inputs_gid = 30;
  // Legend: the peer's groups, then whether it may read, control, send inputs.
  struct Case {
    std::vector<gid_t> gids;
    bool read, control, inputs;
  };
  const Case cases[] = {
      {{5}, false, false, false},    // in none of the groups
      {{10}, true, false, false},    // read group
      {{5, 20}, true, true, false},  // control group as a supplementary group
      {{30}, true, false, true},     // inputs group
      {{10, 20, 30}, true, true, true},
  };
  for (const auto& c : cases) {
    const AccessSet set = policy.access_for(1000, c.gids);
    EXPECT_EQ(set.read, c.read);
    EXPECT_EQ(set.control, c.control);
    EXPECT_EQ(set.inputs, c.inputs);
  }
}

TEST(AccessPolicy, ResolvesKnownGroupsAndNamesUnknownOnes) {
  EXPECT_EQ(resolve_group("root"), 0U);
  try {
    resolve_group("no-such-group-for-liftd");
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("no-such-group-for-liftd"), std::string::npos);
  }
}

/// What a child running as another user saw.
struct ChildResult {
  int connect_errno = 0;           ///< 0 if connect() worked
  std::vector<std::string> lines;  ///< greeting and reply lines
};

/// In a forked child: switches to uid/gid/groups (exits 3 if it cannot) and connects to `path`.
/// The connected socket, or -errno. Only async-signal-safe calls.
int child_connect(const std::string& path, uid_t uid, gid_t gid, const std::vector<gid_t>& groups) {
  if (::setgroups(groups.size(), groups.data()) != 0 || ::setgid(gid) != 0 || ::setuid(uid) != 0) {
    ::_exit(3);
  }
  const int fd = ::socket(AF_UNIX, SOCK_STREAM, 0);
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  std::strncpy(addr.sun_path, path.c_str(), sizeof addr.sun_path - 1);
  if (::connect(fd, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) != 0) return -errno;
  return fd;
}

/// Forks a child that switches to uid/gid/groups, connects, sends `requests` and reads one line
/// per request plus the greeting. Only async-signal-safe calls in the child.
ChildResult run_as(const std::string& path, uid_t uid, gid_t gid, std::vector<gid_t> groups,
                   const std::vector<std::string>& requests) {
  std::string script;
  for (const auto& r : requests) script += r + "\n";
  const std::size_t expect_lines = requests.size() + 1;
  int pipe_fds[2];
  EXPECT_EQ(::pipe(pipe_fds), 0);
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::close(pipe_fds[0]);
    const int out = pipe_fds[1];
    const int fd = child_connect(path, uid, gid, groups);
    if (fd < 0) {
      const int error = -fd;
      (void)!::write(out, &error, sizeof error);
      ::_exit(0);
    }
    const int ok = 0;
    (void)!::write(out, &ok, sizeof ok);
    (void)!::write(fd, script.data(), script.size());
    std::size_t newlines = 0;
    char buf[4096];
    while (newlines < expect_lines) {
      const ssize_t n = ::read(fd, buf, sizeof buf);
      if (n <= 0) break;
      for (ssize_t i = 0; i < n; ++i) newlines += buf[i] == '\n' ? 1 : 0;
      (void)!::write(out, buf, static_cast<std::size_t>(n));
    }
    ::_exit(0);
  }
  ::close(pipe_fds[1]);
  ChildResult result;
  std::string data;
  char buf[4096];
  ssize_t n;
  while ((n = ::read(pipe_fds[0], buf, sizeof buf)) > 0)
    data.append(buf, static_cast<std::size_t>(n));
  ::close(pipe_fds[0]);
  int status = 0;
  ::waitpid(pid, &status, 0);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "child failed to switch user";
  if (data.size() < sizeof(int)) return result;
  std::memcpy(&result.connect_errno, data.data(), sizeof(int));
  data.erase(0, sizeof(int));
  std::size_t nl;
  while ((nl = data.find('\n')) != std::string::npos) {
    result.lines.push_back(data.substr(0, nl));
    data.erase(0, nl + 1);
  }
  return result;
}

/// One byte with room for one descriptor (SCM_RIGHTS), for sendmsg and recvmsg alike.
struct FdMessage {
  FdMessage() {
    msg.msg_iov = &iov;
    msg.msg_iovlen = 1;
    msg.msg_control = control;
    msg.msg_controllen = sizeof control;
  }
  FdMessage(const FdMessage&) = delete;
  FdMessage& operator=(const FdMessage&) = delete;
  char byte = 'x';
  iovec iov{&byte, 1};
  alignas(cmsghdr) char control[CMSG_SPACE(sizeof(int))] = {};
  msghdr msg{};
};

/// A socket connected by a child running as uid/gid/groups, handed back over SCM_RIGHTS: the
/// server sees the child's credentials, the test talks through it. -1 on failure.
int connect_as(const std::string& path, uid_t uid, gid_t gid, std::vector<gid_t> groups) {
  int pair[2];
  if (::socketpair(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0, pair) != 0) return -1;
  const pid_t pid = ::fork();
  if (pid == 0) {
    const int fd = child_connect(path, uid, gid, groups);
    if (fd < 0) ::_exit(4);
    FdMessage m;
    cmsghdr* c = CMSG_FIRSTHDR(&m.msg);
    c->cmsg_level = SOL_SOCKET;
    c->cmsg_type = SCM_RIGHTS;
    c->cmsg_len = CMSG_LEN(sizeof(int));
    std::memcpy(CMSG_DATA(c), &fd, sizeof fd);
    ::_exit(::sendmsg(pair[1], &m.msg, 0) == 1 ? 0 : 5);
  }
  ::close(pair[1]);
  FdMessage m;
  int fd = -1;
  if (::recvmsg(pair[0], &m.msg, 0) == 1) {
    if (cmsghdr* c = CMSG_FIRSTHDR(&m.msg); c != nullptr && c->cmsg_type == SCM_RIGHTS) {
      std::memcpy(&fd, CMSG_DATA(c), sizeof fd);
    }
  }
  ::close(pair[0]);
  int status = 0;
  ::waitpid(pid, &status, 0);
  return fd;
}

class ApiAccess : public ServerFixture {
 protected:
  void SetUp() override {
    if (::geteuid() != 0) GTEST_SKIP() << "needs root to fork children with other uids";
    // getgrnam() returns static storage: copy each gid before the next call.
    const group* nogroup = ::getgrnam("nogroup");
    if (nogroup == nullptr) GTEST_SKIP() << "needs the group nogroup";
    socket_gid_ = nogroup->gr_gid;
    const group* users = ::getgrnam("users");
    if (users == nullptr) GTEST_SKIP() << "needs the group users";
    control_gid_ = users->gr_gid;
    ServerConfig config = default_config();
    config.socket_group = "nogroup";  // who may connect at all (mode 0660)
    config.read_group = "nogroup";
    config.control_group = "users";
    start_server(config);
  }
  static std::string code(const std::string& line) {
    const json reply = json::parse(line);
    return reply.at("ok").get<bool>() ? "ok" : reply.at("error").at("code").get<std::string>();
  }

  gid_t socket_gid_ = 0;
  gid_t control_gid_ = 0;
  static constexpr uid_t kNobody = 65534;
};

const std::vector<std::string> kProbe = {
    R"({"cmd":"status","id":1})",
    R"({"cmd":"drive_reset","id":2})",
    R"({"cmd":"inputs","safety_chain":true,"id":3})",
};

TEST_F(ApiAccess, ReadGroupMemberMayReadOnly) {
  const ChildResult r = run_as(socket_path(), kNobody, socket_gid_, {socket_gid_}, kProbe);
  ASSERT_EQ(r.connect_errno, 0);
  ASSERT_EQ(r.lines.size(), 4U);
  EXPECT_EQ(json::parse(r.lines[0]).at("data").at("access"), json::array({"read"}));
  EXPECT_EQ(code(r.lines[1]), "ok");
  EXPECT_EQ(code(r.lines[2]), "forbidden");
  EXPECT_EQ(code(r.lines[3]), "forbidden");
  EXPECT_TRUE(on_io([this] { return backend_.requests_seen.empty(); }));
}

TEST_F(ApiAccess, SupplementaryControlGroupAllowsControl) {
  const ChildResult r =
      run_as(socket_path(), kNobody, socket_gid_, {socket_gid_, control_gid_}, kProbe);
  ASSERT_EQ(r.connect_errno, 0);
  ASSERT_EQ(r.lines.size(), 4U);
  EXPECT_EQ(json::parse(r.lines[0]).at("data").at("access"), json::array({"read", "control"}));
  EXPECT_EQ(code(r.lines[1]), "ok");
  EXPECT_EQ(code(r.lines[2]), "ok");
  EXPECT_EQ(code(r.lines[3]), "forbidden");
}

TEST_F(ApiAccess, OutsiderCannotEvenConnect) {
  // Not in the socket's group: the 0660 file mode keeps it out before any credential check.
  const ChildResult r = run_as(socket_path(), kNobody, 4242, {4242}, kProbe);
  EXPECT_EQ(r.connect_errno, EACCES);
}

TEST_F(ApiAccess, RootMayDoEverythingOverTheSocket) {
  auto client = connect();
  for (const auto& line : kProbe) {
    ASSERT_TRUE(client->send(line + "\n"));
    const auto reply = client->read_json();
    ASSERT_TRUE(reply);
    EXPECT_EQ(reply->at("ok"), true) << line;
  }
}

TEST_F(ApiAccess, SocketBelongsToTheConfiguredGroup) {
  struct stat st {};
  ASSERT_EQ(::stat(socket_path().c_str(), &st), 0);
  EXPECT_EQ(st.st_gid, socket_gid_);
}

TEST_F(ApiAccess, AReloadThatTakesReadAccessAwayEndsTheWatchStreamSayingWhy) {
  Client reader(connect_as(socket_path(), kNobody, socket_gid_, {socket_gid_}));
  ASSERT_TRUE(reader.connected());
  ASSERT_TRUE(reader.read_hello());
  ASSERT_EQ(reader.call({{"cmd", "watch"}, {"enable", true}}).at("ok"), true);
  ASSERT_TRUE(reader.read_json());  // the state event
  ServerConfig next = default_config();
  next.socket_group = "nogroup";
  next.read_group = "users";  // nobody in nogroup only: no read access any more
  next.control_group = "users";
  on_io([&] { server_->reconfigure(next); });
  const auto ended = reader.read_json();
  ASSERT_TRUE(ended);
  EXPECT_EQ(ended->at("event"), "watch_ended");
  EXPECT_NE(ended->at("data").at("reason").get<std::string>().find("revoked"), std::string::npos);
  on_io([this] { server_->publish("fault", {{"code", "x"}}); });
  EXPECT_FALSE(reader.read_line(200ms)) << "events still reach a user without read access";
  EXPECT_EQ(reader.call({{"cmd", "status"}}).at("error").at("code"), "forbidden");
  EXPECT_EQ(counters().watchers, 0U);
}

}  // namespace
}  // namespace liftd::api::testing
