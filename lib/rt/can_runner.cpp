#include "rt/can_runner.hpp"

#include <poll.h>
#include <sys/eventfd.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>

namespace liftd::rt {

namespace {

// The packed last error (CanRunner::last_error_): errno in bits 0..31, the ErrorWhat in
// 32..39, the can::OpenStep in 40..47.
constexpr unsigned kWhatShift = 32;
constexpr unsigned kStepShift = 40;
constexpr std::uint64_t kByte = 0xFF;
constexpr std::uint64_t kErrnoMask = 0xFFFF'FFFF;

std::string with_errno(std::string words, int error) {
  if (error != 0) words += std::string(": ") + std::strerror(error);
  return words;
}

}  // namespace

CanRunner::CanRunner(const CanRunnerConfig& config, CanEngine& engine)
    : config_(config),
      engine_(engine),
      opener_(config.endpoint, config.ids),
      socket_(can::CanSocket::unattached(config.ids)),
      recorder_(config.recorder_records, kCanRecordBytes) {
  wake_fd_ = ::eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
}

CanRunner::~CanRunner() {
  stop();
  if (wake_fd_ >= 0) ::close(wake_fd_);
}

void CanRunner::adopt(can::CanSocket socket) {
  socket_ = std::move(socket);
  adopted_ = true;
}

int CanRunner::start() {
  if (wake_fd_ < 0) return EMFILE;
  stop_.store(false, std::memory_order_release);
  RtThreadOptions options = config_.rt;
  if (options.name.empty()) options.name = "liftd-can";  // ps -L, chrt -p, ftrace
  return thread_.start(options, [this] { loop(); });
}

void CanRunner::stop() noexcept {
  if (!thread_.joinable()) return;
  stop_.store(true, std::memory_order_release);
  const std::uint64_t one = 1;
  (void)::write(wake_fd_, &one, sizeof one);
  thread_.join();
}

CanRunnerCounters CanRunner::counters() const noexcept {
  CanRunnerCounters c;
  c.frames_received = frames_received_.load(std::memory_order_relaxed);
  c.frames_sent = frames_sent_.load(std::memory_order_relaxed);
  c.send_errors = send_errors_.load(std::memory_order_relaxed);
  c.error_frames = error_frames_.load(std::memory_order_relaxed);
  c.reopens = reopens_.load(std::memory_order_relaxed);
  c.dropped = dropped_.load(std::memory_order_relaxed);
  c.overflowed = overflowed_.load(std::memory_order_relaxed);
  c.outbox_overflows = outbox_overflows_.load(std::memory_order_relaxed);
  return c;
}

void CanRunner::publish_error(int error, ErrorWhat what, can::OpenStep step) noexcept {
  last_error_.store((static_cast<std::uint64_t>(static_cast<std::uint32_t>(error)) & kErrnoMask) |
                        (static_cast<std::uint64_t>(what) << kWhatShift) |
                        (static_cast<std::uint64_t>(step) << kStepShift),
                    std::memory_order_release);
}

std::string CanRunner::last_error() const {
  const std::uint64_t packed = last_error_.load(std::memory_order_acquire);
  const int error = static_cast<int>(static_cast<std::uint32_t>(packed & kErrnoMask));
  switch (static_cast<ErrorWhat>((packed >> kWhatShift) & kByte)) {
    case ErrorWhat::None:
      return "";
    case ErrorWhat::Open:
      return with_errno(
          opener_.describe({error, static_cast<can::OpenStep>((packed >> kStepShift) & kByte)}),
          error);
    case ErrorWhat::PeerClosed:
      return with_errno("the CAN peer closed the connection", error);
    case ErrorWhat::ReadFailed:
      return with_errno("reading the CAN endpoint failed", error);
    case ErrorWhat::WriteFailed:
      return with_errno("writing to the CAN endpoint failed", error);
  }
  return with_errno("the CAN endpoint failed", error);
}

void CanRunner::notify() noexcept {
  if (notify_fd_ < 0) return;
  const std::uint64_t one = 1;
  (void)::write(notify_fd_, &one, sizeof one);
}

void CanRunner::record(MonoTime now, Direction direction, std::uint8_t flags,
                       const can::Frame& frame) noexcept {
  std::array<std::uint8_t, 2 + can::kMaxData> bytes{};
  bytes[0] = static_cast<std::uint8_t>(frame.id >> 8);
  bytes[1] = static_cast<std::uint8_t>(frame.id & 0xFF);
  std::copy_n(frame.data.begin(), frame.length, bytes.begin() + 2);
  recorder_.record(now, direction, flags,
                   std::span<const std::uint8_t>(bytes.data(), 2U + frame.length));
}

bool CanRunner::open_endpoint(MonoTime now) noexcept {
  // The opener was prepared with the runner: opening allocates nothing and builds no text.
  const auto opened = opener_.open();
  if (!opened) {
    publish_error(opened.error().code, ErrorWhat::Open, opened.error().step);
    schedule_reopen(now);
    return false;
  }
  socket_.attach(opened.value());
  if (ever_opened_) reopens_.fetch_add(1, std::memory_order_relaxed);
  ever_opened_ = true;
  // The backoff is not reset here: a CAN interface that is down still binds, and fails only
  // at the first read (ENETDOWN). It starts again from reopen_first once a record arrives.
  engine_.on_endpoint(true, now);
  recorder_.record(now, Direction::Event, 0, {});
  return true;
}

void CanRunner::schedule_reopen(MonoTime now) noexcept {
  // reopen_first, doubling up to reopen_max while the endpoint fails again before carrying a
  // record: one failing interface is tried a few times a minute, not ten times a second.
  reopen_delay_ = std::min(config_.reopen_max,
                           reopen_delay_ == MonoTime{} ? config_.reopen_first : reopen_delay_ * 2);
  reopen_at_ = now + reopen_delay_;
}

void CanRunner::close_endpoint(MonoTime now, int error, ErrorWhat what) noexcept {
  publish_error(error, what);
  socket_.close();  // a CAN or Unix socket closes at once (no output to drain, unlike a tty)
  engine_.on_endpoint(false, now);
  recorder_.record(now, Direction::Event, record_flag::kPortLost, {});
  schedule_reopen(now);
}

bool CanRunner::send_queued(MonoTime now) noexcept {
  int failure = 0;  // the errno that failed the endpoint, if one did
  for (const can::Frame& frame : outbox_.queued()) {
    if (failure != 0 || !socket_.is_open()) {
      // No endpoint (it failed in this call, or is down while the engine keeps its schedule):
      // counted, not recorded, so a long outage does not flood the trace with the same line.
      send_errors_.fetch_add(1, std::memory_order_relaxed);
      engine_.on_sent(frame, false, now);
      continue;
    }
    const int error = socket_.write(frame);
    if (error == 0) {
      frames_sent_.fetch_add(1, std::memory_order_relaxed);
      record(now, Direction::Tx, record_flag::kSent, frame);
    } else {
      send_errors_.fetch_add(1, std::memory_order_relaxed);
      record(now, Direction::Tx, record_flag::kSendFailed, frame);
      // A full queue (EAGAIN, ENOBUFS) refuses this frame only; anything else fails the
      // endpoint.
      if (error != EAGAIN && error != ENOBUFS) failure = error;
    }
    engine_.on_sent(frame, error == 0, now);
  }
  outbox_overflows_.store(outbox_.overflows(), std::memory_order_relaxed);
  outbox_.clear();
  if (failure != 0) close_endpoint(now, failure, ErrorWhat::WriteFailed);
  return failure == 0;
}

void CanRunner::loop() {
  const MonoTime start = mono_now();
  if (adopted_) {
    ever_opened_ = true;
    engine_.on_endpoint(true, start);
  } else {
    (void)open_endpoint(start);
  }
  while (!stop_.load(std::memory_order_acquire)) {
    progress_.fetch_add(1, std::memory_order_relaxed);
    std::array<pollfd, 2> fds{};
    fds[0] = {wake_fd_, POLLIN, 0};
    fds[1] = {socket_.fd(), POLLIN, 0};  // -1 while closed: poll() skips it
    const auto timeout_ms = static_cast<int>(
        std::chrono::duration_cast<std::chrono::milliseconds>(config_.tick).count());
    (void)::poll(fds.data(), fds.size(), std::max(1, timeout_ms));
    MonoTime now = mono_now();
    if (!socket_.is_open() && !adopted_ && now >= reopen_at_) (void)open_endpoint(now);
    // Every record waiting, each fed to the engine (and its answer sent) before the next is
    // read: the card's frames come 100 ms apart, so this loop is short.
    for (int i = 0; socket_.is_open() && i < 64; ++i) {
      const can::Received r = socket_.read();
      now = mono_now();
      if (r.kind == can::Received::Kind::Nothing) break;
      if (r.kind == can::Received::Kind::Closed || r.kind == can::Received::Kind::Failed) {
        close_endpoint(
            now, r.errno_value,
            r.kind == can::Received::Kind::Closed ? ErrorWhat::PeerClosed : ErrorWhat::ReadFailed);
        break;
      }
      reopen_delay_ = MonoTime{};  // the endpoint carries records: a new failure starts over
      if (r.kind == can::Received::Kind::Error) {
        error_frames_.fetch_add(1, std::memory_order_relaxed);
        recorder_.record(now, Direction::Event, record_flag::kBad, {});
        engine_.on_bus_error(r.error, now);
        continue;
      }
      frames_received_.fetch_add(1, std::memory_order_relaxed);
      record(now, Direction::Rx, record_flag::kReply, r.frame);
      outbox_.clear();
      engine_.on_frame(r.frame, now, outbox_);
      if (!send_queued(now)) break;
    }
    // The endpoint keeps its drop counters over every descriptor it had.
    const can::DropCounters& d = socket_.drops();
    dropped_.store(d.filtered + d.malformed + d.extended, std::memory_order_relaxed);
    overflowed_.store(d.overflowed, std::memory_order_relaxed);
    now = mono_now();
    outbox_.clear();
    engine_.on_tick(now, outbox_);  // timeouts, and what the engine sends on its own schedule
    (void)send_queued(now);
    notify();  // a frame, a tick or a send's fate may have queued news for the io thread
  }
  socket_.close();
}

}  // namespace liftd::rt
