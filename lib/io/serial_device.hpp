// What the kernel says about the serial device a drive link runs on (sysfs): its tty name, its
// driver, whether it is a USB serial adapter, and the settings that decide when received bytes
// reach the cycle: a USB adapter's latency timer (FTDI chips hold received bytes up to 16 ms by
// default before they send them to the host: longer than a 15 ms DCP cycle, DCP 7.2) and a
// 16550-type UART's receive FIFO trigger level (rx_trig_bytes of the 8250 driver). Read at start,
// off the real-time thread; the latency timer is set to 1 ms where the system lets liftd.
#pragma once

#include <filesystem>
#include <optional>
#include <string>

namespace liftd::io {

struct SerialDeviceInfo {
  std::string device;  ///< as configured (/dev/ttyUSB0, a /dev/serial/by-id link, a pty)
  std::string tty;     ///< the kernel's name of the tty (ttyUSB0); "" when sysfs has no such tty
  std::string driver;  ///< the tty's driver (ftdi_sio, cp210x, serial8250, ...); "" unknown
  bool usb = false;    ///< a USB serial adapter (its port on the usb-serial bus)
  /// The adapter's latency timer in ms, where its driver has one (ftdi_sio), and its sysfs file.
  std::optional<int> latency_timer_ms;
  std::filesystem::path latency_timer_path;
  /// The UART's receive FIFO trigger level in bytes, where the driver has one (8250), and its file.
  std::optional<int> rx_trig_bytes;
  std::filesystem::path rx_trig_bytes_path;
};

/// Reads what sysfs (`sys`, normally /sys) says about `device`. Never fails: what cannot be read
/// stays empty.
SerialDeviceInfo query_serial_device(const std::string& device,
                                     const std::filesystem::path& sys = "/sys");

/// The latency timer liftd sets on a USB serial adapter: 1 ms, the smallest the FTDI chips take,
/// so that a 6-byte reply reaches the cycle within its DCP 7.2 window.
inline constexpr int kLatencyTimerMs = 1;

/// Writes `ms` to the adapter's latency timer: "" when done, else why not (the errno's text).
std::string set_latency_timer(const SerialDeviceInfo& info, int ms);

/// One line naming the device and its settings, for the journal:
/// "/dev/ttyUSB0 (ttyUSB0, driver ftdi_sio, USB adapter, latency timer 1 ms)".
std::string describe(const SerialDeviceInfo& info);

/// What a technician runs to set the latency timer by hand, and a udev rule that keeps it set:
/// the text liftd journals when it may not write the file itself.
std::string latency_timer_advice(const SerialDeviceInfo& info, int ms);

}  // namespace liftd::io
