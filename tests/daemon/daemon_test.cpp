// End to end: the liftd binary with NOTIFY_SOCKET pointing at a socket this test binds.
// Real time is unavoidable here, so the assertions are about order and counts, with wide
// margins for a loaded machine (and for the sanitizer build).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fcntl.h>
#include <sys/stat.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/cpu_set.hpp"
#include "daemon/process.hpp"
#include "daemon/test_socket.hpp"
#include "rt/board_settings.hpp"
#include "support/api_client.hpp"

namespace liftd {
namespace {

using namespace std::chrono_literals;
using ::testing::HasSubstr;
using ::testing::Not;
using testing::Process;
using testing::TestSocket;

const std::string kLiftd = LIFTD_BINARY;
const std::string kSourceDir = LIFTD_SOURCE_DIR;
// Generous: 2 shared cores, sometimes under ASan.
constexpr auto kStartupLimit = 20s;
// The task asks for a stop within a second; allow for a loaded machine.
constexpr auto kStopLimit = 5s;

std::vector<std::string> base_env() {
  std::vector<std::string> env = {"PATH=/usr/bin:/bin", "TZ=UTC"};
  for (const char* name : {"ASAN_OPTIONS", "UBSAN_OPTIONS", "LSAN_OPTIONS"}) {
    if (const char* value = std::getenv(name)) env.push_back(std::string(name) + "=" + value);
  }
  return env;
}

std::string write_file(const std::string& dir, const std::string& name, const std::string& text);

// A config for --simulate --config: the given log level, the API socket in `dir`, no access
// groups (the test's user owns the daemon), so parallel tests never share a socket.
std::string write_sim_config(const std::string& dir, const std::string& log_level) {
  return write_file(dir, "liftd.json",
                    R"({"log": {"level": ")" + log_level + R"("}, "api": {"socket": ")" + dir +
                        R"(/api.sock", "socket_group": "", "read_group": "", "control_group": "",
                            "inputs_group": ""}})");
}

std::string write_file(const std::string& dir, const std::string& name, const std::string& text) {
  const std::string path = dir + "/" + name;
  std::ofstream(path) << text;
  return path;
}

bool starts_with(const std::string& text, const std::string& prefix) {
  return text.rfind(prefix, 0) == 0;
}

bool has_line(const std::string& datagram, const std::string& line) {
  return datagram == line || starts_with(datagram, line + "\n") ||
         datagram.find("\n" + line + "\n") != std::string::npos ||
         (datagram.size() > line.size() &&
          datagram.compare(datagram.size() - line.size() - 1, std::string::npos, "\n" + line) == 0);
}

// Receives datagrams until one has `line`; all received so far are appended to `seen`.
bool receive_until(TestSocket& socket, const std::string& line, std::vector<std::string>& seen,
                   std::chrono::milliseconds limit) {
  const auto end = std::chrono::steady_clock::now() + limit;
  while (std::chrono::steady_clock::now() < end) {
    const auto datagram = socket.receive(100ms);
    if (!datagram) continue;
    seen.push_back(*datagram);
    if (has_line(*datagram, line)) return true;
  }
  return false;
}

std::string joined(const std::vector<std::string>& datagrams) {
  std::string out;
  for (const auto& d : datagrams) out += "[" + d + "] ";
  return out;
}

TEST(DaemonNotify, SimulateSendsReadyStatusThenStoppingOnSigterm) {
  TestSocket notify;
  auto env = base_env();
  env.push_back("NOTIFY_SOCKET=" + notify.path());
  env.push_back("XDG_RUNTIME_DIR=" + notify.dir());  // its own API socket: tests run in parallel
  Process liftd({kLiftd, "--simulate"}, env, notify.dir());

  std::vector<std::string> seen;
  ASSERT_TRUE(receive_until(notify, "READY=1", seen, kStartupLimit)) << joined(seen) << "\n"
                                                                     << liftd.err();
  // Startup reports progress first, then READY=1 carries the running status.
  ASSERT_GE(seen.size(), 2U);
  EXPECT_EQ(seen.front(), "STATUS=starting");
  EXPECT_THAT(seen.back(),
              ::testing::StartsWith("READY=1\nSTATUS=simulated lift running; API on "));

  const auto stop_sent = std::chrono::steady_clock::now();
  liftd.signal(SIGTERM);
  std::vector<std::string> after;
  ASSERT_TRUE(receive_until(notify, "STOPPING=1", after, kStopLimit)) << joined(after);
  EXPECT_TRUE(has_line(after.back(), "STATUS=stopping: SIGTERM")) << after.back();
  const auto code = liftd.wait(kStopLimit);
  const auto took = std::chrono::steady_clock::now() - stop_sent;
  ASSERT_TRUE(code.has_value()) << "liftd did not exit after SIGTERM";
  EXPECT_EQ(*code, 0) << liftd.err();
  EXPECT_LT(took, kStopLimit);
  RecordProperty(
      "stop_ms",
      static_cast<int>(std::chrono::duration_cast<std::chrono::milliseconds>(took).count()));
  EXPECT_THAT(liftd.err(), HasSubstr("simulated drive answering on /dev/pts/"));
  EXPECT_THAT(liftd.err(), HasSubstr("[event=stopping reason=SIGTERM]"));
}

