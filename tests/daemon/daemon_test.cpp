// End to end: the liftd binary with NOTIFY_SOCKET pointing at a socket this test binds.
// Real time is unavoidable here, so the assertions are about order and counts, with wide
// margins for a loaded machine (and for the sanitizer build).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "daemon/process.hpp"
#include "daemon/test_socket.hpp"

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

TEST(DaemonSignals, SighupIsRefusedAndTheDaemonKeepsRunning) {
  TestSocket notify;
  auto env = base_env();
  env.push_back("NOTIFY_SOCKET=" + notify.path());
  env.push_back("XDG_RUNTIME_DIR=" + notify.dir());  // its own API socket: tests run in parallel
  Process liftd({kLiftd, "--simulate"}, env, notify.dir());
  std::vector<std::string> seen;
  ASSERT_TRUE(receive_until(notify, "READY=1", seen, kStartupLimit)) << liftd.err();
  liftd.signal(SIGHUP);
  // Still running a while later, and said why nothing was reloaded.
  EXPECT_FALSE(liftd.wait(500ms).has_value());
  EXPECT_THAT(liftd.err(), HasSubstr("reloading the configuration is not supported"));
  liftd.signal(SIGTERM);
  EXPECT_EQ(liftd.wait(kStopLimit), 0) << liftd.err();
}

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
