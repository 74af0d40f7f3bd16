#include "host/serial_device_report.hpp"

#include "log/log.hpp"

namespace liftd::daemon {

io::SerialDeviceInfo prepare_serial_device(const std::string& device, std::string_view component,
                                           const std::filesystem::path& sys) {
  io::SerialDeviceInfo info = io::query_serial_device(device, sys);
  const std::string c(component);
  if (info.latency_timer_ms && *info.latency_timer_ms > io::kLatencyTimerMs) {
    const int was = *info.latency_timer_ms;
    const std::string why = io::set_latency_timer(info, io::kLatencyTimerMs);
    if (why.empty()) {
      info.latency_timer_ms = io::kLatencyTimerMs;
      log::event(log::Level::info, c, "serial_latency_set",
                 {{"device", device}, {"was_ms", std::to_string(was)}},
                 "serial device " + device + ": the USB adapter's latency timer was " +
                     std::to_string(was) + " ms, set to " + std::to_string(io::kLatencyTimerMs) +
                     " ms");
    } else {
      // DCP 7.2: a reply held longer than the cycle by the adapter is a missing reply.
      log::event(
          log::Level::warn, c, "serial_latency_high",
          {{"device", device}, {"latency_timer_ms", std::to_string(was)}},
          "serial device " + device + ": the USB adapter holds received bytes up to " +
              std::to_string(was) +
              " ms (its latency timer), longer than a 15 ms cycle; liftd could not set it (" + why +
              "): " + io::latency_timer_advice(info, io::kLatencyTimerMs));
    }
  }
  log::event(log::Level::info, c, "serial_device",
             {{"device", device}, {"driver", info.driver}, {"usb", info.usb ? "yes" : "no"}},
             "serial device " + io::describe(info));
  return info;
}

nlohmann::json serial_device_json(const io::SerialDeviceInfo& info) {
  const auto number = [](const std::optional<int>& v) {
    return v ? nlohmann::json(*v) : nlohmann::json(nullptr);
  };
  return {{"device", info.device},
          {"tty", info.tty.empty() ? nlohmann::json(nullptr) : nlohmann::json(info.tty)},
          {"driver", info.driver.empty() ? nlohmann::json(nullptr) : nlohmann::json(info.driver)},
          {"usb", info.usb},
          {"latency_timer_ms", number(info.latency_timer_ms)},
          {"rx_trig_bytes", number(info.rx_trig_bytes)}};
}

}  // namespace liftd::daemon