TEST(DaemonSignals, SigintStopsCleanly) {
  TestSocket notify;
  auto env = base_env();
  env.push_back("NOTIFY_SOCKET=" + notify.path());
  env.push_back("XDG_RUNTIME_DIR=" + notify.dir());  // its own API socket: tests run in parallel
  Process liftd({kLiftd, "--simulate"}, env, notify.dir());
  std::vector<std::string> seen;
  ASSERT_TRUE(receive_until(notify, "READY=1", seen, kStartupLimit)) << liftd.err();
  liftd.signal(SIGINT);
  ASSERT_TRUE(receive_until(notify, "STOPPING=1", seen, kStopLimit));
  EXPECT_EQ(liftd.wait(kStopLimit), 0) << liftd.err();
}

// A liftd --simulate --config with its own notify socket, waiting for READY=1.
struct SimDaemon {
  explicit SimDaemon(TestSocket& notify, const std::string& config,
                     const std::string& name = "liftd", int stderr_fd = -1)
      : process({kLiftd, "--simulate", "--config", config}, env_for(notify), notify.dir(), name,
                stderr_fd) {}
  static std::vector<std::string> env_for(TestSocket& notify) {
    auto env = base_env();
    env.push_back("NOTIFY_SOCKET=" + notify.path());
    env.push_back("RUNTIME_DIRECTORY=" + notify.dir());  // flight recorder files go here
    return env;
  }
  Process process;
};

// The "event" of an API line ("" when nothing arrived).
std::string event_of(const nlohmann::json& line) {
  return line.is_object() ? line.value("event", "") : "";
}

// The error code of an API reply ("" when it is not an error).
std::string error_code_of(const nlohmann::json& line) {
  return line.is_object() && line.contains("error") ? line["error"].value("code", "") : "";
}

bool exists(const std::string& path) {
  struct stat info {};
  return ::lstat(path.c_str(), &info) == 0;
}

TEST(DaemonSignals, StraySignalsAreLoggedAndIgnored) {
  TestSocket notify;
  const std::string config = write_sim_config(notify.dir(), "info");
  SimDaemon liftd(notify, config);
  std::vector<std::string> seen;
  ASSERT_TRUE(receive_until(notify, "READY=1", seen, kStartupLimit)) << liftd.process.err();
  // Signals liftd does not use must not end it: each is ignored, the socket stays.
  for (int number : {SIGUSR2, SIGALRM, SIGRTMIN + 1}) {
    liftd.process.signal(number);
    EXPECT_FALSE(liftd.process.wait(300ms).has_value()) << number << "\n" << liftd.process.err();
  }
  EXPECT_THAT(liftd.process.err(), HasSubstr("SIGUSR2 has no meaning for liftd; ignored"));
  EXPECT_THAT(liftd.process.err(), HasSubstr("SIGALRM has no meaning for liftd; ignored"));
  EXPECT_THAT(liftd.process.err(), HasSubstr("[event=signal_ignored signal=SIGRTMIN+1]"));
  EXPECT_TRUE(exists(notify.dir() + "/api.sock"));
  liftd.process.signal(SIGTERM);
  EXPECT_EQ(liftd.process.wait(kStopLimit), 0) << liftd.process.err();
  EXPECT_FALSE(exists(notify.dir() + "/api.sock"));
}

TEST(DaemonSignals, Sigusr1WritesTheFlightRecorder) {
  TestSocket notify;
  const std::string config = write_sim_config(notify.dir(), "info");
  SimDaemon liftd(notify, config);
  std::vector<std::string> seen;
  ASSERT_TRUE(receive_until(notify, "READY=1", seen, kStartupLimit)) << liftd.process.err();
  liftd.process.signal(SIGUSR1);
  std::string trace;
  const auto end = std::chrono::steady_clock::now() + kStopLimit;
  while (trace.empty() && std::chrono::steady_clock::now() < end) {
    for (const auto& entry : std::filesystem::directory_iterator(notify.dir())) {
      const std::string name = entry.path().filename().string();
      if (starts_with(name, "liftd-trace-")) trace = entry.path().string();
    }
    std::this_thread::sleep_for(20ms);
  }
  ASSERT_FALSE(trace.empty()) << liftd.process.err();
  EXPECT_FALSE(liftd.process.wait(200ms).has_value());
  EXPECT_THAT(liftd.process.err(), HasSubstr("written to " + trace + " after SIGUSR1"));
  liftd.process.signal(SIGTERM);
  EXPECT_EQ(liftd.process.wait(kStopLimit), 0) << liftd.process.err();
}

