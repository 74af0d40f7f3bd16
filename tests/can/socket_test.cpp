// The CAN endpoint over Unix SOCK_SEQPACKET sockets (the path simulators and tests use) and the
// error-frame decoding. The same endpoint over a real SocketCAN interface: real_socket_test.cpp.
#include <gtest/gtest.h>

#include <linux/can.h>
#include <linux/can/error.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <vector>

#include "can/interface_info.hpp"
#include "can/socket.hpp"

namespace liftd::can {
namespace {

using Bytes = std::vector<std::uint8_t>;

/// Reads until something other than Nothing arrives (at most 1 s).
Received read_one(CanSocket& s) {
  for (int i = 0; i < 100; ++i) {
    const Received r = s.read();
    if (r.kind != Received::Kind::Nothing) return r;
    pollfd p{s.fd(), POLLIN, 0};
    ::poll(&p, 1, 10);
  }
  return {};
}

TEST(CanSocketPair, CarriesFramesBothWays) {
  auto pair = CanSocket::pair();
  ASSERT_TRUE(pair) << pair.error().what;
  auto& [a, b] = pair.value();
  const Frame sent = make_frame(0x551, Bytes{0x68, 0x15, 0x00, 0x03});
  ASSERT_EQ(a.write(sent), 0);
  const Received r = read_one(b);
  ASSERT_EQ(r.kind, Received::Kind::Frame);
  EXPECT_EQ(r.frame, sent);
  ASSERT_EQ(b.write(make_frame(0x581, Bytes{0x61, 0x02})), 0);
  const Received back = read_one(a);
  ASSERT_EQ(back.kind, Received::Kind::Frame);
  EXPECT_EQ(back.frame.id, 0x581U);
  EXPECT_EQ(back.frame.length, 2);
  EXPECT_EQ(a.read().kind, Received::Kind::Nothing) << "nothing more queued";
}

TEST(CanSocketPair, RefusesFramesNoClassicCanFrameCanBe) {
  auto pair = CanSocket::pair();
  ASSERT_TRUE(pair);
  Frame f = make_frame(0x800, Bytes{1});  // 12 bits
  EXPECT_EQ(pair.value().first.write(f), EINVAL);
}

TEST(CanSocketPair, TellsWhenThePeerCloses) {
  auto pair = CanSocket::pair();
  ASSERT_TRUE(pair);
  CanSocket a = std::move(pair.value().first);
  { CanSocket gone = std::move(pair.value().second); }
  EXPECT_EQ(read_one(a).kind, Received::Kind::Closed);
  EXPECT_NE(a.write(make_frame(0x551, Bytes{1})), 0) << "writing to a closed peer fails";
}

TEST(CanSocketPair, AnEmptyRecordIsARecordNotTheEndOfTheConnection) {
  int fds[2];
  ASSERT_EQ(::socketpair(AF_UNIX, SOCK_SEQPACKET | SOCK_NONBLOCK | SOCK_CLOEXEC, 0, fds), 0);
  CanSocket reader = CanSocket::adopt(fds[0], {0x581});
  ASSERT_EQ(::send(fds[1], "", 0, 0), 0);
  ASSERT_EQ(::send(fds[1], "", 0, 0), 0);
  can_frame cf{};
  cf.can_id = 0x581;
  cf.len = 2;
  cf.data[0] = 0x61;
  cf.data[1] = 0x02;
  ASSERT_EQ(::send(fds[1], &cf, sizeof cf, 0), static_cast<ssize_t>(sizeof cf));
  // Two empty records (counted as malformed, the connection kept), then the frame.
  const Received r = read_one(reader);
  ASSERT_EQ(r.kind, Received::Kind::Frame) << "an empty record was taken for end of file";
  EXPECT_EQ(r.frame, make_frame(0x581, Bytes{0x61, 0x02}));
  EXPECT_EQ(reader.drops().malformed, 2U);
  // An empty record and then the peer's close: the connection ends.
  ASSERT_EQ(::send(fds[1], "", 0, 0), 0);
  ::close(fds[1]);
  EXPECT_EQ(read_one(reader).kind, Received::Kind::Closed);
}

TEST(CanSocketPair, DropsWhatIsNotAWantedClassicFrame) {
  int fds[2];
  ASSERT_EQ(::socketpair(AF_UNIX, SOCK_SEQPACKET | SOCK_NONBLOCK | SOCK_CLOEXEC, 0, fds), 0);
  CanSocket reader = CanSocket::adopt(fds[0], {0x581});
  const auto send_raw = [&](const void* data, std::size_t size) {
    ASSERT_EQ(::send(fds[1], data, size, 0), static_cast<ssize_t>(size));
  };
  can_frame cf{};
  cf.can_id = 0x123;  // not in the filter
  cf.len = 1;
  send_raw(&cf, sizeof cf);
  cf.can_id = 0x581 | CAN_EFF_FLAG;  // 29-bit
  send_raw(&cf, sizeof cf);
  cf.can_id = 0x581 | CAN_RTR_FLAG;  // remote frame
  send_raw(&cf, sizeof cf);
  cf.can_id = 0x581;
  cf.len = 9;  // longer than a classic frame
  send_raw(&cf, sizeof cf);
  const char junk[5] = "abcd";  // not one can_frame
  send_raw(junk, sizeof junk);
  cf.len = 2;
  cf.data[0] = 0x61;
  send_raw(&cf, sizeof cf);
  const Received r = read_one(reader);  // the six records: only the last is passed on
  ASSERT_EQ(r.kind, Received::Kind::Frame);
  EXPECT_EQ(r.frame, make_frame(0x581, Bytes{0x61, 0x00}));
  EXPECT_EQ(reader.drops().filtered, 1U);
  EXPECT_EQ(reader.drops().extended, 2U);
  EXPECT_EQ(reader.drops().malformed, 2U);
  ::close(fds[1]);
}

TEST(CanErrorFrames, DecodedAsTheKernelSendsThem) {
  struct Case {
    std::uint32_t error_class;
    std::uint8_t controller;  // data[1]
    bool ErrorReport::*flag;
    bool fault;
  };
  for (const Case& c : {
           Case{CAN_ERR_BUSOFF, 0, &ErrorReport::bus_off, true},
           Case{CAN_ERR_ACK, 0, &ErrorReport::no_ack, true},
           Case{CAN_ERR_TX_TIMEOUT, 0, &ErrorReport::tx_timeout, true},
           Case{CAN_ERR_CRTL, CAN_ERR_CRTL_RX_PASSIVE, &ErrorReport::error_passive, true},
           Case{CAN_ERR_CRTL, CAN_ERR_CRTL_TX_PASSIVE, &ErrorReport::error_passive, true},
           Case{CAN_ERR_CRTL, CAN_ERR_CRTL_TX_WARNING, &ErrorReport::error_warning, false},
           Case{CAN_ERR_CRTL, CAN_ERR_CRTL_RX_OVERFLOW, &ErrorReport::rx_overflow, false},
           Case{CAN_ERR_CRTL, CAN_ERR_CRTL_ACTIVE, &ErrorReport::back_to_active, false},
           Case{CAN_ERR_RESTARTED, 0, &ErrorReport::restarted, false},
           Case{CAN_ERR_PROT, 0, &ErrorReport::protocol_violation, false},
           Case{CAN_ERR_LOSTARB, 0, &ErrorReport::lost_arbitration, false},
           Case{CAN_ERR_TRX, 0, &ErrorReport::transceiver, false},
       }) {
    std::array<std::uint8_t, kMaxData> data{};
    data[1] = c.controller;
    const ErrorReport r = decode_error_frame(c.error_class, data);
    EXPECT_TRUE(r.*(c.flag)) << std::hex << c.error_class << " " << int{c.controller};
    EXPECT_EQ(r.is_fault(), c.fault) << r.describe();
    // What a simulator sends for it decodes to the same report.
    const auto [id, bytes] = encode_error_frame(r);
    EXPECT_EQ(decode_error_frame(id & CAN_ERR_MASK, bytes), r) << r.describe();
  }
  std::array<std::uint8_t, kMaxData> counters{};
  counters[6] = 130;
  counters[7] = 7;
  const ErrorReport r = decode_error_frame(CAN_ERR_CNT, counters);
  EXPECT_EQ(r.tx_errors, 130);
  EXPECT_EQ(r.rx_errors, 7);
}

TEST(CanErrorFrames, ReachTheReaderOverTheSamePath) {
  auto pair = CanSocket::pair();
  ASSERT_TRUE(pair);
  ErrorReport bus_off;
  bus_off.bus_off = true;
  ASSERT_EQ(pair.value().second.write_error(bus_off), 0);
  const Received r = read_one(pair.value().first);
  ASSERT_EQ(r.kind, Received::Kind::Error);
  EXPECT_TRUE(r.error.bus_off);
  EXPECT_EQ(r.error.describe(), "bus-off");
}

TEST(CanUnixEndpoint, ConnectsToAListeningSimulator) {
  const std::string path =
      (std::filesystem::temp_directory_path() / ("liftd-can-" + std::to_string(::getpid())))
          .string();
  auto listener = listen_unix(path);
  ASSERT_TRUE(listener) << listener.error().what;
  auto client = CanSocket::open("unix:" + path, {0x581});
  ASSERT_TRUE(client) << client.error().what << ": " << std::strerror(client.error().code);
  pollfd p{listener.value(), POLLIN, 0};
  ASSERT_EQ(::poll(&p, 1, 1000), 1);
  CanSocket server =
      CanSocket::adopt(::accept4(listener.value(), nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC));
  ASSERT_EQ(server.write(make_frame(0x581, Bytes{0x61, 0x02})), 0);
  const Received r = read_one(client.value());
  ASSERT_EQ(r.kind, Received::Kind::Frame);
  EXPECT_EQ(r.frame.id, 0x581U);
  ::close(listener.value());
  ::unlink(path.c_str());
}

TEST(CanUnixEndpoint, SaysWhatFailed) {
  auto missing = CanSocket::open("unix:/nonexistent/liftd-can.sock", {});
  ASSERT_FALSE(missing);
  EXPECT_EQ(missing.error().code, ENOENT);
  EXPECT_EQ(missing.error().what, "connect to /nonexistent/liftd-can.sock");
}

TEST(CanUnixEndpoint, AnOpenerReopensIntoOneEndpointThatKeepsItsFilterAndCounters) {
  // What the CAN runner does on its real-time thread: one endpoint built up front, descriptors
  // from an opener prepared up front attached and closed again and again.
  const std::string path =
      (std::filesystem::temp_directory_path() / ("liftd-can-opener-" + std::to_string(::getpid())))
          .string();
  const std::vector<std::uint32_t> ids{0x581};
  const EndpointOpener opener("unix:" + path, ids);
  EXPECT_EQ(opener.endpoint(), "unix:" + path);
  const auto absent = opener.open();
  ASSERT_FALSE(absent);
  EXPECT_EQ(absent.error().code, ENOENT);
  EXPECT_EQ(absent.error().step, OpenStep::UnixConnect);
  EXPECT_EQ(opener.describe(absent.error()), "connect to " + path);

  auto listener = listen_unix(path);
  ASSERT_TRUE(listener) << listener.error().what;
  CanSocket client = CanSocket::unattached(ids);
  EXPECT_FALSE(client.is_open());
  for (int round = 1; round <= 2; ++round) {
    const auto fd = opener.open();
    ASSERT_TRUE(fd) << opener.describe(fd.error());
    client.attach(fd.value());
    ASSERT_TRUE(client.is_open());
    pollfd p{listener.value(), POLLIN, 0};
    ASSERT_EQ(::poll(&p, 1, 1000), 1);
    CanSocket server = CanSocket::adopt(
        ::accept4(listener.value(), nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC));
    ASSERT_EQ(server.write(make_frame(0x551, Bytes{0x01})), 0);  // filtered out
    ASSERT_EQ(server.write(make_frame(0x581, Bytes{0x61, static_cast<std::uint8_t>(round)})), 0);
    const Received r = read_one(client);
    ASSERT_EQ(r.kind, Received::Kind::Frame);
    EXPECT_EQ(r.frame, make_frame(0x581, Bytes{0x61, static_cast<std::uint8_t>(round)}));
    EXPECT_EQ(client.drops().filtered, static_cast<std::uint64_t>(round)) << "over both sockets";
    client.close();
    EXPECT_FALSE(client.is_open());
    EXPECT_EQ(client.fd(), -1);
  }
  ::close(listener.value());
  ::unlink(path.c_str());
  const auto gone = opener.open();
  ASSERT_FALSE(gone);
  EXPECT_EQ(gone.error().code, ENOENT);
}

// The same endpoint over the kernel's SocketCAN is tested in real_socket_test.cpp (label "vcan",
// run by tools/uml/can-stage.sh inside user-mode Linux). What a kernel without AF_CAN says:
TEST(CanRealSocket, WithoutAfCanOpeningSaysSo) {
  if (kernel_has_can()) GTEST_SKIP() << "this kernel has AF_CAN";
  auto s = CanSocket::open("can0", {});
  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().code, EAFNOSUPPORT);
  EXPECT_EQ(s.error().what, "socket(PF_CAN, SOCK_RAW, CAN_RAW)");
}

}  // namespace
}  // namespace liftd::can

namespace liftd::can {
namespace {

// rtnetlink answers for any interface; "lo" is on every Linux machine (no CAN bitrate).
TEST(CanInterfaceInfo, ReadsStateFromTheKernel) {
  const InterfaceInfo lo = query_interface("lo");
  ASSERT_TRUE(lo.found);
  EXPECT_TRUE(lo.up) << lo.error;
  EXPECT_FALSE(lo.bitrate.has_value());
  const InterfaceInfo missing = query_interface("nosuchcan9");
  EXPECT_FALSE(missing.found);
  EXPECT_EQ(missing.error, "no network interface \"nosuchcan9\"");
}

}  // namespace
}  // namespace liftd::can
