// SerialPort and PtyPair over real pseudo-terminals: settings, errors, deadline reads,
// flushing and device-loss detection.
#include "io/serial_port.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <poll.h>
#include <sys/epoll.h>

#include <array>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <future>
#include <thread>
#include <vector>

#include "io/pty.hpp"

namespace liftd::io {
namespace {

using std::chrono::milliseconds;

PtyPair make_pty() {
  auto pty = PtyPair::create();
  if (!pty.ok()) ADD_FAILURE() << pty.error().message();
  return std::move(pty).value();
}

TEST(IoSerialPort, OpensAPtySlaveAtEveryRequiredRate) {
  // Legend: the rates the brief names (DCP 7.1 38400; USS A: 9600..187500, 187500 needs BOTHER),
  // each with the framing its protocol uses.
  struct Case {
    std::uint32_t baud;
    Parity parity;
  };
  const Case cases[] = {{9600, Parity::None},  {19200, Parity::Even},  {38400, Parity::None},
                        {57600, Parity::None}, {115200, Parity::None}, {187500, Parity::Even}};
  PtyPair pty = make_pty();
  for (const auto& c : cases) {
    SerialSettings s;
    s.baud = c.baud;
    s.parity = c.parity;
    auto port = SerialPort::open(pty.slave_path(), s);
    ASSERT_TRUE(port.ok()) << c.baud << ": " << port.error().message();
    EXPECT_TRUE(port.value().is_open());
  }
}

TEST(IoSerialPort, MissingDeviceErrorNamesDeviceCallAndErrno) {
  auto port = SerialPort::open("/dev/liftd-no-such-tty", SerialSettings{});
  ASSERT_FALSE(port.ok());
  EXPECT_EQ(port.error().device, "/dev/liftd-no-such-tty");
  EXPECT_EQ(port.error().call, "open");
  EXPECT_EQ(port.error().error_number, ENOENT);
  EXPECT_EQ(port.error().message(), "/dev/liftd-no-such-tty: open: No such file or directory");
}

TEST(IoSerialPort, NotATtyIsRefusedAtTermiosSetup) {
  auto port = SerialPort::open("/dev/null", SerialSettings{});
  ASSERT_FALSE(port.ok());
  EXPECT_EQ(port.error().error_number, ENOTTY);
  EXPECT_NE(port.error().message().find("/dev/null: TIOCEXCL"), std::string::npos);
}

TEST(IoSerialPort, RejectsImpossibleFraming) {
  PtyPair pty = make_pty();
  SerialSettings s;
  s.data_bits = 9;
  auto port = SerialPort::open(pty.slave_path(), s);
  ASSERT_FALSE(port.ok());
  EXPECT_EQ(port.error().call, "settings");
  EXPECT_EQ(port.error().error_number, EINVAL);
}

TEST(IoSerialPort, SecondOpenIsRefusedWhileExclusive) {
  PtyPair pty = make_pty();
  auto first = SerialPort::open(pty.slave_path(), SerialSettings{});
  ASSERT_TRUE(first.ok());
  if (geteuid() != 0) {
    auto second = SerialPort::open(pty.slave_path(), SerialSettings{});
    ASSERT_FALSE(second.ok());
    EXPECT_EQ(second.error().error_number, EBUSY);
    return;
  }
  // Root (CAP_SYS_ADMIN) may ignore TIOCEXCL, so try the second open as an ordinary user.
  ASSERT_EQ(chmod(pty.slave_path().c_str(), 0666), 0);
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    constexpr uid_t kNobody = 65534;
    if (setgid(kNobody) != 0 || setuid(kNobody) != 0) _exit(100);
    auto second = SerialPort::open(pty.slave_path(), SerialSettings{});
    _exit(second.ok() ? 0 : second.error().error_number);
  }
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), EBUSY);
}

TEST(IoSerialPort, Rs485AutoCarriesOnAndSaysWhyRequiredFails) {
  PtyPair pty = make_pty();
  SerialSettings s;
  s.rs485 = Rs485Mode::Auto;
  {
    auto port = SerialPort::open(pty.slave_path(), s);
    ASSERT_TRUE(port.ok()) << port.error().message();
    EXPECT_FALSE(port.value().features().rs485_enabled);
    EXPECT_NE(port.value().features().rs485_errno, 0);  // a pty has no RS485 mode
    EXPECT_FALSE(port.value().features().low_latency_enabled);
  }
  s.rs485 = Rs485Mode::Required;
  auto port = SerialPort::open(pty.slave_path(), s);
  ASSERT_FALSE(port.ok());
  EXPECT_EQ(port.error().call, "TIOCSRS485");
  EXPECT_NE(port.error().message().find("rs485 mode required"), std::string::npos);
  s.rs485 = Rs485Mode::Off;
  auto off = SerialPort::open(pty.slave_path(), s);
  ASSERT_TRUE(off.ok());
  EXPECT_EQ(off.value().features().rs485_errno, 0);
}

