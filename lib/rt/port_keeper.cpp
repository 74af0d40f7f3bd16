#include "rt/port_keeper.hpp"

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <string_view>
#include <utility>

namespace liftd::rt {
namespace {

constexpr auto kKeeperTick = std::chrono::milliseconds(5);  // keeper's polling interval

void set_event_text(CycleEvent& event, std::string_view text) noexcept {
  const std::size_t n = std::min(text.size(), event.text.size() - 1);
  std::copy_n(text.data(), n, event.text.data());
  event.text[n] = '\0';
}

}  // namespace

PortKeeper::PortKeeper(PortKeeperConfig config) : config_(std::move(config)) {}

PortKeeper::~PortKeeper() {
  stop();
}

int PortKeeper::start(const RtThreadOptions& options, std::function<void()> rt_loop) {
  if (started_) return EBUSY;
  stop_.store(false);
  port_wanted_.store(true);
  if (const int err = rt_thread_.start(options, std::move(rt_loop)); err != 0) return err;
  started_ = true;
  if (const std::string text = rt_thread_.status().describe(); !text.empty()) {
    CycleEvent e;
    e.kind = CycleEventKind::ThreadStatus;
    e.time = mono_now();
    e.error_number = rt_thread_.status().sched_errno;
    set_event_text(e, text);
    keeper_events_.try_push(e);  // before the keeper exists: this thread is its producer now
  }
  keeper_ = std::thread([this] { keeper_loop(); });
  return 0;
}

void PortKeeper::stop() noexcept {
  if (!started_) return;
  stop_.store(true);
  rt_thread_.join();
  if (keeper_.joinable()) keeper_.join();
  port_.close();  // never waits for output the line cannot drain (io::close_port_fd)
  port_ready_.store(false);
  if (const int fd = offered_fd_.exchange(-1); fd >= 0) io::close_port_fd(fd);
  if (const int fd = dead_fd_.exchange(-1); fd >= 0) io::close_port_fd(fd);
  started_ = false;
}

bool PortKeeper::adopt_offered_port() noexcept {
  const int fd = offered_fd_.exchange(-1, std::memory_order_acq_rel);
  if (fd < 0) return false;
  port_ = io::SerialPort::adopt(fd);
  port_ready_.store(true, std::memory_order_relaxed);
  port_opens_.store(port_opens_.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
  return true;
}

void PortKeeper::hand_back_port() noexcept {
  port_ready_.store(false, std::memory_order_relaxed);
  // Closing a tty may wait for output to drain: leave that to the keeper thread.
  if (const int old = dead_fd_.exchange(port_.release(), std::memory_order_acq_rel); old >= 0) {
    ::close(old);  // the keeper has not collected the previous one yet (rare)
  }
  port_wanted_.store(true, std::memory_order_release);
  port_losses_.store(port_losses_.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
}

std::string PortKeeper::describe_opened(const io::SerialPort& opened) const {
  const io::PortFeatures& f = opened.features();
  std::string text = config_.device_path;
  text += f.rs485_enabled ? ", rs485 mode on" : "";
  if (f.rs485_errno != 0) {
    text += ", rs485 mode not supported by the driver (" +
            std::string(std::strerror(f.rs485_errno)) + ")";
  }
  text += f.low_latency_enabled ? ", low latency on" : ", low latency not available";
  if (config_.add_open_notes) config_.add_open_notes(opened, text);
  return text;
}

void PortKeeper::keeper_loop() {
  auto backoff = config_.reopen_backoff_min;
  MonoTime next_attempt = mono_now();
  int last_reported_errno = -1;
  while (!stop_.load(std::memory_order_relaxed)) {
    const MonoTime now = mono_now();
    if (const int dead = dead_fd_.exchange(-1, std::memory_order_acq_rel); dead >= 0) {
      io::close_port_fd(dead);  // a stalled line must not hold the keeper (and stop()) 30 s
      // Give a replugged adapter time to come back before the first attempt.
      backoff = config_.reopen_backoff_min;
      next_attempt = now + backoff;
    }
    if (port_wanted_.load(std::memory_order_acquire) &&
        offered_fd_.load(std::memory_order_acquire) < 0 && now >= next_attempt) {
      auto opened = io::SerialPort::open(config_.device_path, config_.serial);
      CycleEvent e;
      e.time = now;
      if (opened.ok()) {
        e.kind = CycleEventKind::PortOpened;
        set_event_text(e, describe_opened(opened.value()));
        keeper_events_.try_push(e);
        last_reported_errno = -1;
        backoff = config_.reopen_backoff_min;
        port_wanted_.store(false, std::memory_order_release);
        offered_fd_.store(opened.value().release(), std::memory_order_release);
      } else {
        // Report the first failure and every change of reason, not every retry.
        if (opened.error().error_number != last_reported_errno) {
          e.kind = CycleEventKind::PortOpenFailed;
          e.error_number = opened.error().error_number;
          set_event_text(e, opened.error().message());
          keeper_events_.try_push(e);
          last_reported_errno = opened.error().error_number;
        }
        next_attempt = now + backoff;
        backoff = std::min(backoff * 2, config_.reopen_backoff_max);
      }
    }
    std::this_thread::sleep_for(kKeeperTick);
  }
}

}  // namespace liftd::rt