TEST(DaemonSignals, AStderrReaderThatGoesAwayDoesNotEndTheDaemon) {
  TestSocket notify;
  const std::string config = write_sim_config(notify.dir(), "debug");
  int pipe_fds[2];
  ASSERT_EQ(::pipe2(pipe_fds, O_CLOEXEC), 0);
  ::close(pipe_fds[0]);  // nobody reads: every write to stderr is EPIPE (before: SIGPIPE, 141)
  SimDaemon liftd(notify, config, "liftd", pipe_fds[1]);
  ::close(pipe_fds[1]);
  std::vector<std::string> seen;
  ASSERT_TRUE(receive_until(notify, "READY=1", seen, kStartupLimit))
      << "exit " << liftd.process.wait(0ms).value_or(-1);
  liftd.process.signal(SIGUSR2);  // more log lines
  EXPECT_FALSE(liftd.process.wait(300ms).has_value());
  liftd.process.signal(SIGTERM);
  EXPECT_EQ(liftd.process.wait(kStopLimit), 0);
}

TEST(DaemonSocket, LeavesASocketAnotherDaemonBoundSinceAlone) {
  TestSocket notify_a;
  TestSocket notify_b;
  const std::string config = write_sim_config(notify_a.dir(), "info");
  const std::string socket = notify_a.dir() + "/api.sock";
  SimDaemon first(notify_a, config, "first");
  std::vector<std::string> seen;
  ASSERT_TRUE(receive_until(notify_a, "READY=1", seen, kStartupLimit)) << first.process.err();
  // Someone deletes the socket; a second daemon starts on the same path.
  ASSERT_EQ(::unlink(socket.c_str()), 0);
  SimDaemon second(notify_b, config, "second");
  ASSERT_TRUE(receive_until(notify_b, "READY=1", seen, kStartupLimit)) << second.process.err();
  first.process.signal(SIGTERM);
  ASSERT_EQ(first.process.wait(kStopLimit), 0) << first.process.err();
  EXPECT_THAT(first.process.err(), HasSubstr("not removing " + socket));
  // The second daemon still has its socket and answers on it.
  ASSERT_TRUE(exists(socket));
  testing::ApiClient client(socket);
  ASSERT_TRUE(client.connected());
  EXPECT_EQ(event_of(client.next(kStartupLimit)), "hello");
  second.process.signal(SIGTERM);
  EXPECT_EQ(second.process.wait(kStopLimit), 0) << second.process.err();
  EXPECT_FALSE(exists(socket));  // its own socket it does remove
}

// The children of a process (from /proc), e.g. the liftd a shell started.
std::vector<pid_t> children_of(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/task/" + std::to_string(pid) + "/children");
  std::vector<pid_t> out;
  pid_t child = 0;
  while (in >> child) out.push_back(child);
  return out;
}

// Waits until `pid` is the only child of `parent` or gone; returns its pid or 0.
pid_t wait_for_child(pid_t parent, std::chrono::milliseconds limit) {
  const auto end = std::chrono::steady_clock::now() + limit;
  while (std::chrono::steady_clock::now() < end) {
    const auto children = children_of(parent);
    if (children.size() == 1) return children.front();
    std::this_thread::sleep_for(10ms);
  }
  return 0;
}

// A client of a socket systemd-socket-activate holds. Its file appears at bind(), a moment
// before the manager listens: connects until the socket takes the connection (a refused connect
// starts nothing) or `end`.
std::unique_ptr<testing::ApiClient> connect_when_listening(
    const std::string& path, std::chrono::steady_clock::time_point end) {
  auto client = std::make_unique<testing::ApiClient>(path);
  while (!client->connected() && std::chrono::steady_clock::now() < end) {
    std::this_thread::sleep_for(10ms);
    client = std::make_unique<testing::ApiClient>(path);
  }
  return client;
}

