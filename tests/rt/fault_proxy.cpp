#include "fault_proxy.hpp"

#include <poll.h>
#include <unistd.h>

#include <cerrno>
#include <thread>
#include <utility>
#include <vector>

#include "common/mono_time.hpp"
#include "fake_responder.hpp"

namespace liftd::rt::testing {
namespace {

// Reads exactly out.size() bytes from fd within `timeout`; false on timeout or error.
bool read_exact(int fd, std::span<std::uint8_t> out, std::chrono::milliseconds timeout,
                const std::atomic<bool>& stop) {
  std::size_t got = 0;
  const MonoTime deadline = mono_now() + timeout;
  while (got < out.size() && !stop.load(std::memory_order_relaxed)) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - mono_now());
    if (left.count() <= 0) return false;
    pollfd pfd{fd, POLLIN, 0};
    if (poll(&pfd, 1, static_cast<int>(left.count()) + 1) <= 0) continue;
    if ((pfd.revents & POLLIN) == 0) return false;
    const ssize_t n = ::read(fd, out.data() + got, out.size() - got);
    if (n > 0) got += static_cast<std::size_t>(n);
  }
  return got == out.size();
}

void write_all(int fd, std::span<const std::uint8_t> bytes) {
  if (!bytes.empty()) (void)!::write(fd, bytes.data(), bytes.size());
}

}  // namespace

FaultProxy::FaultProxy(int a_fd, int b_fd, std::function<Fault(std::uint64_t)> plan, int priority)
    : a_fd_(a_fd), b_fd_(b_fd), plan_(std::move(plan)) {
  options_.priority = priority;
  options_.lock_memory = false;
  options_.stack_prefault_bytes = 0;
}

FaultProxy::~FaultProxy() {
  stop();
}

int FaultProxy::start() {
  stop_.store(false);
  return thread_.start(options_, [this] { loop(); });
}

void FaultProxy::stop() noexcept {
  stop_.store(true);
  thread_.join();
}

void FaultProxy::loop() noexcept {
  constexpr auto kRequestWait = std::chrono::milliseconds(50);  // idle poll for stop()
  constexpr auto kReplyWait = std::chrono::milliseconds(10);    // responder answers in ~1 ms
  while (!stop_.load(std::memory_order_relaxed)) {
    std::array<std::uint8_t, kEchoFrameSize> request{};
    if (!read_exact(a_fd_, request, kRequestWait, stop_)) continue;
    const std::uint64_t index = requests_.fetch_add(1, std::memory_order_relaxed);
    // Drop a reply that came after we gave up waiting for it, or it would be taken as the
    // answer to this request and every later reply would be one behind.
    std::array<std::uint8_t, 64> stale{};
    while (::read(b_fd_, stale.data(), stale.size()) > 0) {
    }
    write_all(b_fd_, request);
    std::array<std::uint8_t, kEchoFrameSize> reply{};
    if (!read_exact(b_fd_, reply, kReplyWait, stop_)) continue;
    const Fault fault = healed_.load(std::memory_order_relaxed) ? Fault::None : plan_(index);
    switch (fault) {
      case Fault::None:
        write_all(a_fd_, reply);
        break;
      case Fault::FlipBit:
        reply[2] ^= 0x04;
        write_all(a_fd_, reply);
        break;
      case Fault::DropByte: {
        const std::array<std::uint8_t, 5> shorter{reply[0], reply[1], reply[3], reply[4], reply[5]};
        write_all(a_fd_, shorter);
        break;
      }
      case Fault::Truncate:
        write_all(a_fd_, std::span(reply).first(3));
        break;
      case Fault::ExtraBytes: {
        const std::array<std::uint8_t, 8> longer{reply[0], reply[1], reply[2], reply[3],
                                                 reply[4], reply[5], 0x55,     0xAA};
        write_all(a_fd_, longer);
        break;
      }
      case Fault::Stall:
        std::this_thread::sleep_for(kStall);
        write_all(a_fd_, reply);
        break;
      case Fault::Silence:
        break;
    }
    applied_[static_cast<std::size_t>(fault)].fetch_add(1, std::memory_order_relaxed);
  }
}

}  // namespace liftd::rt::testing