TEST(IoSerialPort, FrameGoesThroughBothWaysUnchanged) {
  // Raw mode: CR, LF, XON/XOFF, DEL and 0xFF must pass untouched.
  PtyPair pty = make_pty();
  auto port = SerialPort::open(pty.slave_path(), SerialSettings{});
  ASSERT_TRUE(port.ok());
  SerialPort master = pty.take_master();
  const std::array<std::uint8_t, 6> frame{0x0D, 0x0A, 0x11, 0x13, 0x7F, 0xFF};
  ASSERT_EQ(port.value().write_frame(frame).status, IoStatus::Ok);
  std::array<std::uint8_t, 6> got{};
  const IoResult r = master.read_until(got, mono_now() + milliseconds(500));
  ASSERT_EQ(r.status, IoStatus::Ok);
  EXPECT_EQ(got, frame);
  ASSERT_EQ(master.write_frame(frame).status, IoStatus::Ok);
  got = {};
  ASSERT_EQ(port.value().read_until(got, mono_now() + milliseconds(500)).status, IoStatus::Ok);
  EXPECT_EQ(got, frame);
}

TEST(IoSerialPort, ReadUntilTimesOutWithThePartialCount) {
  PtyPair pty = make_pty();
  auto port = SerialPort::open(pty.slave_path(), SerialSettings{});
  ASSERT_TRUE(port.ok());
  const std::array<std::uint8_t, 2> two{0x61, 0x80};
  ASSERT_EQ(::write(pty.master_fd(), two.data(), two.size()), 2);
  std::array<std::uint8_t, 6> buf{};
  const MonoTime start = mono_now();
  const IoResult r = port.value().read_until(buf, start + milliseconds(30));
  const MonoTime took = mono_now() - start;
  EXPECT_EQ(r.status, IoStatus::Timeout);
  EXPECT_EQ(r.bytes, 2U);
  EXPECT_EQ(buf[0], 0x61);
  EXPECT_GE(took, milliseconds(30));  // it waited for the deadline, not less
  EXPECT_LT(took, milliseconds(1000));
}

TEST(IoSerialPort, ReadUntilCollectsBytesArrivingInPieces) {
  PtyPair pty = make_pty();
  auto port = SerialPort::open(pty.slave_path(), SerialSettings{});
  ASSERT_TRUE(port.ok());
  const int master = pty.master_fd();
  std::thread sender([master] {
    for (std::uint8_t b = 1; b <= 6; ++b) {
      (void)!::write(master, &b, 1);
      std::this_thread::sleep_for(milliseconds(2));
    }
  });
  std::array<std::uint8_t, 6> buf{};
  const IoResult r = port.value().read_until(buf, mono_now() + milliseconds(2000));
  sender.join();
  EXPECT_EQ(r.status, IoStatus::Ok);
  EXPECT_EQ(buf, (std::array<std::uint8_t, 6>{1, 2, 3, 4, 5, 6}));
}

TEST(IoSerialPort, FlushInputDropsStrayBytes) {
  PtyPair pty = make_pty();
  auto port = SerialPort::open(pty.slave_path(), SerialSettings{});
  ASSERT_TRUE(port.ok());
  const std::array<std::uint8_t, 3> junk{1, 2, 3};
  ASSERT_EQ(::write(pty.master_fd(), junk.data(), junk.size()), 3);
  std::this_thread::sleep_for(milliseconds(20));  // let the pty deliver them
  EXPECT_EQ(port.value().flush_input().status, IoStatus::Ok);
  std::array<std::uint8_t, 1> buf{};
  EXPECT_EQ(port.value().read_until(buf, mono_now() + milliseconds(20)).status, IoStatus::Timeout);
}

