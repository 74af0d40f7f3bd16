// What sysfs says about a serial device, read from trees laid out as the kernel lays them out for
// a USB serial adapter (ftdi_sio: the port device on the usb-serial bus holds latency_timer), a
// 16550-type UART (serial8250: the tty holds rx_trig_bytes) and a pseudo-terminal (not in
// /sys/class/tty by that name).
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "io/serial_device.hpp"

namespace liftd::io {
namespace {

namespace fs = std::filesystem;

class SerialDeviceTest : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = fs::temp_directory_path() /
            ("liftd-sysfs-" + std::to_string(::getpid()) + "-" +
             ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(root_);
    fs::create_directories(root_ / "dev");
  }
  void TearDown() override { fs::remove_all(root_); }

  /// /sys/class/tty/NAME -> devices/.../NAME, its `device` the port `port` whose driver and bus
  /// are `driver` and `bus`; the device node dev/NAME.
  fs::path add_tty(const std::string& name, const std::string& port, const std::string& driver,
                   const std::string& bus) {
    const fs::path sys = root_ / "sys";
    const fs::path port_dir = sys / "devices" / "platform" / port;
    const fs::path tty_dir = port_dir / "tty" / name;
    fs::create_directories(tty_dir);
    fs::create_directories(sys / "bus" / bus / "drivers" / driver);
    fs::create_directory_symlink(sys / "bus" / bus / "drivers" / driver, port_dir / "driver");
    fs::create_directory_symlink(sys / "bus" / bus, port_dir / "subsystem");
    fs::create_directory_symlink(port_dir, tty_dir / "device");
    fs::create_directories(sys / "class" / "tty");
    fs::create_directory_symlink(tty_dir, sys / "class" / "tty" / name);
    std::ofstream(root_ / "dev" / name) << "";
    return port_dir;
  }
  fs::path sys() const { return root_ / "sys"; }
  fs::path dev(const std::string& name) const { return root_ / "dev" / name; }

  fs::path root_;
};

TEST_F(SerialDeviceTest, AnFtdiAdapterShowsItsLatencyTimerAndItIsSetToOneMillisecond) {
  const fs::path port = add_tty("ttyUSB0", "ttyUSB0", "ftdi_sio", "usb-serial");
  std::ofstream(port / "latency_timer") << "16\n";
  const SerialDeviceInfo info = query_serial_device(dev("ttyUSB0"), sys());
  EXPECT_EQ(info.tty, "ttyUSB0");
  EXPECT_EQ(info.driver, "ftdi_sio");
  EXPECT_TRUE(info.usb);
  ASSERT_EQ(info.latency_timer_ms, 16);
  EXPECT_FALSE(info.rx_trig_bytes.has_value());
  EXPECT_EQ(describe(info), dev("ttyUSB0").string() +
                                " (ttyUSB0, driver ftdi_sio, USB adapter, latency timer 16 ms)");

  EXPECT_EQ(set_latency_timer(info, kLatencyTimerMs), "");
  EXPECT_EQ(query_serial_device(dev("ttyUSB0"), sys()).latency_timer_ms, 1);
}

TEST_F(SerialDeviceTest, ALinkByIdNamesTheTtyItPointsTo) {
  const fs::path port = add_tty("ttyUSB1", "ttyUSB1", "cp210x", "usb-serial");
  fs::create_symlink(dev("ttyUSB1"), root_ / "dev" / "usb-Silicon_Labs_CP2102-if00-port0");
  const SerialDeviceInfo info =
      query_serial_device((root_ / "dev" / "usb-Silicon_Labs_CP2102-if00-port0").string(), sys());
  EXPECT_EQ(info.tty, "ttyUSB1");
  EXPECT_EQ(info.driver, "cp210x");
  EXPECT_TRUE(info.usb);
  EXPECT_FALSE(info.latency_timer_ms.has_value()) << "the CP210x has no latency timer file";
  EXPECT_EQ(set_latency_timer(info, 1), "the device has no latency timer");
  (void)port;
}

TEST_F(SerialDeviceTest, A16550UartShowsItsReceiveTriggerLevel) {
  add_tty("ttyS1", "serial8250", "serial8250", "platform");
  std::ofstream(root_ / "sys" / "class" / "tty" / "ttyS1" / "rx_trig_bytes") << "8\n";
  const SerialDeviceInfo info = query_serial_device(dev("ttyS1"), sys());
  EXPECT_EQ(info.driver, "serial8250");
  EXPECT_FALSE(info.usb);
  EXPECT_EQ(info.rx_trig_bytes, 8);
  EXPECT_EQ(describe(info),
            dev("ttyS1").string() + " (ttyS1, driver serial8250, receive FIFO trigger 8 bytes)");
}

TEST_F(SerialDeviceTest, APseudoTerminalIsNoTtyOfSysfs) {
  fs::create_directories(root_ / "sys" / "class" / "tty");
  std::ofstream(root_ / "dev" / "7") << "";
  const SerialDeviceInfo info = query_serial_device(dev("7"), sys());
  EXPECT_EQ(info.tty, "");
  EXPECT_EQ(info.driver, "");
  EXPECT_NE(describe(info).find("a pseudo-terminal?"), std::string::npos);
}

TEST_F(SerialDeviceTest, TheAdviceSaysWhatToRunAndTheUdevRuleThatKeepsIt) {
  const fs::path port = add_tty("ttyUSB2", "ttyUSB2", "ftdi_sio", "usb-serial");
  std::ofstream(port / "latency_timer") << "16\n";
  const SerialDeviceInfo info = query_serial_device(dev("ttyUSB2"), sys());
  // The path through /sys/class/tty, which every kernel has for a tty.
  EXPECT_EQ(latency_timer_advice(info, 1),
            "run as root: echo 1 > " +
                (sys() / "class" / "tty" / "ttyUSB2" / "device" / "latency_timer").string() +
                "; to keep it across reconnects, a udev rule: ACTION==\"add\", "
                "SUBSYSTEM==\"usb-serial\", DRIVER==\"ftdi_sio\", ATTR{latency_timer}=\"1\"");
}

}  // namespace
}  // namespace liftd::io