TEST(DaemonSocketActivation, AClientConnectingDuringARestartIsQueuedNotRefused) {
  const std::string activate = "/usr/bin/systemd-socket-activate";
  if (::access(activate.c_str(), X_OK) != 0) {
    GTEST_SKIP() << activate << " is not installed (Debian package systemd)";
  }
  TestSocket notify;
  const std::string config = write_sim_config(notify.dir(), "info");
  const std::string socket = notify.dir() + "/api.sock";
  // What systemd does with liftd.socket and Restart=: the listening socket belongs to the
  // manager (here systemd-socket-activate, then the shell it becomes), and each liftd started
  // gets it as fd 3 with LISTEN_PID set to its own pid.
  const std::string run_liftd =
      "sh -c 'LISTEN_PID=$$ exec " + kLiftd + " --simulate --config " + config + "'";
  // systemd-socket-activate passes on only PATH, TERM, USER, HOME and what -E names.
  std::vector<std::string> args = {activate,
                                   "--listen=" + socket,
                                   "--fdname=api",
                                   "-E",
                                   "NOTIFY_SOCKET=" + notify.path(),
                                   "-E",
                                   "RUNTIME_DIRECTORY=" + notify.dir()};
  for (const auto& variable : base_env()) {
    if (!starts_with(variable, "PATH=")) {
      args.push_back("-E");
      args.push_back(variable);
    }
  }
  for (const std::string arg : {"/bin/sh", "-c"}) args.push_back(arg);
  args.push_back(run_liftd + "; sleep 1; " + run_liftd);
  Process manager(args, base_env(), notify.dir(), "manager");
  // Whatever happens below, no liftd outlives the test (the manager's destructor kills only
  // the shell, not the liftd it started).
  struct KillChildren {
    pid_t parent;
    ~KillChildren() {
      for (const pid_t child : children_of(parent)) ::kill(child, SIGKILL);
    }
  } kill_children{manager.pid()};
  const auto end = std::chrono::steady_clock::now() + kStartupLimit;
  while (!exists(socket) && std::chrono::steady_clock::now() < end) {
    std::this_thread::sleep_for(10ms);
  }
  ASSERT_TRUE(exists(socket)) << manager.err();
  struct stat before {};
  ASSERT_EQ(::lstat(socket.c_str(), &before), 0);

  // The first client starts the first liftd and is served by it.
  const std::unique_ptr<testing::ApiClient> first_client = connect_when_listening(socket, end);
  testing::ApiClient& first = *first_client;
  ASSERT_TRUE(first.connected());
  const auto hello = first.next(kStartupLimit);
  ASSERT_EQ(event_of(hello), "hello") << manager.err();
  std::vector<std::string> seen;
  ASSERT_TRUE(receive_until(notify, "READY=1", seen, kStartupLimit)) << manager.err();
  EXPECT_THAT(manager.err(), HasSubstr("using the API socket systemd passed"));

  // Restart: the first liftd stops; while none runs, a client connects and waits in the queue.
  const pid_t liftd1 = wait_for_child(manager.pid(), kStartupLimit);
  ASSERT_NE(liftd1, 0);
  ::kill(liftd1, SIGTERM);
  ASSERT_TRUE(receive_until(notify, "STOPPING=1", seen, kStopLimit));
  while (::kill(liftd1, 0) == 0 && std::chrono::steady_clock::now() < end + kStopLimit) {
    std::this_thread::sleep_for(10ms);
  }
  ASSERT_TRUE(exists(socket)) << "the stopping liftd removed systemd's socket";
  testing::ApiClient waiting(socket);
  ASSERT_TRUE(waiting.connected()) << "refused during the restart: " << std::strerror(errno);
  ASSERT_TRUE(receive_until(notify, "READY=1", seen, kStartupLimit)) << manager.err();
  const auto second_hello = waiting.next(kStartupLimit);
  EXPECT_EQ(event_of(second_hello), "hello") << manager.err();

  // The socket is the one the manager made, untouched by liftd (owner, group, mode), and a
  // connection gets the same access as on a socket liftd creates itself.
  struct stat after {};
  ASSERT_EQ(::lstat(socket.c_str(), &after), 0);
  EXPECT_EQ(after.st_ino, before.st_ino);
  EXPECT_EQ(after.st_mode, before.st_mode);
  EXPECT_EQ(after.st_uid, before.st_uid);
  EXPECT_EQ(after.st_gid, before.st_gid);
  {
    TestSocket own_notify;
    const std::string own_config = write_sim_config(own_notify.dir(), "info");
    SimDaemon own(own_notify, own_config, "own");
    ASSERT_TRUE(receive_until(own_notify, "READY=1", seen, kStartupLimit)) << own.process.err();
    testing::ApiClient client(own_notify.dir() + "/api.sock");
    const auto own_hello = client.next(kStartupLimit);
    ASSERT_EQ(event_of(own_hello), "hello");
    EXPECT_EQ(own_hello["data"]["access"], hello["data"]["access"]);
    EXPECT_EQ(own_hello["data"]["access"], second_hello["data"]["access"]);
    own.process.signal(SIGTERM);
    EXPECT_EQ(own.process.wait(kStopLimit), 0);
  }

  const pid_t liftd2 = wait_for_child(manager.pid(), kStartupLimit);
  ASSERT_NE(liftd2, 0);
  ::kill(liftd2, SIGTERM);
  EXPECT_EQ(manager.wait(kStopLimit), 0) << manager.err();
  EXPECT_TRUE(exists(socket));  // systemd's file: liftd never removes it
}

