// Helpers of the tests that run a serial port over real ptys: a pty pair, a device name that
// can be pointed at a new pty (a replugged adapter), waiting for a condition, draining events.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <functional>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "common/mono_time.hpp"
#include "io/pty.hpp"
#include "rt/cycle_event.hpp"

namespace liftd::rt::testing {

/// Polls `done` every 5 ms until it is true or `timeout` passes; its last answer.
inline bool wait_for(const std::function<bool()>& done, std::chrono::milliseconds timeout) {
  const MonoTime end = mono_now() + timeout;
  while (mono_now() < end) {
    if (done()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return done();
}

/// Every event `source` (a runner or a port keeper) has queued, oldest first.
template <class EventSource>
std::vector<CycleEvent> drain(EventSource& source) {
  std::vector<CycleEvent> events;
  CycleEvent e;
  while (source.poll_event(e)) events.push_back(e);
  return events;
}

/// A new pty pair (a test failure if none can be made).
inline io::PtyPair make_pty() {
  auto pty = io::PtyPair::create();
  if (!pty.ok()) ADD_FAILURE() << pty.error().message();
  return std::move(pty).value();
}

// A directory with a symlink standing for a udev name (/dev/serial/by-id/...), so a test can
// point the "device" at a new pty, as a replugged USB adapter would reappear.
class DeviceLink {
 public:
  DeviceLink()
      : dir_(std::filesystem::temp_directory_path() /
             ("liftd-rt-" + std::to_string(getpid()) + "-" + std::to_string(counter_++))) {
    std::filesystem::create_directories(dir_);
  }
  ~DeviceLink() { std::filesystem::remove_all(dir_); }
  std::string path() const { return (dir_ / "tty").string(); }
  void point_to(const std::string& target) {
    const auto tmp = dir_ / "tty.new";
    std::filesystem::remove(tmp);
    std::filesystem::create_symlink(target, tmp);
    std::filesystem::rename(tmp, dir_ / "tty");  // atomic replace
  }

 private:
  static inline int counter_ = 0;
  std::filesystem::path dir_;
};

}  // namespace liftd::rt::testing
