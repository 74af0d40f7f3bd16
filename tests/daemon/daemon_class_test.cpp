// The Daemon frame in-process: component order, start failure, stop requests, notifications.
#include "daemon/daemon.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <asio/post.hpp>
#include <csignal>
#include <string>
#include <vector>

#include "daemon/test_socket.hpp"
#include "log/log.hpp"

namespace liftd::daemon {
namespace {

using namespace std::chrono_literals;
using testing::ScopedEnv;
using testing::TestSocket;

TEST(Daemon, StartsInOrderStopsInReverseAndReturnsTheRequestedCode) {
  TestSocket socket;
  ScopedEnv env("NOTIFY_SOCKET", socket.path());
  Daemon daemon(config::Config{}, service::Notifier::from_environment(), std::nullopt);
  std::vector<std::string> calls;
  for (const std::string name : {"a", "b", "c"}) {
    daemon.add_component({name,
                          [&calls, name] {
                            calls.push_back("start " + name);
                            return true;
                          },
                          [&calls, name] { calls.push_back("stop " + name); }});
  }
  daemon.set_running_status("all good");
  asio::post(daemon.io(), [&] { daemon.request_stop("test over", 7); });
  EXPECT_EQ(daemon.run(), 7);
  EXPECT_EQ(calls, (std::vector<std::string>{"start a", "start b", "start c", "stop c", "stop b",
                                             "stop a"}));
  EXPECT_EQ(socket.receive(2s), "STATUS=starting");
  EXPECT_EQ(socket.receive(2s), "READY=1\nSTATUS=all good");
  EXPECT_EQ(socket.receive(2s), "STOPPING=1\nSTATUS=stopping: test over");
}

TEST(Daemon, FailedStartStopsWhatStartedAndNeverSendsReady) {
  TestSocket socket;
  ScopedEnv env("NOTIFY_SOCKET", socket.path());
  Daemon daemon(config::Config{}, service::Notifier::from_environment(), std::nullopt);
  std::vector<std::string> calls;
  daemon.add_component({"a",
                        [&] {
                          calls.push_back("start a");
                          return true;
                        },
                        [&] { calls.push_back("stop a"); }});
  daemon.add_component({"b",
                        [&] {
                          calls.push_back("start b");
                          return false;
                        },
                        [&] { calls.push_back("stop b"); }});
  daemon.add_component({"c",
                        [&] {
                          calls.push_back("start c");
                          return true;
                        },
                        [&] { calls.push_back("stop c"); }});
  EXPECT_EQ(daemon.run(), exit_code::kFailure);
  EXPECT_EQ(calls, (std::vector<std::string>{"start a", "start b", "stop a"}));
  EXPECT_EQ(socket.receive(2s), "STATUS=starting");
  EXPECT_EQ(socket.receive(2s), "STOPPING=1\nSTATUS=failed to start b");
}

TEST(Daemon, ProgressProbeGatesTheWatchdog) {
  TestSocket socket;
  ScopedEnv env("NOTIFY_SOCKET", socket.path());
  Daemon daemon(config::Config{}, service::Notifier::from_environment(), 20ms);
  int probes = 0;
  daemon.set_progress_probe([&] {
    ++probes;
    if (probes == 4) asio::post(daemon.io(), [&] { daemon.request_stop("enough"); });
    return probes <= 2;  // progress twice, then stuck
  });
  EXPECT_EQ(daemon.run(), 0);
  const auto datagrams = socket.receive_all(200ms);
  const std::vector<std::string> expected = {"STATUS=starting", "READY=1\nSTATUS=running",
                                             "WATCHDOG=1", "WATCHDOG=1",
                                             "STOPPING=1\nSTATUS=stopping: enough"};
  EXPECT_EQ(datagrams, expected);
}

TEST(Daemon, SignalNamesForLogs) {
  // Legend: signal -> name in the journal's LIFTD_SIGNAL field.
  const std::vector<std::pair<int, std::string>> cases = {
      {SIGTERM, "SIGTERM"}, {SIGINT, "SIGINT"},       {SIGHUP, "SIGHUP"},
      {SIGUSR1, "SIGUSR1"}, {SIGUSR2, "SIGUSR2"},     {SIGALRM, "SIGALRM"},
      {SIGPWR, "SIGPWR"},   {SIGRTMIN, "SIGRTMIN+0"}, {SIGRTMIN + 3, "SIGRTMIN+3"},
  };
  for (const auto& [number, name] : cases) EXPECT_EQ(signal_name(number), name) << number;
}

TEST(Daemon, HandlesEverySignalWhoseDefaultWouldEndItSilently) {
  const std::vector<int> handled = handled_signals();
  const auto has = [&](int n) {
    return std::find(handled.begin(), handled.end(), n) != handled.end();
  };
  // Default action "terminate" (signal(7)) and no meaning to liftd, or a meaning we give it.
  for (int n : {SIGTERM, SIGINT, SIGHUP, SIGUSR1, SIGUSR2, SIGALRM, SIGVTALRM, SIGPROF, SIGIO,
                SIGPWR, SIGSTKFLT}) {
    EXPECT_TRUE(has(n)) << signal_name(n);
  }
  for (int n = SIGRTMIN; n <= SIGRTMAX; ++n) EXPECT_TRUE(has(n)) << signal_name(n);
  // A core dump on request and the fault signals keep their default.
  for (int n : {SIGQUIT, SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT, SIGKILL, SIGSTOP}) {
    EXPECT_FALSE(has(n)) << signal_name(n);
  }
}

// A daemon whose "file" is whatever the test puts in `next`, with a recording applier.
struct ReloadRig {
  TestSocket socket;
  ScopedEnv env{"NOTIFY_SOCKET", socket.path()};
  Daemon daemon{config::Config{}, service::Notifier::from_environment(), std::nullopt};
  config::LoadResult next;
  std::vector<config::Config> applied;
  std::string refuse;  // what the applier answers ("" = fine)