TEST(DaemonSocketActivation, RefusesPassedSocketsItCannotServeAndLeavesTheirFilesAlone) {
  const std::string activate = "/usr/bin/systemd-socket-activate";
  if (::access(activate.c_str(), X_OK) != 0) {
    GTEST_SKIP() << activate << " is not installed (Debian package systemd)";
  }
  struct Case {
    const char* what;
    std::vector<std::string> listen;  // paths under the test's directory, in order
    std::vector<std::string> names;   // --fdname (empty: none)
    std::vector<std::string> said;    // in liftd's error
  };
  const std::vector<Case> cases = {
      {"a socket bound elsewhere than api.socket",
       {"other.sock"},
       {"api"},
       {"/other.sock", "but api.socket is", "/api.sock", "ListenStream="}},
      {"two unnamed sockets", {"one.sock", "two.sock"}, {}, {"passed 2 socket(s)", "\"api\""}},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.what);
    TestSocket notify;
    const std::string config = write_sim_config(notify.dir(), "info");
    std::vector<std::string> args = {activate};
    for (const auto& path : c.listen) args.push_back("--listen=" + notify.dir() + "/" + path);
    for (const auto& name : c.names) args.push_back("--fdname=" + name);
    args.push_back("-E");
    args.push_back("RUNTIME_DIRECTORY=" + notify.dir());
    for (const auto& variable : base_env()) {
      if (!starts_with(variable, "PATH=")) {
        args.push_back("-E");
        args.push_back(variable);
      }
    }
    args.push_back("/bin/sh");
    args.push_back("-c");
    args.push_back("LISTEN_PID=$$ exec " + kLiftd + " --simulate --config " + config);
    Process manager(args, base_env(), notify.dir(), "manager");
    const std::string first = notify.dir() + "/" + c.listen.front();
    const auto end = std::chrono::steady_clock::now() + kStartupLimit;
    while (!exists(first) && std::chrono::steady_clock::now() < end) {
      std::this_thread::sleep_for(10ms);
    }
    ASSERT_TRUE(exists(first)) << manager.err();
    // systemd-socket-activate starts liftd on a connection.
    const std::unique_ptr<testing::ApiClient> trigger = connect_when_listening(first, end);
    const auto code = manager.wait(kStartupLimit);
    ASSERT_TRUE(code.has_value()) << "liftd ran on sockets it cannot serve";
    EXPECT_NE(*code, 0);
    for (const auto& text : c.said) EXPECT_THAT(manager.err(), HasSubstr(text));
    for (const auto& path : c.listen) {
      EXPECT_TRUE(exists(notify.dir() + "/" + path)) << "liftd removed systemd's " << path;
    }
    EXPECT_FALSE(exists(notify.dir() + "/api.sock")) << "liftd made a socket of its own";
  }
}

TEST(DaemonReload, SighupAppliesWhatItCanAndNamesWhatNeedsARestart) {
  TestSocket notify;
  const std::string config = write_sim_config(notify.dir(), "info");
  SimDaemon liftd(notify, config);
  std::vector<std::string> seen;
  ASSERT_TRUE(receive_until(notify, "READY=1", seen, kStartupLimit)) << liftd.process.err();
  auto before = std::make_unique<testing::ApiClient>(notify.dir() + "/api.sock");
  ASSERT_EQ(event_of(before->next(kStartupLimit)), "hello");

  // Valid file: log level and client limit apply now; the drive device needs a restart.
  write_file(notify.dir(), "liftd.json",
             R"({"log": {"level": "debug"}, "drive": {"device": "/dev/ttyUSB7"},
                 "api": {"socket": ")" +
                 notify.dir() + R"(/api.sock", "socket_group": "",
                 "read_group": "", "control_group": "", "inputs_group": "", "max_clients": 1, "reserved_clients": 0}})");
  liftd.process.signal(SIGHUP);
  std::vector<std::string> reload;
  ASSERT_TRUE(receive_until(notify, "READY=1", reload, kStopLimit)) << liftd.process.err();
  // The drive link's own STATUS= lines may fall in between (the link comes up when it does);
  // the reload is the RELOADING=1 message and then READY=1.
  std::erase_if(reload, [](const std::string& m) {
    return m.rfind("STATUS=drive link", 0) == 0 && m.find('\n') == std::string::npos;
  });
  ASSERT_EQ(reload.size(), 2U) << joined(reload);
  EXPECT_THAT(reload[0], ::testing::StartsWith("RELOADING=1\nSTATUS=reloading " + config +
                                               "\nMONOTONIC_USEC="));
  EXPECT_THAT(reload[1], HasSubstr("(1 changed key(s) wait for a restart)"));
  const std::string err = liftd.process.err();
  EXPECT_THAT(err, HasSubstr("drive.device changed from \"/dev/ttyS1\" to \"/dev/ttyUSB7\": it "
                             "takes effect only after a restart"));
  EXPECT_THAT(err, HasSubstr("applied api.max_clients, api.reserved_clients, log.level"));
  // max_clients 1: a second client is now refused with busy; debug lines now appear.
  testing::ApiClient extra(notify.dir() + "/api.sock");
  const auto refused = extra.next(kStartupLimit);
  EXPECT_EQ(error_code_of(refused), "busy") << refused;
  before.reset();  // its goodbye is a debug line, written only at the new level
  const auto end = std::chrono::steady_clock::now() + kStopLimit;
  while (liftd.process.err().find("DEBUG api:") == std::string::npos &&
         std::chrono::steady_clock::now() < end) {
    std::this_thread::sleep_for(20ms);
  }
  EXPECT_THAT(liftd.process.err(), HasSubstr("DEBUG api:"));

  // Invalid file: refused, nothing changes, the daemon runs on.
  write_file(notify.dir(), "liftd.json", R"({"log": {"level": "loud"}})");
  liftd.process.signal(SIGHUP);
  std::vector<std::string> refused_reload;
  ASSERT_TRUE(receive_until(notify, "READY=1", refused_reload, kStopLimit));
  EXPECT_THAT(refused_reload.back(), HasSubstr("STATUS=reload refused (1 problem(s) in " + config));
  EXPECT_THAT(liftd.process.err(),
              HasSubstr("reload refused, the running configuration stays: log.level: \"loud\" is "
                        "not allowed"));
  EXPECT_FALSE(liftd.process.wait(200ms).has_value());
  liftd.process.signal(SIGTERM);
  EXPECT_EQ(liftd.process.wait(kStopLimit), 0) << liftd.process.err();
}

