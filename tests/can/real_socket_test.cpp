// The CAN endpoint over the kernel's SocketCAN (a vcan interface): the same read/write path the
// Unix-socket tests cover, here with the kernel's filters, its loopback rules, error frames and
// an interface that goes down and up. Needs AF_CAN, which this project's build machines lack:
// tools/uml/can-stage.sh runs these tests inside user-mode Linux with vcan0 up and
// LIFTD_TEST_CAN=vcan0 (label "vcan"; the host's ctest run leaves the label out). With
// LIFTD_TEST_CAN set, a kernel without AF_CAN or a missing interface is a failure, not a skip.
#include <gtest/gtest.h>
#include <linux/can.h>
#include <linux/can/error.h>
#include <net/if.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "can/interface_info.hpp"
#include "can/socket.hpp"

namespace liftd::can {
namespace {

using Bytes = std::vector<std::uint8_t>;

/// The interface under test (LIFTD_TEST_CAN), or empty when the test runs outside the stage.
std::string interface_under_test() {
  const char* name = std::getenv("LIFTD_TEST_CAN");
  return name == nullptr ? std::string() : std::string(name);
}

#define REQUIRE_CAN_INTERFACE(name)                                                        \
  const std::string name = interface_under_test();                                         \
  if (name.empty()) {                                                                      \
    GTEST_SKIP() << "LIFTD_TEST_CAN is not set: run by tools/uml/can-stage.sh (user-mode " \
                    "Linux with vcan0), or set it to a vcan interface of this machine";    \
  }                                                                                        \
  ASSERT_TRUE(kernel_has_can()) << "LIFTD_TEST_CAN=" << name << " but this kernel has no " \
                                << "AF_CAN";                                               \
  ASSERT_TRUE(query_interface(name).found) << "no interface " << name

/// Reads until something other than Nothing arrives (at most 2 s).
Received read_one(CanSocket& s) {
  for (int i = 0; i < 200; ++i) {
    const Received r = s.read();
    if (r.kind != Received::Kind::Nothing) return r;
    pollfd p{s.fd(), POLLIN, 0};
    ::poll(&p, 1, 10);
  }
  return {};
}

/// Reads for `ms` and returns every record that came (Nothing excluded).
std::vector<Received> read_all(CanSocket& s, int ms) {
  std::vector<Received> out;
  for (int i = 0; i < ms / 10; ++i) {
    for (Received r = s.read(); r.kind != Received::Kind::Nothing; r = s.read()) out.push_back(r);
    pollfd p{s.fd(), POLLIN, 0};
    ::poll(&p, 1, 10);
  }
  return out;
}

/// `ip link set IFACE up|down` (root inside the guest).
void set_link(const std::string& name, bool up) {
  const std::string command = "ip link set " + name + (up ? " up" : " down");
  ASSERT_EQ(std::system(command.c_str()), 0) << command;
}

TEST(CanRealSocket, FramesOverTheInterface) {
  REQUIRE_CAN_INTERFACE(name);
  auto a = CanSocket::open(name, {0x551});
  ASSERT_TRUE(a) << a.error().what << ": " << std::strerror(a.error().code);
  auto b = CanSocket::open(name, {0x581});
  ASSERT_TRUE(b) << b.error().what;
  ASSERT_EQ(b.value().write(make_frame(0x551, Bytes{0x68, 0x01, 0, 2})), 0);
  const Received r = read_one(a.value());
  ASSERT_EQ(r.kind, Received::Kind::Frame);
  EXPECT_EQ(r.frame, make_frame(0x551, Bytes{0x68, 0x01, 0, 2}));
  ASSERT_EQ(a.value().write(make_frame(0x581, Bytes{0x61, 0x02})), 0);
  const Received back = read_one(b.value());
  ASSERT_EQ(back.kind, Received::Kind::Frame);
  EXPECT_EQ(back.frame, make_frame(0x581, Bytes{0x61, 0x02}));
}

// The kernel filter (CAN_RAW_FILTER) keeps every identifier the socket did not ask for out:
// nothing of them reaches the socket, so our own filter counts no drop.
TEST(CanRealSocket, KernelFilterPassesOnlyTheWantedIdentifiers) {
  REQUIRE_CAN_INTERFACE(name);
  auto reader = CanSocket::open(name, {0x581, 0x1A0});
  ASSERT_TRUE(reader) << reader.error().what;
  auto writer = CanSocket::open(name, {});
  ASSERT_TRUE(writer) << writer.error().what;
  for (std::uint32_t id : {0x000U, 0x551U, 0x580U, 0x581U, 0x582U, 0x1A0U, 0x7FFU}) {
    ASSERT_EQ(writer.value().write(make_frame(id, Bytes{static_cast<std::uint8_t>(id)})), 0);
  }
  const auto got = read_all(reader.value(), 300);
  ASSERT_EQ(got.size(), 2U);
  EXPECT_EQ(got[0].frame, make_frame(0x581, Bytes{0x81}));
  EXPECT_EQ(got[1].frame, make_frame(0x1A0, Bytes{0xA0}));
  EXPECT_EQ(reader.value().drops().filtered, 0U) << "the kernel filter, not ours, drops them";
  // Empty: every identifier.
  auto all = CanSocket::open(name, {});
  ASSERT_TRUE(all);
  ASSERT_EQ(writer.value().write(make_frame(0x123, Bytes{1})), 0);
  const Received r = read_one(all.value());
  ASSERT_EQ(r.kind, Received::Kind::Frame);
  EXPECT_EQ(r.frame.id, 0x123U);
}

// A reader that falls behind the bus: the kernel drops what its full receive queue cannot
// hold, and the endpoint counts every such frame (SO_RXQ_OVFL) instead of losing it unseen.
TEST(CanRealSocket, FramesTheKernelDroppedOnAFullQueueAreCounted) {
  REQUIRE_CAN_INTERFACE(name);
  auto reader = CanSocket::open(name, {0x581});
  ASSERT_TRUE(reader) << reader.error().what;
  const int smallest = 1;  // the kernel rounds it up to its minimum (a few frames)
  ASSERT_EQ(::setsockopt(reader.value().fd(), SOL_SOCKET, SO_RCVBUF, &smallest, sizeof smallest),
            0);
  auto writer = CanSocket::open(name, {});
  ASSERT_TRUE(writer) << writer.error().what;
  constexpr int kSent = 400;
  for (int i = 0; i < kSent; ++i) {
    ASSERT_EQ(writer.value().write(make_frame(0x581, Bytes{0x61, static_cast<std::uint8_t>(i)})),
              0);
    if (i % 50 == 49) ::usleep(2000);  // the loopback's backlog drains: no drop before the socket
  }
  const auto got = read_all(reader.value(), 300);
  // The kernel reports its running count of drops with the next frame it queues (SO_RXQ_OVFL),
  // so the drops behind the last frame read show with the next one.
  EXPECT_EQ(reader.value().drops().overflowed, 0U) << "reported before a later frame came";
  ASSERT_EQ(writer.value().write(make_frame(0x581, Bytes{0x61, 0xFF})), 0);
  const Received next = read_one(reader.value());
  ASSERT_EQ(next.kind, Received::Kind::Frame);
  EXPECT_EQ(next.frame.data[1], 0xFF);
  const std::uint64_t overflowed = reader.value().drops().overflowed;
  EXPECT_GT(overflowed, 0U) << "the queue held all " << kSent << " frames";
  EXPECT_EQ(got.size() + overflowed, static_cast<std::uint64_t>(kSent))
      << got.size() << " read, " << overflowed << " counted as dropped";
  // Counted once: a second frame after it brings the same running total.
  ASSERT_EQ(writer.value().write(make_frame(0x581, Bytes{0x61, 0xFE})), 0);
  ASSERT_EQ(read_one(reader.value()).kind, Received::Kind::Frame);
  EXPECT_EQ(reader.value().drops().overflowed, overflowed);
  // Nobody read while they came: the queue kept the first frames and the kernel dropped the
  // rest.
  for (std::size_t i = 0; i < got.size(); ++i) {
    ASSERT_EQ(got[i].frame.data[1], static_cast<std::uint8_t>(i)) << "frame " << i;
  }
  EXPECT_EQ(reader.value().drops().filtered + reader.value().drops().malformed, 0U);
}

// The kernel's loopback rules: every other socket on the interface sees a frame this one sends
// (how a controller and a card simulator on one vcan talk), the sender does not see its own
// frame even where its filter asks for that identifier (CAN_RAW_RECV_OWN_MSGS is off), and a
// frame another node sends on the sender's own identifier does reach it.
TEST(CanRealSocket, OwnFramesAreNotReadBackOthersOnTheSameIdentifierAre) {
  REQUIRE_CAN_INTERFACE(name);
  auto controller = CanSocket::open(name, {0x551, 0x581});
  ASSERT_TRUE(controller);
  auto other = CanSocket::open(name, {0x551});
  ASSERT_TRUE(other);
  ASSERT_EQ(controller.value().write(make_frame(0x551, Bytes{0x68, 0, 0, 0})), 0);
  const Received seen = read_one(other.value());
  ASSERT_EQ(seen.kind, Received::Kind::Frame);
  EXPECT_EQ(seen.frame, make_frame(0x551, Bytes{0x68, 0, 0, 0}));
  EXPECT_TRUE(read_all(controller.value(), 200).empty()) << "its own frame came back";
  ASSERT_EQ(other.value().write(make_frame(0x551, Bytes{0x68, 0x01, 0, 1})), 0);
  const Received foreign = read_one(controller.value());
  ASSERT_EQ(foreign.kind, Received::Kind::Frame)
      << "a frame on its own identifier from another node";
  EXPECT_EQ(foreign.frame, make_frame(0x551, Bytes{0x68, 0x01, 0, 1}));
}

// Error frames: vcan has no controller to raise them, but it carries one a socket sends (the
// way a CAN controller driver hands them to every reader); the endpoint asks for them
// (CAN_RAW_ERR_FILTER) and decodes them on the same path as data frames.
TEST(CanRealSocket, ErrorFramesReachTheReaderDecoded) {
  REQUIRE_CAN_INTERFACE(name);
  auto reader = CanSocket::open(name, {0x581});
  ASSERT_TRUE(reader);
  const int raw = ::socket(PF_CAN, SOCK_RAW | SOCK_CLOEXEC, CAN_RAW);
  ASSERT_GE(raw, 0) << std::strerror(errno);
  sockaddr_can address{};
  address.can_family = AF_CAN;
  address.can_ifindex = static_cast<int>(::if_nametoindex(name.c_str()));
  ASSERT_EQ(::bind(raw, reinterpret_cast<sockaddr*>(&address), sizeof address), 0)
      << std::strerror(errno);
  struct Case {
    std::uint32_t error_class;
    std::uint8_t controller;
    bool ErrorReport::*flag;
  };
  for (const Case& c :
       {Case{CAN_ERR_BUSOFF, 0, &ErrorReport::bus_off}, Case{CAN_ERR_ACK, 0, &ErrorReport::no_ack},
        Case{CAN_ERR_CRTL, CAN_ERR_CRTL_TX_PASSIVE, &ErrorReport::error_passive},
        Case{CAN_ERR_RESTARTED, 0, &ErrorReport::restarted}}) {
    can_frame cf{};
    cf.can_id = CAN_ERR_FLAG | c.error_class;
    cf.len = CAN_ERR_DLC;
    cf.data[1] = c.controller;
    ASSERT_EQ(::write(raw, &cf, sizeof cf), static_cast<ssize_t>(sizeof cf))
        << std::strerror(errno);
    const Received r = read_one(reader.value());
    ASSERT_EQ(r.kind, Received::Kind::Error) << std::hex << c.error_class;
    EXPECT_TRUE(r.error.*(c.flag)) << r.error.describe();
  }
  // CAN_ERR_BUSERROR is left out on purpose (a broken bus floods it): not passed on.
  can_frame bus_error{};
  bus_error.can_id = CAN_ERR_FLAG | CAN_ERR_BUSERROR;
  bus_error.len = CAN_ERR_DLC;
  ASSERT_EQ(::write(raw, &bus_error, sizeof bus_error), static_cast<ssize_t>(sizeof bus_error));
  EXPECT_TRUE(read_all(reader.value(), 200).empty());
  ::close(raw);
}

// The interface goes down and comes back: while it is down a write fails with ENETDOWN and the
// reader is told once (Failed, ENETDOWN); once it is up the same sockets carry frames again,
// after the one ENETDOWN report the kernel keeps for a socket that made no call while it was
// down (what a controller must expect after reopening nothing: its first write may fail).
TEST(CanRealSocket, InterfaceDownAndUpAgain) {
  REQUIRE_CAN_INTERFACE(name);
  auto a = CanSocket::open(name, {0x551});
  ASSERT_TRUE(a);
  auto b = CanSocket::open(name, {0x581});
  ASSERT_TRUE(b);
  set_link(name, false);
  EXPECT_FALSE(query_interface(name).up);
  EXPECT_EQ(b.value().write(make_frame(0x551, Bytes{1})), ENETDOWN);
  std::vector<Received> while_down = read_all(a.value(), 200);
  ASSERT_FALSE(while_down.empty()) << "the reader is not told that the interface went down";
  EXPECT_EQ(while_down.front().kind, Received::Kind::Failed);
  EXPECT_EQ(while_down.front().errno_value, ENETDOWN);
  for (const Received& r : while_down) EXPECT_NE(r.kind, Received::Kind::Frame);
  set_link(name, true);
  EXPECT_TRUE(query_interface(name).up);
  ASSERT_EQ(b.value().write(make_frame(0x551, Bytes{2})), 0);
  Received r = read_one(a.value());
  while (r.kind == Received::Kind::Failed) r = read_one(a.value());  // a late down report
  ASSERT_EQ(r.kind, Received::Kind::Frame);
  EXPECT_EQ(r.frame, make_frame(0x551, Bytes{2}));
  // A socket opened while it was down works too once it is up. The kernel left the down report
  // pending on b (it made no call while the interface was down): its next call, this write,
  // gets ENETDOWN once, and the write after it goes out.
  set_link(name, false);
  auto c = CanSocket::open(name, {0x551});
  set_link(name, true);
  ASSERT_TRUE(c) << c.error().what << ": " << std::strerror(c.error().code);
  EXPECT_EQ(b.value().write(make_frame(0x551, Bytes{3})), ENETDOWN) << "the pending down report";
  ASSERT_EQ(b.value().write(make_frame(0x551, Bytes{3})), 0);
  Received rc = read_one(c.value());
  while (rc.kind == Received::Kind::Failed) rc = read_one(c.value());
  ASSERT_EQ(rc.kind, Received::Kind::Frame);
  EXPECT_EQ(rc.frame, make_frame(0x551, Bytes{3}));
}

TEST(CanRealSocket, NamesAMissingInterface) {
  REQUIRE_CAN_INTERFACE(name);
  auto s = CanSocket::open("nosuchcan9", {});
  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().what, "no network interface \"nosuchcan9\"");
}

// rtnetlink's view of the vcan: present, its state, no bitrate (a vcan has none; liftd warns).
TEST(CanRealSocket, InterfaceInfoOfTheVcan) {
  REQUIRE_CAN_INTERFACE(name);
  const InterfaceInfo info = query_interface(name);
  ASSERT_TRUE(info.found) << info.error;
  EXPECT_TRUE(info.up);
  EXPECT_FALSE(info.bitrate.has_value());
}

}  // namespace
}  // namespace liftd::can
