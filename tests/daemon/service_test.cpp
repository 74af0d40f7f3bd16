// sd_notify datagrams, WATCHDOG_USEC parsing and the progress-gated watchdog.
#include "service/notify.hpp"

#include <gtest/gtest.h>

#include <sys/socket.h>
#include <sys/un.h>

#include "daemon/test_socket.hpp"

namespace liftd::service {
namespace {

using namespace std::chrono_literals;
using testing::TestSocket;

TEST(Notifier, SendsEachNotificationAsOneDatagram) {
  TestSocket socket;
  Notifier notifier(socket.path());
  ASSERT_TRUE(notifier.enabled());
  // Legend: call -> exact datagram (sd_notify(3) format: newline-separated KEY=value).
  EXPECT_EQ(notifier.status("starting"), 0);
  EXPECT_EQ(socket.receive(2s), "STATUS=starting");
  EXPECT_EQ(notifier.ready("running"), 0);
  EXPECT_EQ(socket.receive(2s), "READY=1\nSTATUS=running");
  EXPECT_EQ(notifier.watchdog(), 0);
  EXPECT_EQ(socket.receive(2s), "WATCHDOG=1");
  EXPECT_EQ(notifier.stopping("stopping: SIGTERM"), 0);
  EXPECT_EQ(socket.receive(2s), "STOPPING=1\nSTATUS=stopping: SIGTERM");
}

TEST(Notifier, ReachesAnAbstractSocket) {
  const std::string name = "liftd-test-" + std::to_string(::getpid());
  const int fd = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  ASSERT_GE(fd, 0);
  sockaddr_un address{};
  address.sun_family = AF_UNIX;
  std::memcpy(address.sun_path + 1, name.data(), name.size());  // sun_path[0] = 0: abstract
  const auto length = static_cast<socklen_t>(offsetof(sockaddr_un, sun_path) + 1 + name.size());
  ASSERT_EQ(::bind(fd, reinterpret_cast<const sockaddr*>(&address), length), 0);
  Notifier notifier("@" + name);
  EXPECT_EQ(notifier.notify("READY=1"), 0);
  char buffer[64] = {};
  const ssize_t n = ::recv(fd, buffer, sizeof(buffer), 0);
  ::close(fd);
  EXPECT_EQ(std::string(buffer, static_cast<std::size_t>(n > 0 ? n : 0)), "READY=1");
}

TEST(Notifier, DisabledWithoutASocketAndHarmless) {
  Notifier notifier;
  EXPECT_FALSE(notifier.enabled());
  EXPECT_EQ(notifier.ready("x"), 0);
  ::unsetenv("NOTIFY_SOCKET");
  EXPECT_FALSE(Notifier::from_environment().enabled());
  ::setenv("NOTIFY_SOCKET", "/run/systemd/notify", 1);
  EXPECT_EQ(Notifier::from_environment().socket(), "/run/systemd/notify");
  ::unsetenv("NOTIFY_SOCKET");
}

TEST(Notifier, ReportsAnUnreachableSocket) {
  Notifier notifier("/nonexistent/notify");
  EXPECT_EQ(notifier.status("x"), ENOENT);
}

TEST(WatchdogEnvironment, ParsesUsecAndChecksPid) {
  // Legend: WATCHDOG_USEC, WATCHDOG_PID, our pid -> timeout (nullopt: no watchdog).
  struct Case {
    const char* usec;
    const char* pid;
    pid_t self;
    std::optional<std::chrono::microseconds> expected;
  };
  const std::vector<Case> cases = {
      {"5000000", nullptr, 42, 5s},
      {"5000000", "42", 42, 5s},
      {"5000000", "", 42, 5s},
      {"5000000", "43", 42, std::nullopt},
      {"5000000", "4x", 42, std::nullopt},
      {nullptr, nullptr, 42, std::nullopt},
      {"", nullptr, 42, std::nullopt},
      {"0", nullptr, 42, std::nullopt},
      {"-5", nullptr, 42, std::nullopt},
      {"12abc", nullptr, 42, std::nullopt},
      {"200000", nullptr, 42, 200ms},
  };
  for (const auto& c : cases) {
    EXPECT_EQ(parse_watchdog(c.usec, c.pid, c.self), c.expected)
        << (c.usec ? c.usec : "(unset)") << " / " << (c.pid ? c.pid : "(unset)");
  }
}

TEST(Watchdog, PeriodIsHalfTheTimeout) {
  asio::io_context io;
  Notifier notifier;
  Watchdog dog(io, notifier, 5s, {});
  EXPECT_EQ(dog.period(), 2500ms);
}

TEST(Watchdog, PingsOnlyWhileTheProbeReportsProgress) {
  TestSocket socket;
  asio::io_context io;
  Notifier notifier(socket.path());
  bool progress = true;
  Watchdog dog(io, notifier, 20ms, [&] { return progress; });
  dog.start();  // first ping at once
  EXPECT_EQ(dog.pings_sent(), 1U);
  EXPECT_EQ(socket.receive(2s), "WATCHDOG=1");
  // Run until three more periods have fired (counts, not wall time, decide).
  while (dog.pings_sent() < 4) io.run_one();
  for (int i = 0; i < 3; ++i) EXPECT_EQ(socket.receive(2s), "WATCHDOG=1");
  progress = false;
  while (dog.pings_withheld() < 3) io.run_one();
  EXPECT_EQ(dog.pings_sent(), 4U);
  EXPECT_FALSE(socket.receive(50ms).has_value());
  progress = true;
  while (dog.pings_sent() < 5) io.run_one();
  EXPECT_EQ(socket.receive(2s), "WATCHDOG=1");
  dog.stop();
  io.run();  // the cancelled wait completes; nothing more is sent
  EXPECT_EQ(dog.pings_sent(), 5U);
  EXPECT_FALSE(socket.receive(50ms).has_value());
}

}  // namespace
}  // namespace liftd::service
