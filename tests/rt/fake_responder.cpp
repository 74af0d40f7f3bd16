#include "fake_responder.hpp"

#include <poll.h>
#include <unistd.h>

#include <cerrno>
#include <ctime>

#include "common/mono_time.hpp"

namespace liftd::rt::testing {
namespace {

void sleep_until(MonoTime when) noexcept {
  const auto ns = when.count();
  const timespec ts{static_cast<time_t>(ns / 1'000'000'000), static_cast<long>(ns % 1'000'000'000)};
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
}

}  // namespace

std::uint8_t echo_checksum(std::span<const std::uint8_t> frame) noexcept {
  std::uint8_t x = 0;
  for (std::size_t i = 0; i + 1 < kEchoFrameSize && i < frame.size(); ++i) x ^= frame[i];
  return x;
}

std::array<std::uint8_t, kEchoFrameSize> echo_reply(
    std::span<const std::uint8_t> request) noexcept {
  std::array<std::uint8_t, kEchoFrameSize> reply{};
  for (std::size_t i = 0; i + 1 < kEchoFrameSize; ++i) {
    reply[i] = static_cast<std::uint8_t>(request[i] ^ kEchoMask);
  }
  reply[kEchoFrameSize - 1] = echo_checksum(reply);
  return reply;
}

FakeResponder::FakeResponder(int fd, std::chrono::microseconds reply_delay, int priority, Line line)
    : fd_(fd), reply_delay_(reply_delay), line_(line) {
  options_.priority = priority;
  options_.lock_memory = false;
  options_.stack_prefault_bytes = 0;
}

FakeResponder::~FakeResponder() {
  stop();
}

int FakeResponder::start() {
  stop_.store(false);
  return thread_.start(options_, [this] { loop(); });
}

void FakeResponder::stop() noexcept {
  stop_.store(true);
  thread_.join();
}

void FakeResponder::loop() noexcept {
  std::array<std::uint8_t, kEchoFrameSize> frame{};
  std::size_t got = 0;
  MonoTime last_byte{};
  bool colliding = false;      // the frame on the line now collides
  constexpr int kPollMs = 20;  // how quickly stop() is noticed
  while (!stop_.load(std::memory_order_relaxed)) {
    pollfd pfd{fd_, POLLIN, 0};
    const int r = poll(&pfd, 1, kPollMs);
    if (r <= 0) continue;
    if ((pfd.revents & POLLIN) == 0) {
      // Hang-up without data: the other side is closed for now; do not spin.
      usleep(5000);
      continue;
    }
    std::array<std::uint8_t, 64> chunk{};
    const ssize_t n = ::read(fd_, chunk.data(), chunk.size());
    if (n <= 0) continue;
    const MonoTime now = mono_now();
    if (line_.echo) {
      // The master's bytes as the line carried them: a collision changes a frame's second
      // byte for every receiver (the master's echo and this responder alike).
      std::size_t at = got;
      for (std::size_t i = 0; i < static_cast<std::size_t>(n); ++i, ++at) {
        if (at % kEchoFrameSize == 0) colliding = false;
        if (at % kEchoFrameSize == 1) {
          std::uint32_t left = collide_.load();
          while (left > 0 && !collide_.compare_exchange_weak(left, left - 1)) {
          }
          colliding = left > 0;
          if (colliding) collisions_.fetch_add(1, std::memory_order_relaxed);
        }
        if (colliding && at % kEchoFrameSize == 1) chunk[i] ^= 0x10;
      }
      (void)!::write(fd_, chunk.data(), static_cast<std::size_t>(n));
    }
    for (std::size_t i = 0; i < static_cast<std::size_t>(n); ++i) {
      if (got > 0 && now - last_byte > kInterByteGap) got = 0;  // stale partial frame
      frame[got++] = chunk[i];
      last_byte = now;
      if (got < kEchoFrameSize) continue;
      got = 0;
      if (line_.silent) continue;
      sleep_until(now + reply_delay_);
      const auto reply = echo_reply(frame);
      if (::write(fd_, reply.data(), reply.size()) == static_cast<ssize_t>(reply.size())) {
        answered_.fetch_add(1, std::memory_order_relaxed);
      }
    }
  }
}

}  // namespace liftd::rt::testing