// `Cpus_allowed_list` of one of liftd's threads ("" when it cannot be read).
std::string cpus_allowed(int pid, const std::string& tid) {
  std::ifstream status("/proc/" + std::to_string(pid) + "/task/" + tid + "/status");
  std::string line;
  while (std::getline(status, line)) {
    if (line.rfind("Cpus_allowed_list:", 0) == 0) {
      return line.substr(line.find_first_not_of(" \t", sizeof "Cpus_allowed_list:" - 1));
    }
  }
  return "";
}

// One drive kind's simulated lift and the name of its real-time loop.
struct RtLoopCase {
  const char* kind;       // drive.kind
  const char* rt_thread;  // what ps -L shows for the loop that runs on rt.cpu
};

class DaemonRealTimeCpu : public ::testing::TestWithParam<RtLoopCase> {};

// rt.cpu set: the kind's real-time loop runs on it, the main thread (the io thread with the API)
// and the threads it started on the other CPUs, and the journal says so once.
TEST_P(DaemonRealTimeCpu, TheRealTimeLoopOwnsRtCpuAndEveryNormalThreadRunsOffIt) {
  const RtLoopCase& c = GetParam();
  const std::vector<int> usable = current_cpus();
  if (usable.size() < 2) GTEST_SKIP() << "one usable CPU: there is nothing to split";
  const int rt_cpu = usable.back();
  const std::string others = cpu_list_text({usable.begin(), usable.end() - 1});
  TestSocket notify;
  const std::string config =
      write_file(notify.dir(), "liftd.json",
                 R"({"drive": {"kind": ")" + std::string(c.kind) + R"("}, "rt": {"cpu": )" +
                     std::to_string(rt_cpu) + R"(}, "api": {"socket": ")" + notify.dir() +
                     R"(/api.sock", "socket_group": "", "read_group": "", "control_group": "",
             "inputs_group": ""}})");
  SimDaemon liftd(notify, config);
  std::vector<std::string> seen;
  ASSERT_TRUE(receive_until(notify, "READY=1", seen, kStartupLimit)) << liftd.process.err();
  const int pid = liftd.process.pid();
  EXPECT_EQ(cpus_allowed(pid, std::to_string(pid)), others);
  int loops = 0;
  for (const auto& task :
       std::filesystem::directory_iterator("/proc/" + std::to_string(pid) + "/task")) {
    const std::string tid = task.path().filename();
    std::string comm;
    std::getline(std::ifstream(task.path() / "comm"), comm);
    if (comm == c.rt_thread) {
      ++loops;
      EXPECT_EQ(cpus_allowed(pid, tid), std::to_string(rt_cpu));
    } else if (comm != "liftd") {
      // Named threads are liftd's real-time loops, and this kind runs one; every unnamed one
      // is normal or a simulator standing in for the drive, the card or the bus.
      ADD_FAILURE() << "unexpected thread " << comm;
    } else {
      EXPECT_EQ(cpus_allowed(pid, tid), others) << "thread " << tid;
    }
  }
  EXPECT_EQ(loops, 1);
  EXPECT_THAT(liftd.process.err(), HasSubstr("real-time threads on CPU " + std::to_string(rt_cpu) +
                                             ", every other thread on CPU(s) " + others +
                                             " [event=cpu_split cpu=" + std::to_string(rt_cpu) +
                                             " normal_cpus=" + others + "]"));
  // The board settings it cannot make itself: named when missing on this machine, else silent.
  const auto missing = rt::missing_board_settings(rt_cpu, rt::BoardFacts::current(rt_cpu));
  if (missing.empty()) {
    EXPECT_THAT(liftd.process.err(), Not(HasSubstr("rt_settings_missing")));
  } else {
    EXPECT_THAT(liftd.process.err(), HasSubstr(missing.front()));
    EXPECT_THAT(
        liftd.process.err(),
        HasSubstr("[event=rt_settings_missing missing=" + std::to_string(missing.size()) + "]"));
  }
  liftd.process.signal(SIGTERM);
  EXPECT_EQ(liftd.process.wait(kStopLimit), 0) << liftd.process.err();
}

INSTANTIATE_TEST_SUITE_P(EveryDriveKind, DaemonRealTimeCpu,
                         ::testing::Values(RtLoopCase{"dcp", "liftd-cycle"},
                                           RtLoopCase{"sch001", "liftd-sch001"},
                                           RtLoopCase{"uss", "liftd-uss-bus"}),
                         [](const auto& p) { return std::string(p.param.kind); });