TEST(IoSerialPort, HangUpIsReportedAsDeviceLostEverywhere) {
  // Legend: after the far end closes, each operation must answer DeviceLost, never Timeout.
  PtyPair pty = make_pty();
  auto port = SerialPort::open(pty.slave_path(), SerialSettings{});
  ASSERT_TRUE(port.ok());
  pty.close();
  std::array<std::uint8_t, 6> buf{};
  EXPECT_EQ(port.value().read_until(buf, mono_now() + milliseconds(200)).status,
            IoStatus::DeviceLost);
  EXPECT_EQ(port.value().flush_input().status, IoStatus::DeviceLost);
  EXPECT_EQ(port.value().wait_readable(mono_now() + milliseconds(200)).status,
            IoStatus::DeviceLost);
  EXPECT_EQ(port.value().write_frame(buf).status, IoStatus::DeviceLost);
  // The real-time side's calls see it too: TIOCINQ on a hung-up tty answers EIO.
  EXPECT_EQ(port.value().input_queued().status, IoStatus::DeviceLost);
  EXPECT_EQ(port.value().read_queued(buf).status, IoStatus::DeviceLost);
  EXPECT_EQ(port.value().wait_queued(mono_now() + milliseconds(200), milliseconds(1)).status,
            IoStatus::DeviceLost);
  EXPECT_EQ(
      port.value().read_queued_until(buf, mono_now() + milliseconds(200), milliseconds(1)).status,
      IoStatus::DeviceLost);
  EXPECT_EQ(port.value().drain_queued().status, IoStatus::DeviceLost);
  EXPECT_EQ(port.value().flush_queued().status, IoStatus::DeviceLost);
}

// The reads of the real-time threads: they take only what the line discipline
// already holds and wait with their own sleeps, never in read(2) or poll(2) on an empty tty
// (which wait for the tty's normal-priority flip-buffer worker). A pty delivers through that
// worker too, so each test first waits (up to 2 s, not a timing assumption) for the bytes.

/// Waits until the port's line discipline holds `bytes` bytes (or 2 s passed).
bool await_queued(SerialPort& port, std::size_t bytes) {
  const MonoTime end = mono_now() + milliseconds(2000);
  while (mono_now() < end) {
    const IoResult q = port.input_queued();
    if (q.status != IoStatus::Ok) return false;
    if (q.bytes >= bytes) return true;
    (void)port.wait_queued(end, milliseconds(1));
    std::this_thread::sleep_for(milliseconds(1));
  }
  return false;
}

TEST(IoSerialPort, QueuedReadTakesOnlyWhatTheLineDisciplineHolds) {
  PtyPair pty = make_pty();
  auto port = SerialPort::open(pty.slave_path(), SerialSettings{});
  ASSERT_TRUE(port.ok());
  std::array<std::uint8_t, 6> buf{};
  // Nothing there: an empty answer, not a read(2) of an empty tty.
  const IoResult empty = port.value().read_queued(buf);
  EXPECT_EQ(empty.status, IoStatus::Ok);
  EXPECT_EQ(empty.bytes, 0U);
  EXPECT_EQ(port.value().input_queued().bytes, 0U);
  const std::array<std::uint8_t, 4> sent{7, 8, 9, 10};
  ASSERT_EQ(::write(pty.master_fd(), sent.data(), sent.size()), 4);
  ASSERT_TRUE(await_queued(port.value(), 4));
  EXPECT_EQ(port.value().input_queued().bytes, 4U);
  const IoResult got = port.value().read_queued(buf);
  EXPECT_EQ(got.status, IoStatus::Ok);
  ASSERT_EQ(got.bytes, 4U);
  EXPECT_EQ(buf[0], 7);
  EXPECT_EQ(buf[3], 10);
  EXPECT_EQ(port.value().input_queued().bytes, 0U);
}

