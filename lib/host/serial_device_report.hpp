// The serial device of a DCP or USS drive link as the lift reports it: journalled once at start
// with its driver and settings, a USB adapter's latency timer set to 1 ms where liftd may (or the
// command and udev rule that do it), and the same facts in `stats` (io::SerialDeviceInfo).
#pragma once

#include <filesystem>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

#include "io/serial_device.hpp"

namespace liftd::daemon {

/// Reads what the kernel says about `device` and journals it under `component`; a latency timer
/// above io::kLatencyTimerMs is set to it, or a warning says what to run. Returns the facts as
/// they are after that. Call before the link's thread starts (it reads and writes sysfs).
io::SerialDeviceInfo prepare_serial_device(const std::string& device, std::string_view component,
                                           const std::filesystem::path& sys = "/sys");

/// `stats.<kind>.serial`: the device, its tty and driver, whether it is a USB adapter, and its
/// latency timer and receive FIFO trigger level (null where it has none).
nlohmann::json serial_device_json(const io::SerialDeviceInfo& info);

}  // namespace liftd::daemon
