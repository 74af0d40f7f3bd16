// `liftd --check-config` and the daemon's start agree: whatever the daemon refuses, the check
// refuses with the same message and exit 2 (the unit's RestartPreventExitStatus), and neither
// ever hangs on a file that is not a regular file. Real time: a cycle that cannot get SCHED_FIFO
// ends the start with exit 2 unless the configuration (or --simulate) makes real time optional.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <linux/capability.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/stat.h>

#include <chrono>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

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
// Generous: 2 shared cores, sometimes under ASan. A hang is caught by this limit.
constexpr auto kLimit = 20s;

#if defined(__SANITIZE_ADDRESS__)
constexpr bool kUnderSanitizer = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
constexpr bool kUnderSanitizer = true;
#else
constexpr bool kUnderSanitizer = false;
#endif
#else
constexpr bool kUnderSanitizer = false;
#endif

std::vector<std::string> base_env() {
  std::vector<std::string> env = {"PATH=/usr/bin:/bin", "TZ=UTC"};
  for (const char* name : {"ASAN_OPTIONS", "UBSAN_OPTIONS", "LSAN_OPTIONS"}) {
    if (const char* value = std::getenv(name)) env.push_back(std::string(name) + "=" + value);
  }
  return env;
}

std::string write_file(const std::string& path, const std::string& text) {
  std::ofstream(path) << text;
  return path;
}

std::string read_file(const std::string& path) {
  std::ifstream in(path);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

/// A liftd child started with fork/exec so it can be limited first: optionally without real-time
/// scheduling (CAP_SYS_NICE dropped from the bounding set, so even root loses it across exec, and
/// RLIMIT_RTPRIO 0) and with an address-space limit (a runaway read fails instead of eating the
/// machine's memory).
class LimitedLiftd {
 public:
  struct Limits {
    bool no_realtime = false;
    std::optional<rlim_t> address_space_bytes;
  };
  LimitedLiftd(const std::vector<std::string>& args, const std::vector<std::string>& env,
               const std::string& dir, const std::string& name, Limits limits)
      : out_(dir + "/" + name + ".out"), err_(dir + "/" + name + ".err") {
    std::vector<char*> argv;
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    std::vector<char*> envp;
    for (const auto& e : env) envp.push_back(const_cast<char*>(e.c_str()));
    envp.push_back(nullptr);
    pid_ = ::fork();
    if (pid_ < 0) throw std::runtime_error("fork failed");
    if (pid_ == 0) {
      const int out = ::open(out_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      const int err = ::open(err_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      ::dup2(out, 1);
      ::dup2(err, 2);
      if (limits.no_realtime) {
        // Fails without CAP_SETPCAP, but then the process has no CAP_SYS_NICE to lose.
        ::prctl(PR_CAPBSET_DROP, CAP_SYS_NICE, 0, 0, 0);
        const rlimit none{0, 0};
        ::setrlimit(RLIMIT_RTPRIO, &none);
      }
      if (limits.address_space_bytes) {
        const rlimit as{*limits.address_space_bytes, *limits.address_space_bytes};
        ::setrlimit(RLIMIT_AS, &as);
      }
      ::execve(argv[0], argv.data(), envp.data());
      ::_exit(127);
    }
  }
  ~LimitedLiftd() {
    if (!status_) {
      ::kill(pid_, SIGKILL);
      int status = 0;
      ::waitpid(pid_, &status, 0);
    }
  }
  LimitedLiftd(const LimitedLiftd&) = delete;
  LimitedLiftd& operator=(const LimitedLiftd&) = delete;

  void signal(int signal_number) { ::kill(pid_, signal_number); }
  std::optional<int> wait(std::chrono::milliseconds timeout) {
    const auto end = std::chrono::steady_clock::now() + timeout;
    while (!status_) {
      int status = 0;
      if (::waitpid(pid_, &status, WNOHANG) == pid_) {
        status_ = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
        break;
      }
      if (std::chrono::steady_clock::now() >= end) return std::nullopt;
      std::this_thread::sleep_for(5ms);
    }
    return status_;
  }
  std::string err() const { return read_file(err_); }
  std::string out() const { return read_file(out_); }

 private:
  std::string out_;
  std::string err_;
  pid_t pid_ = -1;
  std::optional<int> status_;
};

struct RefusedCase {
  const char* legend;
  std::string file_text;  // written to liftd.json unless `path` is set
  std::string path;       // a path to use instead (a FIFO, a device)
  const char* expected;   // substring of stderr for both the check and the daemon
};

// Legend: each case is a configuration the daemon cannot run. Before this change the check
// accepted the first five (exit 0) and hung on the last two.
TEST(CheckConfigAgreesWithTheDaemon, EverythingTheDaemonRefusesIsRefusedWithTwo) {
  TestSocket scratch;
  const std::string fifo = scratch.dir() + "/fifo.json";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const std::vector<RefusedCase> cases = {
      {"USS drive at a rate USS has not", R"({"drive": {"kind": "uss"}, "uss": {"baud": 1000}})",
       "", "uss.baud: 1000 is not a USS rate"},
      {"CPU that is not there", R"({"rt": {"cpu": 1023}})", "",
       "rt.cpu: 1023 is not a CPU this machine lets liftd run on"},
      {"NUL inside the socket path", R"({"api": {"socket": "/tmp/liftd.sock\u0000x"}})", "",
       "api.socket: \"/tmp/liftd.sock\\u0000x\" contains a control character (byte 0x00"},
      {"a FIFO", "", fifo, "it is a FIFO; only a regular file is read"},
      {"/dev/zero", "", "/dev/zero", "it is a character device; only a regular file is read"},
  };
  // Under the memory limit a runaway read of /dev/zero ends in bad_alloc instead of the
  // machine's memory (the sanitizer reserves terabytes of address space: no limit there).
  LimitedLiftd::Limits limits;
  if (!kUnderSanitizer) limits.address_space_bytes = rlim_t{1} << 30;
  for (const auto& c : cases) {
    const std::string path =
        c.path.empty() ? write_file(scratch.dir() + "/liftd.json", c.file_text) : c.path;
    LimitedLiftd check({kLiftd, "--check-config", path}, base_env(), scratch.dir(), "check",
                       limits);
    const auto check_code = check.wait(kLimit);
    EXPECT_EQ(check_code, 2) << c.legend << (check_code ? "" : " (hung)") << "\n" << check.err();
    EXPECT_THAT(check.err(), HasSubstr(c.expected)) << c.legend;
    EXPECT_EQ(check.out(), "") << c.legend;

    TestSocket notify;
    auto env = base_env();
    env.push_back("NOTIFY_SOCKET=" + notify.path());
    LimitedLiftd daemon({kLiftd, "--config", path}, env, scratch.dir(), "daemon", limits);
    const auto daemon_code = daemon.wait(kLimit);
    EXPECT_EQ(daemon_code, 2) << c.legend << (daemon_code ? "" : " (hung)") << "\n" << daemon.err();
    EXPECT_THAT(daemon.err(), HasSubstr(c.expected)) << c.legend;
    for (const auto& d : notify.receive_all(100ms)) {
      EXPECT_THAT(d, Not(HasSubstr("READY=1"))) << c.legend;
    }
  }
}

TEST(CheckConfigAgreesWithTheDaemon, ASymlinkToAValidFileIsFollowed) {
  TestSocket scratch;
  const std::string target = write_file(scratch.dir() + "/real.json", R"({"sim": {"dcp": 3}})");
  const std::string link = scratch.dir() + "/liftd.json";
  ASSERT_EQ(::symlink(target.c_str(), link.c_str()), 0);
  Process check({kLiftd, "--check-config", link}, base_env(), scratch.dir());
  EXPECT_EQ(check.wait(kLimit), 0) << check.err();
  EXPECT_THAT(check.out(), HasSubstr("configuration is valid"));
}

// A config for a real drive on a device that does not exist: the real-time check comes before
// any port is opened, so the refusal is all that happens.
std::string drive_config(const std::string& dir, const std::string& rt) {
  return write_file(dir + "/liftd.json", R"({"drive": {"device": ")" + dir +
                                             R"(/no-such-tty"}, "rt": )" + rt +
                                             R"(, "api": {"socket": ")" + dir +
                                             R"(/api.sock", "socket_group": "", "read_group": "",
                             "control_group": "", "inputs_group": ""}})");
}