TEST(DaemonWatchdog, PingsAtHalfTheTimeout) {
  TestSocket notify;
  auto env = base_env();
  env.push_back("NOTIFY_SOCKET=" + notify.path());
  env.push_back("XDG_RUNTIME_DIR=" + notify.dir());  // its own API socket: tests run in parallel
  env.push_back("WATCHDOG_USEC=200000");             // 200 ms: a ping every 100 ms
  Process liftd({kLiftd, "--simulate"}, env, notify.dir());
  std::vector<std::string> seen;
  ASSERT_TRUE(receive_until(notify, "READY=1", seen, kStartupLimit)) << liftd.err();
  const auto window = 2000ms;
  const auto datagrams = notify.receive_all(window);
  const auto pings = std::count(datagrams.begin(), datagrams.end(), std::string("WATCHDOG=1"));
  // 2 s / 100 ms = 20 expected; a loaded machine delays timers, it never speeds them up.
  EXPECT_GE(pings, 8) << joined(datagrams);
  EXPECT_LE(pings, 22) << joined(datagrams);
  liftd.signal(SIGTERM);
  EXPECT_EQ(liftd.wait(kStopLimit), 0) << liftd.err();
}

TEST(DaemonWatchdog, NoPingsWhenWatchdogPidIsAnotherProcess) {
  TestSocket notify;
  auto env = base_env();
  env.push_back("NOTIFY_SOCKET=" + notify.path());
  env.push_back("XDG_RUNTIME_DIR=" + notify.dir());  // its own API socket: tests run in parallel
  env.push_back("WATCHDOG_USEC=100000");
  env.push_back("WATCHDOG_PID=1");  // meant for another process: not ours to answer
  Process liftd({kLiftd, "--simulate"}, env, notify.dir());
  std::vector<std::string> seen;
  ASSERT_TRUE(receive_until(notify, "READY=1", seen, kStartupLimit)) << liftd.err();
  const auto datagrams = notify.receive_all(500ms);
  EXPECT_EQ(std::count(datagrams.begin(), datagrams.end(), std::string("WATCHDOG=1")), 0);
  liftd.signal(SIGTERM);
  EXPECT_EQ(liftd.wait(kStopLimit), 0);
}

struct ConfigErrorCase {
  const char* legend;
  const char* file_text;  // nullptr: the file does not exist
  const char* expected;   // substring of stderr
};

TEST(DaemonConfig, EveryKindOfConfigErrorExitsWithTwo) {
  const std::vector<ConfigErrorCase> cases = {
      {"missing file", nullptr, "cannot read the config file: No such file or directory"},
      {"malformed JSON", "{\n  \"log\": {\n", "liftd.json:3:1: malformed JSON"},
      {"unknown key", R"({"dcp": {"manufactuer": "LI"}})",
       "dcp.manufactuer: unknown key (did you mean \"dcp.manufacturer\"?)"},
      {"wrong type", R"({"rt": {"lock_memory": "yes"}})",
       "rt.lock_memory: expected true or false, got \"yes\""},
      {"out of range", R"({"api": {"max_clients": 0}})",
       "api.max_clients: 0 is out of range: allowed 1..256"},
      {"value not allowed", R"({"drive": {"kind": "can"}})", "drive.kind: \"can\" is not allowed"},
      {"inconsistent keys", R"({"travel": {"dcp3_speed_count": 1}})",
       "travel.dcp3_decel_distance_mm.V3: is not used with travel.dcp3_speed_count 1"},
      {"duplicate key", R"({"sim": {"dcp": 3, "dcp": 4}})", "sim.dcp: duplicate key"},
  };
  for (const auto& c : cases) {
    TestSocket notify;
    const std::string path = notify.dir() + "/liftd.json";
    if (c.file_text != nullptr) write_file(notify.dir(), "liftd.json", c.file_text);
    auto env = base_env();
    env.push_back("NOTIFY_SOCKET=" + notify.path());
    env.push_back("XDG_RUNTIME_DIR=" + notify.dir());  // its own API socket: tests run in parallel
    Process liftd({kLiftd, "--config", path}, env, notify.dir());
    EXPECT_EQ(liftd.wait(kStartupLimit), 2) << c.legend << "\n" << liftd.err();
    EXPECT_THAT(liftd.err(), HasSubstr(c.expected)) << c.legend;
    const auto datagrams = notify.receive_all(200ms);
    for (const auto& d : datagrams) EXPECT_THAT(d, Not(HasSubstr("READY=1"))) << c.legend;
    ASSERT_FALSE(datagrams.empty()) << c.legend;
    EXPECT_THAT(datagrams.back(), HasSubstr("STATUS=configuration invalid")) << c.legend;

    Process check({kLiftd, "--check-config", path}, base_env(), notify.dir(), "check");
    EXPECT_EQ(check.wait(kStartupLimit), 2) << c.legend;
    EXPECT_THAT(check.err(), HasSubstr(c.expected)) << c.legend;
  }
}

TEST(DaemonCheckConfig, ValidFilePrintsASummaryAndExitsZero) {
  TestSocket scratch;
  Process check({kLiftd, "--check-config", kSourceDir + "/config/liftd.json"}, base_env(),
                scratch.dir());
  ASSERT_EQ(check.wait(kStartupLimit), 0) << check.err();
  const std::string out = check.out();
  EXPECT_THAT(out, HasSubstr("config/liftd.json: configuration is valid\n"));
  EXPECT_THAT(out, HasSubstr("drive:    dcp on /dev/ttyS1 (rs485 auto)\n"));
  EXPECT_THAT(out, HasSubstr("floors:   6, \"0\" at 0 mm to \"5\" at 15000 mm\n"));
  EXPECT_EQ(check.err(), "");
}