  ReloadRig() {
    daemon.set_config_loader([this] { return next; }, "/etc/liftd/liftd.json");
    daemon.set_config_applier([this](const config::Config& c) {
      applied.push_back(c);
      return refuse;
    });
    log::set_level(log::Level::info);
  }
  ~ReloadRig() { log::set_level(log::Level::info); }
};

TEST(DaemonReload, AppliesLiveKeysAndSaysSoToSystemd) {
  ReloadRig rig;
  rig.next.config.log.level = config::LogLevel::debug;
  rig.next.config.api.max_clients = 4;
  rig.next.config.api.control_group = "operators";
  const ReloadOutcome outcome = rig.daemon.reload();
  EXPECT_FALSE(outcome.refused);
  EXPECT_EQ(outcome.applied,
            (std::vector<std::string>{"api.control_group", "api.max_clients", "log.level"}));
  EXPECT_TRUE(outcome.need_restart.empty());
  EXPECT_EQ(log::level(), log::Level::debug);
  ASSERT_EQ(rig.applied.size(), 1U);
  EXPECT_EQ(rig.applied[0].api.max_clients, 4);
  EXPECT_EQ(rig.daemon.config().api.control_group, "operators");
  const auto datagrams = rig.socket.receive_all(200ms);
  ASSERT_EQ(datagrams.size(), 2U);
  EXPECT_EQ(
      datagrams[0].rfind("RELOADING=1\nSTATUS=reloading /etc/liftd/liftd.json\nMONOTONIC_USEC=", 0),
      0U)
      << datagrams[0];
  EXPECT_EQ(datagrams[1], "READY=1\nSTATUS=running");
}

TEST(DaemonReload, KeysThatNeedARestartAreNamedAndKept) {
  ReloadRig rig;
  rig.next.config.drive.device = "/dev/ttyUSB0";
  rig.next.config.floors.pop_back();
  rig.next.config.api.idle_timeout_s = 60;
  const ReloadOutcome outcome = rig.daemon.reload();
  EXPECT_FALSE(outcome.refused);
  EXPECT_EQ(outcome.applied, (std::vector<std::string>{"api.idle_timeout_s"}));
  EXPECT_EQ(outcome.need_restart, (std::vector<std::string>{"drive.device", "floors"}));
  EXPECT_EQ(rig.daemon.config().drive.device, "/dev/ttyS1");
  EXPECT_EQ(rig.daemon.config().floors.size(), 6U);
  EXPECT_EQ(rig.daemon.config().api.idle_timeout_s, 60);
  const auto datagrams = rig.socket.receive_all(200ms);
  ASSERT_EQ(datagrams.size(), 2U);
  EXPECT_EQ(datagrams[1], "READY=1\nSTATUS=running (2 changed key(s) wait for a restart)");
}

TEST(DaemonReload, AnInvalidFileChangesNothing) {
  ReloadRig rig;
  rig.next.config.log.level = config::LogLevel::debug;
  rig.next.problems = {{"rt.priority", "120 is out of range: allowed 1..99"}};
  const ReloadOutcome outcome = rig.daemon.reload();
  EXPECT_TRUE(outcome.refused);
  EXPECT_EQ(outcome.problems,
            (std::vector<std::string>{"rt.priority: 120 is out of range: allowed 1..99"}));
  EXPECT_TRUE(rig.applied.empty());
  EXPECT_EQ(log::level(), log::Level::info);
  EXPECT_EQ(rig.daemon.config().log.level, config::LogLevel::info);
  const auto datagrams = rig.socket.receive_all(200ms);
  ASSERT_EQ(datagrams.size(), 2U);
  EXPECT_EQ(datagrams[1],
            "READY=1\nSTATUS=reload refused (1 problem(s) in /etc/liftd/liftd.json, see the "
            "journal); running");
}

TEST(DaemonReload, ARefusedApplyChangesNothing) {
  ReloadRig rig;
  rig.next.config.log.level = config::LogLevel::debug;
  rig.next.config.api.read_group = "no-such-group";
  rig.refuse = "api: unknown group \"no-such-group\"";
  const ReloadOutcome outcome = rig.daemon.reload();
  EXPECT_TRUE(outcome.refused);
  EXPECT_EQ(outcome.problems, (std::vector<std::string>{rig.refuse}));
  EXPECT_EQ(log::level(), log::Level::info);
  EXPECT_EQ(rig.daemon.config().api.read_group, "liftd");
}

TEST(DaemonReload, CommandLineLogLevelWins) {
  ReloadRig rig;
  rig.daemon.keep_log_level(true);
  log::set_level(log::Level::warn);
  rig.next.config.log.level = config::LogLevel::debug;
  const ReloadOutcome outcome = rig.daemon.reload();
  EXPECT_TRUE(outcome.applied.empty());
  EXPECT_EQ(log::level(), log::Level::warn);
}

TEST(DaemonReload, NothingToReadWithoutAFile) {
  TestSocket socket;
  ScopedEnv env("NOTIFY_SOCKET", socket.path());
  Daemon daemon(config::Config{}, service::Notifier::from_environment(), std::nullopt);
  const ReloadOutcome outcome = daemon.reload();
  EXPECT_FALSE(outcome.refused);
  EXPECT_TRUE(outcome.applied.empty());
  const auto datagrams = socket.receive_all(200ms);
  ASSERT_EQ(datagrams.size(), 2U);
  EXPECT_EQ(datagrams[1], "READY=1\nSTATUS=running");
}

}  // namespace
}  // namespace liftd::daemon
