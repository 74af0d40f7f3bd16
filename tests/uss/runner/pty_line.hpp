// The far end of a pty standing in for a USS bus line. A pty moves bytes at once and has no
// baud rate, so this thread plays the line: every byte the master wrote is handed to the slave
// simulator only when it would be complete on a real line (one character time after the
// previous one, A 6.1), and a reply is written one character time after the slave starts it
// (when its STX would be complete). The master's own pacing (uss::Master + uss::UssRunner: start
// pause, transmission time, reply delay) then makes the cycle a real line would have.
// Header only: used by tests/uss/runner and by tools/bench/uss/uss_bench.cpp and uss_bus.cpp (the
// USS bus of api-load-bench), which build without the tests.
#pragma once

#include <poll.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <thread>

#include "common/mono_time.hpp"
#include "rt/rt_thread.hpp"
#include "uss/line.hpp"
#include "uss/timing.hpp"

namespace liftd::uss::testing {

/// Drives a slave simulator with the interface of uss::sim::UssBusSim / uss::sim::UssSlaveSim:
/// on_char, on_time, deadline, next_reply_at, take_reply(now, reply) with reply.view() and
/// reply.parity_error_at, reply_sent(end). The simulator belongs to the line's thread between
/// start() and stop().
template <class Sim, class Reply>
class PtyLine {
 public:
  PtyLine(int fd, Sim& sim, std::uint32_t baud)
      : fd_(fd), sim_(sim), baud_(baud), tz_(character_time(baud)) {}
  PtyLine(const PtyLine&) = delete;
  PtyLine& operator=(const PtyLine&) = delete;
  ~PtyLine() { stop(); }

  /// Starts the line thread; `priority` > 0: SCHED_FIFO where allowed (normal otherwise);
  /// `cpu` >= 0: pinned to that CPU. Returns 0 or an errno.
  int start(int priority = 0, int cpu = -1) {
    stop_.store(false);
    rt::RtThreadOptions options;
    options.priority = priority;
    options.cpu = cpu;
    options.lock_memory = false;
    return thread_.start(options, [this] { loop(); });
  }
  void stop() noexcept {
    stop_.store(true);
    thread_.join();
  }
  /// The line echoes (an RS485 transceiver whose receiver stays on while it sends, an
  /// auto-direction USB adapter): every byte the master sends comes back to it as it is sent,
  /// before any reply. Set before start().
  void set_echo(bool on) noexcept { echo_.store(on); }
  /// The next `telegrams` telegrams collide with another station's bits: the first byte of
  /// each (its STX) is changed on the line, for the master's echo and the slaves alike (one
  /// line, one signal for every receiver on it).
  void collide(std::uint32_t telegrams) noexcept { collide_.fetch_add(telegrams); }
  /// Collisions made so far.
  std::uint64_t collisions() const noexcept { return collisions_.load(); }
  /// Replies written.
  std::uint64_t replies() const noexcept { return replies_.load(); }
  /// Bytes received from the master.
  std::uint64_t received() const noexcept { return received_.load(); }

 private:
  struct Pending {
    std::uint8_t byte = 0;
    MonoTime due{};
  };

  void loop() noexcept {
    std::array<std::uint8_t, 1024> buf{};
    MonoTime last_due{};
    while (!stop_.load()) {
      MonoTime now = mono_now();
      while (count_ > 0 && pending_[head_].due <= now) {
        const Pending& p = pending_[head_];
        sim_.on_char(RxChar{p.byte, LineError::None}, p.due);
        head_ = (head_ + 1) % pending_.size();
        --count_;
      }
      sim_.on_time(now);
      if (const auto at = sim_.next_reply_at(); at && now >= *at + tz_) {
        Reply reply;
        if (sim_.take_reply(now, reply)) {
          std::array<std::uint8_t, 256> out{};
          const auto view = reply.view();
          std::copy(view.begin(), view.end(), out.begin());
          // A pty cannot send a parity error: the byte is corrupted instead.
          if (reply.parity_error_at >= 0 &&
              static_cast<std::size_t>(reply.parity_error_at) < view.size()) {
            out[static_cast<std::size_t>(reply.parity_error_at)] ^= 0x01;
          }
          const MonoTime written = mono_now();
          std::size_t done = 0;
          while (done < view.size()) {
            const ssize_t n = ::write(fd_, out.data() + done, view.size() - done);
            if (n > 0) {
              done += static_cast<std::size_t>(n);
            } else if (n < 0 && errno != EINTR && errno != EAGAIN) {
              break;
            }
          }
          sim_.reply_sent(written - tz_ + transmission_time(baud_, view.size()));
          replies_.fetch_add(1);
        }
        continue;
      }
      MonoTime wake = now + std::chrono::milliseconds(1);
      if (count_ > 0) wake = std::min(wake, pending_[head_].due);
      if (const auto at = sim_.next_reply_at()) wake = std::min(wake, *at + tz_);
      if (const auto d = sim_.deadline()) wake = std::min(wake, *d);
      const auto wait = std::max<std::int64_t>(
          std::chrono::duration_cast<std::chrono::microseconds>(wake - now).count(), 0);
      pollfd pfd{fd_, POLLIN, 0};
      const timespec ts{static_cast<time_t>(wait / 1000000),
                        static_cast<long>(wait % 1000000) * 1000};
      if (ppoll(&pfd, 1, &ts, nullptr) > 0 && (pfd.revents & POLLIN) != 0) {
        const ssize_t n = ::read(fd_, buf.data(), buf.size());
        now = mono_now();
        // A master writes a telegram at once: a read after the line was quiet starts one.
        if (n > 0 && now - last_due > 2 * tz_) {
          std::uint32_t left = collide_.load();
          while (left > 0 && !collide_.compare_exchange_weak(left, left - 1)) {
          }
          if (left > 0) {
            buf[0] ^= 0x10;
            collisions_.fetch_add(1);
          }
        }
        if (n > 0 && echo_.load()) {
          (void)!::write(fd_, buf.data(), static_cast<std::size_t>(n));
        }
        for (ssize_t i = 0; i < n && count_ < pending_.size(); ++i) {
          // A UART completes one character per character time (A 6.1).
          last_due = std::max(now, last_due) + tz_;
          pending_[(head_ + count_) % pending_.size()] =
              Pending{buf[static_cast<std::size_t>(i)], last_due};
          ++count_;
        }
        if (n > 0) received_.fetch_add(static_cast<std::uint64_t>(n));
      } else if ((pfd.revents & (POLLHUP | POLLERR | POLLNVAL)) != 0) {
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
      }
    }
  }

  int fd_;
  Sim& sim_;
  std::uint32_t baud_;
  std::chrono::nanoseconds tz_;
  std::array<Pending, 2048> pending_{};
  std::size_t head_ = 0;
  std::size_t count_ = 0;
  rt::RtThread thread_;
  std::atomic<bool> stop_{false};
  std::atomic<std::uint64_t> replies_{0};
  std::atomic<std::uint64_t> received_{0};
  std::atomic<bool> echo_{false};
  std::atomic<std::uint32_t> collide_{0};
  std::atomic<std::uint64_t> collisions_{0};
};

}  // namespace liftd::uss::testing