TEST(RealTimeRequirement, RefusedSchedFifoEndsTheStartWithTwoAndSaysWhatToDo) {
  TestSocket notify;
  const std::string path = drive_config(notify.dir(), R"({"priority": 80})");
  auto env = base_env();
  env.push_back("NOTIFY_SOCKET=" + notify.path());
  LimitedLiftd liftd({kLiftd, "--config", path}, env, notify.dir(), "liftd", {true, {}});
  const auto code = liftd.wait(kLimit);
  EXPECT_EQ(code, 2) << liftd.err();
  EXPECT_THAT(liftd.err(),
              HasSubstr("rt.require_realtime is true but the cycle thread cannot run with "
                        "SCHED_FIFO priority 80: SCHED_FIFO refused (EPERM"));
  EXPECT_THAT(liftd.err(), HasSubstr("set rt.require_realtime to false"));
  const auto datagrams = notify.receive_all(200ms);
  for (const auto& d : datagrams) EXPECT_THAT(d, Not(HasSubstr("READY=1")));
  ASSERT_FALSE(datagrams.empty());
  EXPECT_THAT(datagrams.back(), HasSubstr("STATUS=real-time scheduling refused"));
}

// Runs liftd limited to normal scheduling until READY=1, then stops it; returns its stderr.
std::string run_until_ready_without_realtime(const std::vector<std::string>& args,
                                             TestSocket& notify) {
  auto env = base_env();
  env.push_back("NOTIFY_SOCKET=" + notify.path());
  env.push_back("XDG_RUNTIME_DIR=" + notify.dir());
  LimitedLiftd liftd(args, env, notify.dir(), "liftd", {true, {}});
  bool ready = false;
  const auto end = std::chrono::steady_clock::now() + kLimit;
  while (!ready && std::chrono::steady_clock::now() < end) {
    const auto d = notify.receive(100ms);
    if (d && d->find("READY=1") != std::string::npos) ready = true;
    if (liftd.wait(0ms)) break;
  }
  EXPECT_TRUE(ready) << liftd.err();
  liftd.signal(SIGTERM);
  EXPECT_EQ(liftd.wait(kLimit), 0) << liftd.err();
  return liftd.err();
}

TEST(RealTimeRequirement, SimulateRunsWithoutRealTimeAndWarnsOnce) {
  // Without a config (the defaults), as a normal user without CAP_SYS_NICE would run it.
  TestSocket notify;
  const std::string err = run_until_ready_without_realtime({kLiftd, "--simulate"}, notify);
  EXPECT_THAT(err, HasSubstr("SCHED_FIFO refused (EPERM"));
  EXPECT_THAT(err, Not(HasSubstr("realtime_refused")));

  // With a config that requires real time: --simulate moves no car, so it still runs.
  TestSocket notify2;
  const std::string path = drive_config(notify2.dir(), R"({"require_realtime": true})");
  const std::string err2 =
      run_until_ready_without_realtime({kLiftd, "--simulate", "--config", path}, notify2);
  EXPECT_THAT(err2, HasSubstr("SCHED_FIFO refused (EPERM"));
}

}  // namespace
}  // namespace liftd