TEST(IoSerialPort, EdgeTriggeredWatchWakesOncePerArrivalAndNeverForAnEmptyTty) {
  PtyPair pty = make_pty();
  auto port = SerialPort::open(pty.slave_path(), SerialSettings{});
  ASSERT_TRUE(port.ok());
  const int epoll_fd = ::epoll_create1(EPOLL_CLOEXEC);
  ASSERT_GE(epoll_fd, 0);
  ASSERT_TRUE(port.value().watch_input(epoll_fd));
  epoll_event ready{};
  EXPECT_EQ(::epoll_wait(epoll_fd, &ready, 1, 0), 0) << "nothing arrived yet";
  const std::array<std::uint8_t, 3> sent{1, 2, 3};
  ASSERT_EQ(::write(pty.master_fd(), sent.data(), sent.size()), 3);
  ASSERT_EQ(::epoll_wait(epoll_fd, &ready, 1, 5000), 1);
  EXPECT_EQ(ready.data.fd, port.value().fd());
  EXPECT_TRUE((ready.events & EPOLLIN) != 0);
  ASSERT_TRUE(await_queued(port.value(), 3));
  std::array<std::uint8_t, 8> buf{};
  EXPECT_EQ(port.value().read_queued(buf).bytes, 3U);
  // Drained, and no new bytes: an edge-triggered watch does not report the empty tty again.
  EXPECT_EQ(::epoll_wait(epoll_fd, &ready, 1, 20), 0);
  // A second watch of the same port on the same epoll is refused, with errno.
  EXPECT_FALSE(port.value().watch_input(epoll_fd));
  EXPECT_EQ(errno, EEXIST);
  ::close(epoll_fd);
}

TEST(IoSerialPort, QueuedReadUntilCollectsAReplyAsItArrives) {
  PtyPair pty = make_pty();
  auto port = SerialPort::open(pty.slave_path(), SerialSettings{});
  ASSERT_TRUE(port.ok());
  const int master = pty.master_fd();
  std::thread sender([master] {
    for (std::uint8_t b = 1; b <= 6; ++b) {
      (void)!::write(master, &b, 1);
      std::this_thread::sleep_for(milliseconds(2));
    }
  });
  std::array<std::uint8_t, 6> buf{};
  const MonoTime asked = mono_now();
  MonoTime complete_by{};
  const IoResult r = port.value().read_queued_until(buf, asked + milliseconds(2000),
                                                    milliseconds(1), &complete_by);
  const MonoTime returned = mono_now();
  sender.join();
  EXPECT_EQ(r.status, IoStatus::Ok);
  EXPECT_EQ(r.bytes, 6U);
  // The look that completed it started after the call and before it returned.
  EXPECT_GE(complete_by, asked);
  EXPECT_LE(complete_by, returned);
  EXPECT_EQ(buf, (std::array<std::uint8_t, 6>{1, 2, 3, 4, 5, 6}));
}

TEST(IoSerialPort, AReplyOnlySeenAfterItsDeadlineIsATimeoutWithItsBytes) {
  // Legend: DCP 7.3 counts a reply not complete by the deadline as missing. A look after the
  // deadline may still find it complete (the caller counts a late reply) or short (partial).
  PtyPair pty = make_pty();
  auto port = SerialPort::open(pty.slave_path(), SerialSettings{});
  ASSERT_TRUE(port.ok());
  const std::array<std::uint8_t, 6> reply{1, 2, 3, 4, 5, 6};
  std::array<std::uint8_t, 6> buf{};
  ASSERT_EQ(::write(pty.master_fd(), reply.data(), 3), 3);
  ASSERT_TRUE(await_queued(port.value(), 3));
  const IoResult partial =
      port.value().read_queued_until(buf, mono_now() - milliseconds(1), milliseconds(1));
  EXPECT_EQ(partial.status, IoStatus::Timeout);
  EXPECT_EQ(partial.bytes, 3U);
  ASSERT_EQ(::write(pty.master_fd(), reply.data(), reply.size()), 6);
  ASSERT_TRUE(await_queued(port.value(), 6));
  const IoResult late =
      port.value().read_queued_until(buf, mono_now() - milliseconds(1), milliseconds(1));
  EXPECT_EQ(late.status, IoStatus::Timeout);
  EXPECT_EQ(late.bytes, 6U);
  // Nothing arrives: a timeout at the deadline, no bytes.
  const IoResult none =
      port.value().read_queued_until(buf, mono_now() + milliseconds(5), milliseconds(1));
  EXPECT_EQ(none.status, IoStatus::Timeout);
  EXPECT_EQ(none.bytes, 0U);
}

