// The port keeper on its own, over real ptys, with a small reading loop as its real-time
// thread: the keeper opens the device, the port is lost when the far end hangs up, a vanished
// device is retried (reported once), and a new device under the same name is opened again.
#include "rt/port_keeper.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cerrno>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "io/pty.hpp"
#include "pty_device.hpp"

namespace liftd::rt {
namespace {

using std::chrono::milliseconds;
using testing::DeviceLink;
using testing::drain;
using testing::make_pty;
using testing::wait_for;

PortKeeperConfig keeper_config(const std::string& path) {
  PortKeeperConfig c;
  c.device_path = path;
  c.reopen_backoff_min = milliseconds(20);
  c.reopen_backoff_max = milliseconds(80);
  c.add_open_notes = [](const io::SerialPort&, std::string& text) { text += ", test note"; };
  return c;
}

// What the real-time thread does with its port here: adopts what the keeper offers, counts
// the bytes it reads and hands the port back when the device is lost.
class ReadingLoop {
 public:
  explicit ReadingLoop(PortKeeper& keeper) : keeper_(keeper) {}
  void operator()() noexcept {
    std::array<std::uint8_t, 1> byte{};
    while (!keeper_.stop_requested()) {
      keeper_.adopt_offered_port();
      io::SerialPort& port = keeper_.port();
      if (!port.is_open()) {
        std::this_thread::sleep_for(milliseconds(2));
        continue;
      }
      const io::IoResult got = port.read_until(byte, mono_now() + milliseconds(5));
      bytes_.fetch_add(got.bytes);
      if (got.status == io::IoStatus::DeviceLost) keeper_.hand_back_port();
    }
  }
  std::uint64_t bytes() const noexcept { return bytes_.load(); }

 private:
  PortKeeper& keeper_;
  std::atomic<std::uint64_t> bytes_{0};
};

RtThreadOptions normal_thread() {
  RtThreadOptions options;
  options.priority = 0;  // normal scheduling on purpose: reported as a ThreadStatus event
  options.lock_memory = false;
  return options;
}

void send_byte(const io::PtyPair& far_end) {
  const std::uint8_t byte = 0x5A;
  ASSERT_EQ(::write(far_end.master_fd(), &byte, 1), 1);
}

TEST(RtPortKeeper, OpensLosesAndReopensTheDevice) {
  DeviceLink name;
  auto first = std::make_unique<io::PtyPair>(make_pty());
  name.point_to(first->slave_path());
  PortKeeper keeper(keeper_config(name.path()));
  ReadingLoop loop(keeper);
  ASSERT_EQ(keeper.start(normal_thread(), [&loop] { loop(); }), 0);
  EXPECT_EQ(keeper.start(normal_thread(), [] {}), EBUSY);

  ASSERT_TRUE(wait_for([&] { return keeper.port_ready(); }, milliseconds(10000)));
  EXPECT_EQ(keeper.port_opens(), 1U);
  send_byte(*first);
  EXPECT_TRUE(wait_for([&] { return loop.bytes() == 1; }, milliseconds(10000)));
  auto events = drain(keeper);
  ASSERT_EQ(events.size(), 2U);
  EXPECT_EQ(events[0].kind, CycleEventKind::ThreadStatus);
  EXPECT_EQ(events[1].kind, CycleEventKind::PortOpened);
  const std::string opened = describe(events[1]);
  EXPECT_EQ(opened.rfind("serial port opened: " + name.path() + ", ", 0), 0U) << opened;
  EXPECT_NE(opened.find(", low latency"), std::string::npos) << opened;
  EXPECT_EQ(opened.substr(opened.size() - 11), ", test note") << opened;

  // The device goes: its name points nowhere (first, so that no retry can find the old pty's
  // number taken by another one), the far end hangs up, the port is lost and handed back.
  name.point_to(name.path() + ".absent");
  first.reset();
  ASSERT_TRUE(wait_for([&] { return keeper.port_losses() == 1; }, milliseconds(10000)));
  EXPECT_FALSE(keeper.port_ready());

  // Several retries fail while the name points nowhere: reported once, not per retry.
  std::this_thread::sleep_for(milliseconds(300));
  EXPECT_FALSE(keeper.port_ready());
  EXPECT_EQ(keeper.port_opens(), 1U);
  events = drain(keeper);
  ASSERT_EQ(events.size(), 1U);
  EXPECT_EQ(events[0].kind, CycleEventKind::PortOpenFailed);
  EXPECT_EQ(events[0].error_number, ENOENT);

  // A new device under the same name is opened and offered again.
  io::PtyPair second = make_pty();
  name.point_to(second.slave_path());
  ASSERT_TRUE(wait_for([&] { return keeper.port_ready(); }, milliseconds(10000)));
  EXPECT_EQ(keeper.port_opens(), 2U);
  send_byte(second);
  EXPECT_TRUE(wait_for([&] { return loop.bytes() == 2; }, milliseconds(10000)));
  events = drain(keeper);
  ASSERT_EQ(events.size(), 1U);
  EXPECT_EQ(events[0].kind, CycleEventKind::PortOpened);

  keeper.stop();
  EXPECT_FALSE(keeper.port_ready());
  EXPECT_FALSE(keeper.port().is_open());
  EXPECT_EQ(keeper.port_losses(), 1U);
}

}  // namespace
}  // namespace liftd::rt