TEST(DaemonCheckConfig, InvalidFilePrintsEveryProblem) {
  TestSocket scratch;
  const std::string path = write_file(scratch.dir(), "bad.json", R"({
    "log": {"level": "loud"},
    "dcp": {"link_fault_frames": 101, "language": "english"},
    "api": {"socket": "api.sock"},
    "floorz": []
  })");
  Process check({kLiftd, "--check-config", path}, base_env(), scratch.dir());
  ASSERT_EQ(check.wait(kStartupLimit), 2);
  const std::string expected = "liftd: " + path +
                               ": 5 problems:\n"
                               "  floorz: unknown key (did you mean \"floors\"?)\n"
                               "  log.level: \"loud\" is not allowed: use one of \"trace\", "
                               "\"debug\", \"info\", \"warn\", \"error\"\n"
                               "  dcp.language: \"english\" has 7 bytes: allowed 2..2\n"
                               "  dcp.link_fault_frames: 101 is out of range: allowed 1..100\n"
                               "  api.socket: \"api.sock\" must be an absolute path (start "
                               "with /)\n";
  EXPECT_EQ(check.err(), expected);
  EXPECT_EQ(check.out(), "");
}

TEST(DaemonCommandLine, VersionHelpAndBadArguments) {
  TestSocket scratch;
  {
    Process p({kLiftd, "--version"}, base_env(), scratch.dir(), "version");
    EXPECT_EQ(p.wait(kStartupLimit), 0);
    EXPECT_EQ(p.out(), "liftd " LIFTD_VERSION "\n");
  }
  {
    Process p({kLiftd, "--help"}, base_env(), scratch.dir(), "help");
    EXPECT_EQ(p.wait(kStartupLimit), 0);
    EXPECT_THAT(p.out(), HasSubstr("--check-config FILE"));
  }
  // Legend: arguments that must be refused with exit 2 and a message on stderr.
  const std::vector<std::vector<std::string>> bad = {
      {"--frobnicate"}, {"--log-level", "loud"}, {"--config"}, {"--version", "--help"}};
  for (const auto& args : bad) {
    std::vector<std::string> argv{kLiftd};
    argv.insert(argv.end(), args.begin(), args.end());
    Process p(argv, base_env(), scratch.dir(), "bad");
    EXPECT_EQ(p.wait(kStartupLimit), 2) << args[0];
    EXPECT_THAT(p.err(), HasSubstr("Try liftd --help")) << args[0];
  }
}

TEST(DaemonCommandLine, PrintConfigShowsSimulateForcingTheSimPosition) {
  TestSocket scratch;
  Process p({kLiftd, "--simulate", "--print-config"}, base_env(), scratch.dir());
  ASSERT_EQ(p.wait(kStartupLimit), 0) << p.err();
  const auto dumped = nlohmann::json::parse(p.out());
  EXPECT_EQ(dumped.at("position").at("source"), "sim");
  EXPECT_EQ(dumped.at("floors").size(), 6U);
}

TEST(DaemonCommandLine, LogLevelOptionOverridesTheConfig) {
  TestSocket notify;
  const std::string path = write_sim_config(notify.dir(), "error");
  auto env = base_env();
  env.push_back("NOTIFY_SOCKET=" + notify.path());
  env.push_back("XDG_RUNTIME_DIR=" + notify.dir());  // its own API socket: tests run in parallel
  Process liftd({kLiftd, "--simulate", "--config", path, "--log-level", "debug"}, env,
                notify.dir());
  std::vector<std::string> seen;
  ASSERT_TRUE(receive_until(notify, "READY=1", seen, kStartupLimit)) << liftd.err();
  liftd.signal(SIGTERM);
  EXPECT_EQ(liftd.wait(kStopLimit), 0);
  EXPECT_THAT(liftd.err(), HasSubstr("DEBUG daemon: starting sim"));
}

TEST(DaemonCommandLine, ConfigLogLevelAppliesWithoutTheOption) {
  TestSocket notify;
  const std::string path = write_sim_config(notify.dir(), "warn");
  auto env = base_env();
  env.push_back("NOTIFY_SOCKET=" + notify.path());
  env.push_back("XDG_RUNTIME_DIR=" + notify.dir());  // its own API socket: tests run in parallel
  Process liftd({kLiftd, "--simulate", "--config", path}, env, notify.dir());
  std::vector<std::string> seen;
  ASSERT_TRUE(receive_until(notify, "READY=1", seen, kStartupLimit)) << liftd.err();
  liftd.signal(SIGTERM);
  EXPECT_EQ(liftd.wait(kStopLimit), 0);
  // Info records after the config is read are gone; the level applies from then on.
  EXPECT_THAT(liftd.err(), Not(HasSubstr("liftd ready")));
}

}  // namespace
}  // namespace liftd
