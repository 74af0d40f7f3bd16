// The Daemon frame in-process: component order, start failure, stop requests, notifications.
#include "daemon/daemon.hpp"

#include <gtest/gtest.h>

#include <asio/post.hpp>
#include <string>
#include <vector>

#include "daemon/test_socket.hpp"

namespace liftd::daemon {
namespace {

using namespace std::chrono_literals;
using testing::TestSocket;

TEST(Daemon, StartsInOrderStopsInReverseAndReturnsTheRequestedCode) {
  TestSocket socket;
  Daemon daemon(config::Config{}, service::Notifier(socket.path()), std::nullopt);
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
  Daemon daemon(config::Config{}, service::Notifier(socket.path()), std::nullopt);
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
  Daemon daemon(config::Config{}, service::Notifier(socket.path()), 20ms);
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
  EXPECT_EQ(signal_name(SIGTERM), "SIGTERM");
  EXPECT_EQ(signal_name(SIGINT), "SIGINT");
  EXPECT_EQ(signal_name(SIGHUP), "SIGHUP");
  EXPECT_EQ(signal_name(SIGUSR1), "signal " + std::to_string(SIGUSR1));
}

}  // namespace
}  // namespace liftd::daemon
