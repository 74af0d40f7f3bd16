#include "io/serial_device.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <system_error>

namespace liftd::io {
namespace {

namespace fs = std::filesystem;

/// The whole number a sysfs attribute holds ("16\n"), if it reads as one.
std::optional<int> read_number(const fs::path& path) {
  std::ifstream in(path);
  int value = 0;
  if (!(in >> value)) return std::nullopt;
  return value;
}

/// The last component of the target a sysfs link points to ("" when it is no link).
std::string link_name(const fs::path& link) {
  std::error_code ec;
  const fs::path target = fs::read_symlink(link, ec);
  return ec ? std::string() : target.filename().string();
}

}  // namespace

SerialDeviceInfo query_serial_device(const std::string& device, const fs::path& sys) {
  SerialDeviceInfo info;
  info.device = device;
  std::error_code ec;
  // A /dev/serial/by-id link names the tty it points to.
  const fs::path resolved = fs::canonical(device, ec);
  const std::string name = (ec ? fs::path(device) : resolved).filename().string();
  const fs::path tty = sys / "class" / "tty" / name;
  if (name.empty() || !fs::exists(tty, ec)) return info;
  info.tty = name;
  const fs::path parent = tty / "device";
  info.driver = link_name(parent / "driver");
  info.usb = link_name(parent / "subsystem") == "usb-serial";
  if (const auto ms = read_number(parent / "latency_timer")) {
    info.latency_timer_ms = ms;
    info.latency_timer_path = parent / "latency_timer";
  }
  if (const auto bytes = read_number(tty / "rx_trig_bytes")) {
    info.rx_trig_bytes = bytes;
    info.rx_trig_bytes_path = tty / "rx_trig_bytes";
  }
  return info;
}

std::string set_latency_timer(const SerialDeviceInfo& info, int ms) {
  if (info.latency_timer_path.empty()) return "the device has no latency timer";
  const int fd = ::open(info.latency_timer_path.c_str(), O_WRONLY | O_CLOEXEC);
  if (fd < 0) return std::strerror(errno);
  const std::string text = std::to_string(ms) + "\n";
  const ssize_t written = ::write(fd, text.data(), text.size());
  const int error = errno;
  ::close(fd);
  if (written != static_cast<ssize_t>(text.size())) return std::strerror(error);
  return {};
}

std::string describe(const SerialDeviceInfo& info) {
  std::string out = info.device + " (";
  if (info.tty.empty()) return out + "not a tty the kernel lists in sysfs: a pseudo-terminal?)";
  out += info.tty + ", driver " + (info.driver.empty() ? "unknown" : info.driver);
  if (info.usb) out += ", USB adapter";
  if (info.latency_timer_ms) {
    out += ", latency timer " + std::to_string(*info.latency_timer_ms) + " ms";
  }
  if (info.rx_trig_bytes) {
    out += ", receive FIFO trigger " + std::to_string(*info.rx_trig_bytes) + " bytes";
  }
  return out + ")";
}

std::string latency_timer_advice(const SerialDeviceInfo& info, int ms) {
  const std::string value = std::to_string(ms);
  std::string out = "run as root: echo " + value + " > " + info.latency_timer_path.string();
  if (!info.driver.empty()) {
    out +=
        "; to keep it across reconnects, a udev rule: ACTION==\"add\", "
        "SUBSYSTEM==\"usb-serial\", DRIVER==\"" +
        info.driver + "\", ATTR{latency_timer}=\"" + value + "\"";
  }
  return out;
}

}  // namespace liftd::io