// A reply's bytes cannot arrive faster than one a character time: looking again before the
// bytes still missing could all be there only costs a wake-up (issue #43: the cycle woke about a
// thousand times a second). With nothing arriving, a 6-byte reply at a 1 ms character time is
// looked for at 0, 6, 12 and 18 ms and at the deadline (20 ms): five looks, never more (a
// thread woken late looks less often), where one a character time made 21.
TEST(IoSerialPort, QueuedReadUntilLooksWhenTheMissingBytesCouldBeThere) {
  PtyPair pty = make_pty();
  auto port = SerialPort::open(pty.slave_path(), SerialSettings{});
  ASSERT_TRUE(port.ok());
  std::array<std::uint8_t, 6> buf{};
  const std::uint64_t before = port.value().looks();
  const IoResult none =
      port.value().read_queued_until(buf, mono_now() + milliseconds(20), milliseconds(1));
  EXPECT_EQ(none.status, IoStatus::Timeout);
  const std::uint64_t looks = port.value().looks() - before;
  EXPECT_GE(looks, 2U);  // the first look and the one at the deadline
  EXPECT_LE(looks, 5U);
  // Three of six bytes there: the next look is three character times later, and the reply
  // completed by then is taken whole.
  const std::array<std::uint8_t, 6> reply{1, 2, 3, 4, 5, 6};
  ASSERT_EQ(::write(pty.master_fd(), reply.data(), 3), 3);
  ASSERT_TRUE(await_queued(port.value(), 3));
  const int master = pty.master_fd();
  std::thread rest([master, &reply] { (void)!::write(master, reply.data() + 3, 3); });
  const IoResult whole =
      port.value().read_queued_until(buf, mono_now() + milliseconds(2000), milliseconds(1));
  rest.join();
  EXPECT_EQ(whole.status, IoStatus::Ok);
  EXPECT_EQ(buf, reply);
}

TEST(IoSerialPort, QueuedReadUntilLooksFirstAtTheTimeItIsGiven) {
  PtyPair pty = make_pty();
  auto port = SerialPort::open(pty.slave_path(), SerialSettings{});
  ASSERT_TRUE(port.ok());
  const std::array<std::uint8_t, 6> reply{1, 2, 3, 4, 5, 6};
  ASSERT_EQ(::write(pty.master_fd(), reply.data(), reply.size()), 6);
  ASSERT_TRUE(await_queued(port.value(), reply.size()));
  // The reply is there already; the one look is no sooner than the first look asked for.
  std::array<std::uint8_t, 6> buf{};
  const MonoTime first_look = mono_now() + milliseconds(5);
  MonoTime complete_by{};
  const std::uint64_t before = port.value().looks();
  const IoResult got = port.value().read_queued_until(buf, first_look + milliseconds(2000),
                                                      milliseconds(1), &complete_by, first_look);
  EXPECT_EQ(got.status, IoStatus::Ok);
  EXPECT_EQ(buf, reply);
  EXPECT_EQ(port.value().looks() - before, 1U);
  EXPECT_GE(complete_by, first_look);
  // A first look past the deadline is at the deadline: one look, too late for the reply.
  ASSERT_EQ(::write(pty.master_fd(), reply.data(), reply.size()), 6);
  ASSERT_TRUE(await_queued(port.value(), reply.size()));
  const MonoTime deadline = mono_now() + milliseconds(3);
  const IoResult late = port.value().read_queued_until(buf, deadline, milliseconds(1), &complete_by,
                                                       deadline + milliseconds(50));
  EXPECT_EQ(late.status, IoStatus::Timeout);
  EXPECT_LT(complete_by, deadline + milliseconds(50));
}

TEST(IoSerialPort, DrainQueuedReadsStrayBytesAwayAndCountsThem) {
  PtyPair pty = make_pty();
  auto port = SerialPort::open(pty.slave_path(), SerialSettings{});
  ASSERT_TRUE(port.ok());
  EXPECT_EQ(port.value().drain_queued().bytes, 0U);
  std::array<std::uint8_t, 100> junk{};
  junk.fill(0x55);
  ASSERT_EQ(::write(pty.master_fd(), junk.data(), junk.size()), 100);
  ASSERT_TRUE(await_queued(port.value(), junk.size()));
  const IoResult drained = port.value().drain_queued();
  EXPECT_EQ(drained.status, IoStatus::Ok);
  EXPECT_EQ(drained.bytes, 100U);  // more than one read's worth
  EXPECT_EQ(port.value().input_queued().bytes, 0U);
  // flush_queued (after a missing reply): TCFLSH, counting what the line discipline held.
  ASSERT_EQ(::write(pty.master_fd(), junk.data(), 5), 5);
  ASSERT_TRUE(await_queued(port.value(), 5));
  const IoResult flushed = port.value().flush_queued();
  EXPECT_EQ(flushed.status, IoStatus::Ok);
  EXPECT_EQ(flushed.bytes, 5U);
  EXPECT_EQ(port.value().input_queued().bytes, 0U);
}

