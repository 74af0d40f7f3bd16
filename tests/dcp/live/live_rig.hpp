// The real stack over real pseudo-terminals: rt::CycleRunner (normal scheduling, no memory
// lock, so it runs unprivileged) driving control::DcpController, and the drive simulator
// (dcp::sim::SerialDriveRunner) on the far end of a pty. The test thread plays the daemon's io
// thread: it posts the machine's inputs, drains events and replies, reads snapshots.
#pragma once

#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "dcp/control/controller_rig.hpp"
#include "dcp/control/dcp_controller.hpp"
#include "dcp/sim/serial_runner.hpp"
#include "io/pty.hpp"
#include "rt/cycle_runner.hpp"

namespace liftd::integration {

using namespace std::chrono_literals;

/// The simulator's encoder as the controller's position source. The runner can be swapped
/// (device replaced) while the cycle runs; a missing runner reads as "position lost".
class RunnerPosition final : public control::PositionSource {
 public:
  void attach(const dcp::sim::SerialDriveRunner* runner) noexcept {
    runner_.store(runner, std::memory_order_release);
  }
  std::optional<std::int64_t> position_mm(MonoTime) const noexcept override {
    const dcp::sim::SerialDriveRunner* r = runner_.load(std::memory_order_acquire);
    if (r == nullptr) return std::nullopt;
    return std::llround(r->position_mm());
  }

 private:
  std::atomic<const dcp::sim::SerialDriveRunner*> runner_{nullptr};
};

/// A fresh pty pair (raw, no RS485 ioctl on a pty).
inline io::PtyPair make_pty() {
  io::SerialSettings raw;
  raw.rs485 = io::Rs485Mode::Off;
  auto pty = io::PtyPair::create(raw);
  if (!pty.ok()) throw std::runtime_error(pty.error().message());
  return std::move(pty).value();
}

/// A simulator serving the master end of `pty` (through a duplicate of its descriptor, so the
/// pair and the runner close independently).
/// `echo`: the line gives the master its bytes back (RunnerOptions::echo).
inline std::unique_ptr<dcp::sim::SerialDriveRunner> serve(int master_fd,
                                                          const dcp::sim::DriveConfig& config,
                                                          bool echo = false) {
  dcp::sim::RunnerOptions options;
  options.fd = ::dup(master_fd);
  options.echo = echo;
  options.reconnect = false;
  // The drive stands for hardware that answers on time: real-time scheduling one step below
  // the master's cycle (cycle_config) where permitted, as in liftd --simulate.
  options.priority = 19;
  auto runner = std::make_unique<dcp::sim::SerialDriveRunner>(config, options);
  if (!runner->start()) throw std::runtime_error("simulator: " + runner->last_error());
  return runner;
}

/// A symlink standing for a device node that can disappear and come back under its name.
class DeviceAlias {
 public:
  DeviceAlias()
      : path_((std::filesystem::temp_directory_path() /
               ("liftd-it-" + std::to_string(::getpid()) + "-" + std::to_string(next_id())))
                  .string()) {}
  ~DeviceAlias() { remove(); }
  DeviceAlias(const DeviceAlias&) = delete;
  DeviceAlias& operator=(const DeviceAlias&) = delete;
  const std::string& path() const noexcept { return path_; }
  void point_to(const std::string& target) {
    remove();
    std::filesystem::create_symlink(target, path_);
  }
  void remove() noexcept {
    std::error_code ec;
    std::filesystem::remove(path_, ec);
  }

 private:
  static int next_id() {
    static std::atomic<int> id{0};
    return ++id;
  }
  std::string path_;
};

/// Cycle settings for the tests: DCP 7.2 timing, real-time scheduling where permitted.
inline rt::CycleConfig cycle_config(const std::string& device,
                                    io::EchoMode echo = io::EchoMode::Off) {
  rt::CycleConfig c;
  c.device_path = device;
  c.echo = echo;
  // SCHED_FIFO where permitted (normal scheduling otherwise, as RtThread falls back): on a
  // loaded machine a normal thread sees replies after their DCP 7.2 deadline, which the cycle
  // rightly counts as missing.
  c.thread.priority = 20;
  c.thread.lock_memory = false;
  // The send window is the spec's largest (DCP 7.2: 1.375 ms, the default); a wake-up later
  // than that skips the cycle, which the link supervision tolerates (DCP 7.3: 10 frames).
  return c;
}

/// The master side: DcpController run by a CycleRunner on `device`.
struct LiveMaster {
  explicit LiveMaster(const std::string& device,
                      const control::ControllerConfig& config =
                          control::testing::default_config(dcp::Protocol::Dcp4),
                      std::function<rt::CycleEngine&(control::DcpController&)> wrap = {},
                      io::EchoMode echo = io::EchoMode::Off)
      : controller(config, position),
        runner(cycle_config(device, echo), wrap ? wrap(controller) : controller) {
    inputs.valid = inputs.safety_chain_closed = inputs.doors_closed = inputs.doors_locked = true;
  }
  ~LiveMaster() { runner.stop(); }

