#include "rt/can_runner.hpp"

#include <poll.h>
#include <sys/eventfd.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>

namespace liftd::rt {

CanRunner::CanRunner(const CanRunnerConfig& config, CanEngine& engine)
    : config_(config), engine_(engine), recorder_(config.recorder_records, kCanRecordBytes) {
  wake_fd_ = ::eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
}

CanRunner::~CanRunner() {
  stop();
  if (wake_fd_ >= 0) ::close(wake_fd_);
}

void CanRunner::adopt(can::CanSocket socket) {
  socket_.emplace(std::move(socket));
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
  return c;
}

std::string CanRunner::last_error() const {
  std::lock_guard<std::mutex> lock(error_mutex_);
  return last_error_;
}

void CanRunner::notify() noexcept {
  if (notify_fd_ < 0) return;
  const std::uint64_t one = 1;
  (void)::write(notify_fd_, &one, sizeof one);
}

void CanRunner::record(MonoTime now, Direction direction, std::uint8_t flags,
                       const can::Frame& frame) {
  std::array<std::uint8_t, 2 + can::kMaxData> bytes{};
  bytes[0] = static_cast<std::uint8_t>(frame.id >> 8);
  bytes[1] = static_cast<std::uint8_t>(frame.id & 0xFF);
  std::copy_n(frame.data.begin(), frame.length, bytes.begin() + 2);
  recorder_.record(now, direction, flags,
                   std::span<const std::uint8_t>(bytes.data(), 2U + frame.length));
}

bool CanRunner::open_endpoint(MonoTime now) {
  // Opening and its error text allocate: this runs only at start and after a failure, never
  // while frames flow.
  auto opened = can::CanSocket::open(config_.endpoint, config_.ids);
  if (!opened) {
    {
      std::lock_guard<std::mutex> lock(error_mutex_);
      last_error_ = opened.error().what + ": " + std::strerror(opened.error().code);
    }
    schedule_reopen(now);
    return false;
  }
  socket_.emplace(std::move(opened.value()));
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

void CanRunner::close_endpoint(MonoTime now, int error, const char* what) {
  {
    std::lock_guard<std::mutex> lock(error_mutex_);
    last_error_ = std::string(what) + (error != 0 ? std::string(": ") + std::strerror(error) : "");
  }
  overflowed_before_socket_ += socket_->drops().overflowed;
  socket_.reset();
  engine_.on_endpoint(false, now);
  recorder_.record(now, Direction::Event, record_flag::kPortLost, {});
  schedule_reopen(now);
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
    fds[1] = {socket_ ? socket_->fd() : -1, POLLIN, 0};
    const auto timeout_ms = static_cast<int>(
        std::chrono::duration_cast<std::chrono::milliseconds>(config_.tick).count());
    (void)::poll(fds.data(), fds.size(), std::max(1, timeout_ms));
    MonoTime now = mono_now();
    if (!socket_ && !adopted_ && now >= reopen_at_) (void)open_endpoint(now);
    // Every record waiting, each answered before the next is read: the card's frames come
    // 100 ms apart, so this loop is short.
    for (int i = 0; socket_ && i < 64; ++i) {
      const can::Received r = socket_->read();
      now = mono_now();
      if (r.kind == can::Received::Kind::Nothing) break;
      if (r.kind != can::Received::Kind::Closed && r.kind != can::Received::Kind::Failed) {
        reopen_delay_ = MonoTime{};  // the endpoint carries records: a new failure starts over
      }
      if (r.kind == can::Received::Kind::Closed || r.kind == can::Received::Kind::Failed) {
        close_endpoint(now, r.errno_value,
                       r.kind == can::Received::Kind::Closed ? "the CAN peer closed the connection"
                                                             : "reading the CAN endpoint failed");
        break;
      }
      if (r.kind == can::Received::Kind::Error) {
        error_frames_.fetch_add(1, std::memory_order_relaxed);
        recorder_.record(now, Direction::Event, record_flag::kBad, {});
        engine_.on_bus_error(r.error, now);
        continue;
      }
      frames_received_.fetch_add(1, std::memory_order_relaxed);
      record(now, Direction::Rx, record_flag::kReply, r.frame);
      if (const auto answer = engine_.on_frame(r.frame, now)) {
        const int error = socket_->write(*answer);
        engine_.on_sent(error == 0, now);
        if (error == 0) {
          frames_sent_.fetch_add(1, std::memory_order_relaxed);
          record(now, Direction::Tx, record_flag::kSent, *answer);
        } else {
          send_errors_.fetch_add(1, std::memory_order_relaxed);
          record(now, Direction::Tx, record_flag::kSendFailed, *answer);
          if (error != EAGAIN && error != ENOBUFS) {
            close_endpoint(now, error, "writing to the CAN endpoint failed");
            break;
          }
        }
      }
    }
    if (socket_) {
      const can::DropCounters& d = socket_->drops();
      dropped_.store(d.filtered + d.malformed + d.extended, std::memory_order_relaxed);
      overflowed_.store(overflowed_before_socket_ + d.overflowed, std::memory_order_relaxed);
    }
    engine_.on_tick(mono_now());
    notify();  // a frame's answer or a tick's timeout may have queued news for the io thread
  }
  socket_.reset();
}

}  // namespace liftd::rt