TEST(IoSerialPort, CharacterTimeCountsStartDataParityAndStopBits) {
  // Legend: DCP 7.1 38400 8N1 = 10 bits; USS A 6.1 8E1 = 11 bits, at 38400 and 187500 baud.
  SerialSettings dcp;
  EXPECT_EQ(character_time(dcp).count(), 10LL * 1'000'000'000 / 38400);
  SerialSettings uss;
  uss.parity = Parity::Even;
  EXPECT_EQ(character_time(uss).count(), 11LL * 1'000'000'000 / 38400);
  uss.baud = 187500;
  EXPECT_EQ(character_time(uss).count(), 11LL * 1'000'000'000 / 187500);
}

TEST(IoSerialPort, DeviceLostErrnos) {
  for (int e : {EIO, ENODEV, ENXIO, EPIPE, ESHUTDOWN}) EXPECT_TRUE(is_device_lost_errno(e)) << e;
  for (int e : {EAGAIN, EINTR, EINVAL, EBADF}) EXPECT_FALSE(is_device_lost_errno(e)) << e;
  EXPECT_EQ(to_string(IoStatus::DeviceLost), "device-lost");
}

// A stalled line: the far end (the pty master) never reads, so the port's output backs up until
// writes would block. Closing the port must drop what is still queued instead of leaving it to
// drain (on a UART, close() waits up to the port's closing_wait, 30 s, for that).
TEST(IoSerialPort, CloseDiscardsOutputALineThatDoesNotDrainStillHolds) {
  PtyPair pty = make_pty();
  auto opened = SerialPort::open(pty.slave_path(), SerialSettings{});
  ASSERT_TRUE(opened.ok());
  SerialPort port = std::move(opened).value();
  const std::vector<std::uint8_t> chunk(512, 0x55);
  std::size_t written = 0;
  for (int i = 0; i < 100000; ++i) {
    const IoResult r = port.write_frame(chunk);
    written += r.bytes;
    if (r.status == IoStatus::WouldBlock) break;
    ASSERT_EQ(r.status, IoStatus::Ok);
  }
  ASSERT_GT(written, 8192U) << "the line never filled";
  port.close();
  // Now the master reads what reached it: without the flush, every byte written.
  std::size_t read = 0;
  std::array<std::uint8_t, 4096> buf{};
  for (;;) {
    pollfd pfd{pty.master_fd(), POLLIN, 0};
    if (::poll(&pfd, 1, 200) <= 0) break;
    const ssize_t n = ::read(pty.master_fd(), buf.data(), buf.size());
    if (n <= 0) break;
    read += static_cast<std::size_t>(n);
  }
  EXPECT_LT(read, written) << "close() left all " << written << " queued bytes to drain";
}

TEST(IoSerialPort, ACloseThatCannotFinishIsLeftBehindAfterTheLimit) {
  // The close stands in for a tty's close() waiting for output that never drains.
  std::promise<void> release;
  std::shared_future<void> released = release.get_future().share();
  auto closed = std::make_shared<std::atomic<int>>(-1);
  const auto stuck_close = [released, closed](int fd) {
    released.wait();
    closed->store(fd);
    return 0;
  };
  EXPECT_FALSE(close_port_fd(1234, milliseconds(20), stuck_close));
  EXPECT_EQ(closed->load(), -1);  // still waiting, on the helper thread
  release.set_value();
  while (closed->load() == -1) std::this_thread::sleep_for(milliseconds(1));
  EXPECT_EQ(closed->load(), 1234);  // the descriptor is closed in the end
  // A close that finishes is waited for.
  EXPECT_TRUE(
      close_port_fd(5678, milliseconds(60000), [closed](int fd) { return closed->store(fd), 0; }));
  EXPECT_EQ(closed->load(), 5678);
}

TEST(IoPty, SlavePathIsAPtsDeviceAndReleaseKeepsItOpen) {
  PtyPair pty = make_pty();
  EXPECT_EQ(pty.slave_path().rfind("/dev/pts/", 0), 0U);
  EXPECT_GE(pty.master_fd(), 0);
  SerialPort master = pty.take_master();
  EXPECT_EQ(pty.master_fd(), -1);
  const int fd = master.release();
  EXPECT_GE(fd, 0);
  EXPECT_FALSE(master.is_open());
  ::close(fd);
}

}  // namespace
}  // namespace liftd::io
