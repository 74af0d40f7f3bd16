// sd_notify datagrams through libsystemd, sd_watchdog_enabled, listen fds, and the
// progress-gated watchdog. libsystemd reads $NOTIFY_SOCKET, $WATCHDOG_USEC and $LISTEN_FDS, so
// these tests set them (ScopedEnv) to sockets the test binds.
#include "service/notify.hpp"

#include <gtest/gtest.h>

#include <fcntl.h>
#include <sys/socket.h>
#include <sys/un.h>

#include <cstring>
#include <string>
#include <vector>

#include "daemon/test_socket.hpp"

namespace liftd::service {
namespace {

using namespace std::chrono_literals;
using testing::ScopedEnv;
using testing::TestSocket;

TEST(Notifier, SendsEachNotificationAsOneDatagram) {
  TestSocket socket;
  ScopedEnv env("NOTIFY_SOCKET", socket.path());
  Notifier notifier = Notifier::from_environment();
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
  EXPECT_EQ(notifier.status("two\nlines"), 0);
  EXPECT_EQ(socket.receive(2s), "STATUS=two lines");  // a newline would start a new key
}

TEST(Notifier, ReloadingCarriesTheMonotonicTime) {
  TestSocket socket;
  ScopedEnv env("NOTIFY_SOCKET", socket.path());
  Notifier notifier = Notifier::from_environment();
  timespec before{};
  ::clock_gettime(CLOCK_MONOTONIC, &before);
  ASSERT_EQ(notifier.reloading("reloading /etc/liftd/liftd.json"), 0);
  timespec after{};
  ::clock_gettime(CLOCK_MONOTONIC, &after);
  const std::string datagram = socket.receive(2s).value_or("");
  const std::string head = "RELOADING=1\nSTATUS=reloading /etc/liftd/liftd.json\nMONOTONIC_USEC=";
  ASSERT_EQ(datagram.substr(0, head.size()), head) << datagram;
  const auto usec = std::stoull(datagram.substr(head.size()));
  const auto to_usec = [](const timespec& t) {
    return static_cast<unsigned long long>(t.tv_sec) * 1000000ULL +
           static_cast<unsigned long long>(t.tv_nsec) / 1000ULL;
  };
  EXPECT_GE(usec, to_usec(before));
  EXPECT_LE(usec, to_usec(after));
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
  ScopedEnv env("NOTIFY_SOCKET", "@" + name);
  EXPECT_EQ(Notifier::from_environment().notify("READY=1"), 0);
  char buffer[64] = {};
  const ssize_t n = ::recv(fd, buffer, sizeof(buffer), 0);
  ::close(fd);
  EXPECT_EQ(std::string(buffer, static_cast<std::size_t>(n > 0 ? n : 0)), "READY=1");
}

TEST(Notifier, DisabledWithoutASocketAndHarmless) {
  Notifier notifier;
  EXPECT_FALSE(notifier.enabled());
  EXPECT_EQ(notifier.ready("x"), 0);
  {
    ScopedEnv env("NOTIFY_SOCKET", nullptr);
    EXPECT_FALSE(Notifier::from_environment().enabled());
  }
  ScopedEnv env("NOTIFY_SOCKET", "");
  EXPECT_FALSE(Notifier::from_environment().enabled());
}

TEST(Notifier, ReportsAnUnreachableSocket) {
  ScopedEnv env("NOTIFY_SOCKET", "/nonexistent/notify");
  EXPECT_EQ(Notifier::from_environment().status("x"), ENOENT);
}

TEST(WatchdogEnvironment, FollowsSdWatchdogEnabled) {
  // Legend: WATCHDOG_USEC, WATCHDOG_PID ("self": this process) -> timeout (nullopt: none).
  const std::string self = std::to_string(::getpid());
  struct Case {
    const char* usec;
    const char* pid;
    std::optional<std::chrono::microseconds> expected;
  };
  const std::vector<Case> cases = {
      {"5000000", nullptr, 5s},         {"5000000", "self", 5s},
      {"5000000", "1", std::nullopt},   // meant for another process
      {"5000000", "4x", std::nullopt},  // malformed pid
      {"5000000", "", std::nullopt},    // malformed pid
      {nullptr, nullptr, std::nullopt}, {"", nullptr, std::nullopt},
      {"0", nullptr, std::nullopt},     {"-5", nullptr, std::nullopt},
      {"12abc", nullptr, std::nullopt}, {"200000", nullptr, 200ms},
  };
  for (const auto& c : cases) {
    const char* pid = c.pid != nullptr && std::string(c.pid) == "self" ? self.c_str() : c.pid;
    ScopedEnv usec("WATCHDOG_USEC", c.usec);
    ScopedEnv owner("WATCHDOG_PID", pid);
    EXPECT_EQ(watchdog_from_environment(), c.expected)
        << (c.usec ? c.usec : "(unset)") << " / " << (c.pid ? c.pid : "(unset)");
  }
}

TEST(ListenFds, NoneWithoutSocketActivation) {
  ScopedEnv fds("LISTEN_FDS", nullptr);
  ScopedEnv pid("LISTEN_PID", nullptr);
  EXPECT_TRUE(listen_fds_from_environment().empty());
}

TEST(ListenFds, PicksTheNamedListeningUnixStreamSocket) {
  // A listening Unix stream socket, a datagram socket and an unbound stream socket.
  const int listening = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
  sockaddr_un address{};
  address.sun_family = AF_UNIX;  // autobind: an abstract address chosen by the kernel
  ASSERT_EQ(::bind(listening, reinterpret_cast<const sockaddr*>(&address), sizeof(sa_family_t)), 0);
  ASSERT_EQ(::listen(listening, 4), 0);
  const int datagram = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  const int idle = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
  // Legend: passed fds -> what pick_listen_fd takes for "api".
  EXPECT_EQ(pick_listen_fd({{datagram, "api"}, {listening, "api"}}, "api"), listening);
  EXPECT_EQ(pick_listen_fd({{listening, "liftd.socket"}}, "api"), listening);  // the only one
  EXPECT_EQ(pick_listen_fd({{listening, "other"}, {idle, "x"}}, "api"), -1);
  EXPECT_EQ(pick_listen_fd({{datagram, "api"}}, "api"), -1);
  EXPECT_EQ(pick_listen_fd({{idle, "api"}}, "api"), -1);  // not listening
  EXPECT_EQ(pick_listen_fd({}, "api"), -1);
  for (int fd : {listening, datagram, idle}) ::close(fd);
}

// A refused start on the socket systemd passed: the waiting client gets one error line and an
// end of file, not a connection that hangs until the start limit takes the socket down. And the
// refused start ends at its deadline although the socket is blocking and nobody else comes.
TEST(RefusedStart, AnswersEachWaitingClientWithOneErrorLine) {
  const int listening = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
  sockaddr_un address{};
  address.sun_family = AF_UNIX;  // autobind
  ASSERT_EQ(::bind(listening, reinterpret_cast<const sockaddr*>(&address), sizeof(sa_family_t)), 0);
  ASSERT_EQ(::listen(listening, 4), 0);  // blocking, as systemd passes it
  sockaddr_un bound{};
  socklen_t length = sizeof bound;
  ASSERT_EQ(::getsockname(listening, reinterpret_cast<sockaddr*>(&bound), &length), 0);
  std::vector<int> clients;
  for (int i = 0; i < 2; ++i) {
    const int c = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
    ASSERT_EQ(::connect(c, reinterpret_cast<const sockaddr*>(&bound), length), 0);
    clients.push_back(c);
  }
  // The first client already sent its request, as liftctl does.
  const std::string request = "{\"cmd\":\"status\",\"id\":1}\n";
  ASSERT_EQ(::send(clients[0], request.data(), request.size(), 0),
            static_cast<ssize_t>(request.size()));
  EXPECT_EQ(answer_refused_start(listening, "it refused \"x.json\"", 0ms), 2U);
  for (const int c : clients) {
    std::string got;
    char buf[256];
    ssize_t n;
    while ((n = ::recv(c, buf, sizeof buf, 0)) > 0) got.append(buf, static_cast<std::size_t>(n));
    EXPECT_EQ(n, 0) << std::strerror(errno);  // an orderly end, not a reset
    EXPECT_EQ(got,
              "{\"id\":null,\"ok\":false,\"error\":{\"code\":\"not_ready\",\"message\":"
              "\"it refused \\\"x.json\\\"\"}}\n");
    ::close(c);
  }
  EXPECT_EQ(answer_refused_start(listening, "none waiting", 0ms), 0U);
  ::close(listening);
}

TEST(Watchdog, PeriodIsHalfTheTimeout) {
  asio::io_context io;
  Notifier notifier;
  Watchdog dog(io, notifier, 5s, {});
  EXPECT_EQ(dog.period(), 2500ms);
}

TEST(Watchdog, PingsOnlyWhileTheProbeReportsProgress) {
  TestSocket socket;
  ScopedEnv env("NOTIFY_SOCKET", socket.path());
  asio::io_context io;
  Notifier notifier = Notifier::from_environment();
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

// The daemon's progress probes compare a cycle counter with its value at their previous call,
// starting from 0. Right after READY=1 the cycle thread may not have counted its first cycle
// yet: that is a healthy start, not a stall. The first judgement must cover a whole period.
TEST(Watchdog, NoFalseAlarmWhenTheCycleHasNotCountedItsFirstCycleAtStart) {
  TestSocket socket;
  ScopedEnv env("NOTIFY_SOCKET", socket.path());
  asio::io_context io;
  Notifier notifier = Notifier::from_environment();
  std::uint64_t cycles = 0;  // the cycle thread has not run yet
  std::uint64_t last = 0;
  int probes = 0;
  Watchdog dog(io, notifier, 20ms, [&] {
    ++probes;
    const bool advanced = cycles != last;
    last = cycles;
    return advanced;
  });
  dog.start();
  EXPECT_EQ(dog.pings_sent(), 1U);
  EXPECT_EQ(dog.pings_withheld(), 0U);
  EXPECT_EQ(probes, 1);  // the baseline was taken
  EXPECT_EQ(socket.receive(2s), "WATCHDOG=1");
  cycles = 166;  // one period of 15 ms cycles later
  while (dog.pings_sent() + dog.pings_withheld() < 2) io.run_one();
  EXPECT_EQ(dog.pings_sent(), 2U);
  EXPECT_EQ(dog.pings_withheld(), 0U);
  EXPECT_EQ(socket.receive(2s), "WATCHDOG=1");
  // A cycle that never advances after the start is still caught one period later.
  while (dog.pings_withheld() < 1) io.run_one();
  EXPECT_EQ(dog.pings_sent(), 2U);
  dog.stop();
  io.run();
}

TEST(Watchdog, ACycleStuckFromTheStartIsCaughtAfterOnePeriod) {
  TestSocket socket;
  ScopedEnv env("NOTIFY_SOCKET", socket.path());
  asio::io_context io;
  Notifier notifier = Notifier::from_environment();
  std::uint64_t last = 0;
  const std::uint64_t cycles = 0;  // never advances
  Watchdog dog(io, notifier, 20ms, [&] {
    const bool advanced = cycles != last;
    last = cycles;
    return advanced;
  });
  dog.start();
  while (dog.pings_sent() + dog.pings_withheld() < 2) io.run_one();
  EXPECT_EQ(dog.pings_sent(), 1U);  // the start's ping only
  EXPECT_EQ(dog.pings_withheld(), 1U);
  dog.stop();
  io.run();
}

}  // namespace
}  // namespace liftd::service