  int start() { return runner.start(); }

  /// The io thread's chores: inputs every 100 ms (inputs.timeout_ms is 500), drain queues.
  void pump() {
    const MonoTime now = mono_now();
    if (now - last_inputs >= 100ms) {
      controller.post(control::Command{0, control::InputsCommand{inputs}});
      last_inputs = now;
    }
    control::ControllerEvent e;
    while (controller.poll_event(e)) events.push_back(e);
    control::CommandReply r;
    while (controller.poll_reply(r)) replies.push_back(r);
    rt::CycleEvent ce;
    while (runner.poll_event(ce)) cycle_events.push_back(ce);
  }

  /// Pumps every 5 ms until `done` or `timeout`; true if done.
  bool wait_until(const std::function<bool()>& done, std::chrono::milliseconds timeout) {
    const MonoTime end = mono_now() + timeout;
    while (mono_now() < end) {
      pump();
      if (done()) return true;
      std::this_thread::sleep_for(5ms);
    }
    pump();
    return done();
  }
  void run_for(std::chrono::milliseconds duration) {
    wait_until([] { return false; }, duration);
  }

  /// Posts a tagged command and waits for its reply.
  control::CommandReply command(control::CommandBody body,
                                std::chrono::milliseconds timeout = 5000ms) {
    const std::uint32_t tag = ++next_tag;
    controller.post(control::Command{tag, body});
    std::optional<control::CommandReply> got;
    wait_until(
        [&] {
          for (const auto& r : replies) {
            if (r.tag == tag) got = r;
          }
          return got.has_value();
        },
        timeout);
    return got.value_or(
        control::CommandReply{tag, control::ReplyCode::Timeout, "test: no reply", {}, false, {}});
  }

  bool link_up() { return controller.snapshot().link == dcp::LinkState::Up; }
  /// Link up and the drive's status known (the first ready reply after the handshake).
  bool ready() {
    const auto s = controller.snapshot();
    return s.link == dcp::LinkState::Up && s.status_byte &&
           (*s.status_byte & dcp::status_bit::kReady) != 0;
  }
  bool idle() {
    const auto s = controller.snapshot();
    return s.travel_kind == travel::TravelKind::None && s.status_byte &&
           (*s.status_byte & dcp::status_bit::kTravelActive) == 0;
  }
  std::size_t travel_events(travel::Event::Type type) const {
    std::size_t n = 0;
    for (const auto& e : events) {
      n += e.kind == control::ControllerEvent::Kind::Travel && e.travel.type == type ? 1U : 0U;
    }
    return n;
  }
  std::size_t link_events_to(dcp::LinkState state) const {
    std::size_t n = 0;
    for (const auto& e : events) {
      n += e.kind == control::ControllerEvent::Kind::Link &&
                   e.link.kind == dcp::LinkEventKind::StateChanged && e.link.state == state
               ? 1U
               : 0U;
    }
    return n;
  }

  RunnerPosition position;
  control::DcpController controller;
  rt::CycleRunner runner;
  lift::Inputs inputs;
  MonoTime last_inputs{};
  std::uint32_t next_tag = 0;
  std::vector<control::ControllerEvent> events;
  std::vector<control::CommandReply> replies;
  std::vector<rt::CycleEvent> cycle_events;
};

/// The master's channel byte stream in `records` (Tx frames after `from`, idle bytes left
/// out), to look for I-messages in what went over the wire.
inline std::vector<std::uint8_t> master_channel(const std::vector<rt::FrameRecord>& records,
                                                MonoTime from = MonoTime{}) {
  std::vector<std::uint8_t> out;
  for (const auto& r : records) {
    if (r.direction != rt::Direction::Tx || r.length != dcp::kFrameSize || r.time < from) continue;
    for (std::size_t i = 3; i < 5; ++i) {  // DCP 5: bytes 4 and 5 are the channel
      if (r.bytes[i] != 0x00) out.push_back(r.bytes[i]);
    }
  }
  return out;
}

/// How often the master started an I0 (STX, expanded-data mode 0x1C, 'I', '0'; DCP 5.12.2).
inline std::size_t count_i0(const std::vector<std::uint8_t>& stream) {
  std::size_t n = 0;
  for (std::size_t i = 0; i + 3 < stream.size(); ++i) {
    n += stream[i] == 0x02 && stream[i + 1] == 0x1C && stream[i + 2] == 'I' && stream[i + 3] == '0'
             ? 1U
             : 0U;
  }
  return n;
}

}  // namespace liftd::integration
