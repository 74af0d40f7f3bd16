#include "dcp/sim/serial_runner.hpp"

#include <sys/stat.h>
#include <sys/sysmacros.h>

#include <poll.h>
#include <pthread.h>
#include <sched.h>
#include <sys/epoll.h>
#include <sys/eventfd.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstdio>
#include <system_error>
#include <utility>

namespace liftd::dcp::sim {

namespace {

using namespace std::chrono_literals;

void sleep_until(MonoTime t) noexcept {
  timespec ts{};
  ts.tv_sec = static_cast<time_t>(t.count() / 1'000'000'000);
  ts.tv_nsec = static_cast<long>(t.count() % 1'000'000'000);
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
}

// Milliseconds for poll(), rounded up so the loop does not spin just before a deadline.
int poll_timeout_ms(MonoTime left) noexcept {
  if (left <= MonoTime::zero()) return 0;
  return static_cast<int>(std::chrono::ceil<std::chrono::milliseconds>(left).count());
}

timespec to_timespec(MonoTime d) noexcept {
  if (d < MonoTime::zero()) d = MonoTime::zero();
  return timespec{static_cast<time_t>(d.count() / 1'000'000'000),
                  static_cast<long>(d.count() % 1'000'000'000)};
}

bool important(const SimEvent& e) noexcept {
  return e.kind == SimEvent::Kind::Fault || e.kind == SimEvent::Kind::FaultCleared ||
         e.kind == SimEvent::Kind::Violation;
}

}  // namespace

std::string_view to_string(RunnerState state) noexcept {
  switch (state) {
    case RunnerState::Idle:
      return "idle";
    case RunnerState::Running:
      return "running";
    case RunnerState::Reconnecting:
      return "reconnecting";
    case RunnerState::DeviceLost:
      return "device-lost";
    case RunnerState::FrameLimit:
      return "frame-limit";
    case RunnerState::Stopped:
      return "stopped";
    case RunnerState::Failed:
      return "failed";
  }
  return "?";
}

std::string format_event(const SimEvent& event, MonoTime epoch) {
  using K = SimEvent::Kind;
  std::string what;
  switch (event.kind) {
    case K::PhaseChanged:
      what = std::string(to_string(static_cast<Phase>(event.value)));
      break;
    case K::TravelStarted:
      what = std::string(to_string(static_cast<TravelKind>(event.value))) + ", start distance " +
             std::to_string(event.detail) + " mm";
      break;
    case K::Fault:
    case K::FaultCleared:
      what = std::string(to_string(static_cast<FaultCause>(event.value)));
      break;
    case K::ChannelMessage:
      what = std::string("I") + static_cast<char>(event.value);
      break;
    case K::Violation:
      what =
          "master broke the spec: " + std::string(to_string(static_cast<Violation>(event.value)));
      break;
    default:
      what = std::to_string(event.value);
      break;
  }
  std::array<char, 32> stamp{};
  std::snprintf(stamp.data(), stamp.size(), "[%10.3f] ",
                std::chrono::duration<double>(event.at - epoch).count());
  return std::string(stamp.data()) + std::string(to_string(event.kind)) + " " + what;
}

std::string format_status(const RunnerStatus& s) {
  std::array<char, 256> line{};
  std::snprintf(line.data(), line.size(),
                "status 0x%02X phase %s pos %.1f mm v %+.3f m/s frames %llu bad %llu repeats "
                "%llu travels %llu resyncs %llu link %s",
                s.status_byte, std::string(to_string(s.phase)).c_str(), s.position_mm,
                s.velocity_mps, static_cast<unsigned long long>(s.sim.frames),
                static_cast<unsigned long long>(s.sim.bad_frames),
                static_cast<unsigned long long>(s.sim.repeats),
                static_cast<unsigned long long>(s.sim.travels),
                static_cast<unsigned long long>(s.runner.resyncs),
                std::string(to_string(s.state)).c_str());
  return std::string(line.data());
}

bool parse_reply_fault(std::string_view name, ReplyFault& out) noexcept {
  if (name == "badsum")
    out = ReplyFault::BadChecksum;
  else if (name == "s7")
    out = ReplyFault::MessageError;
  else if (name == "late")
    out = ReplyFault::Late;
  else if (name == "noreply")
    out = ReplyFault::NoReply;
  else if (name == "garbage")
    out = ReplyFault::Garbage;
  else
    return false;
  return true;
}

SerialDriveRunner::SerialDriveRunner(const DriveConfig& config, RunnerOptions options)
    : config_(config), options_(std::move(options)), epoch_(mono_now()), sim_(config_, epoch_) {
  publish(epoch_);
}

SerialDriveRunner::~SerialDriveRunner() {
  stop();
  if (epoll_fd_ >= 0) ::close(epoll_fd_);
  if (wake_fd_ >= 0) ::close(wake_fd_);
}

bool SerialDriveRunner::start() {
  if (state() != RunnerState::Idle) {
    std::lock_guard lock(mutex_);
    last_error_ = "the runner was started before";
    return false;
  }
  if (options_.fd >= 0) {
    port_ = io::SerialPort::adopt(options_.fd);
    options_.fd = -1;  // owned by port_ now
  } else {
    io::SerialSettings settings;  // DCP 7.1: 38400 8N1
    settings.rs485 = io::Rs485Mode::Auto;
    auto opened = io::SerialPort::open(options_.device, settings);
    if (!opened) {
      std::lock_guard lock(mutex_);
      last_error_ = opened.error().message();
      state_.store(RunnerState::Failed, std::memory_order_release);
      return false;
    }
    port_ = std::move(opened).value();
  }
  {
    std::lock_guard lock(mutex_);
    features_ = port_.features();
  }
  wire_time_ = pty_wire_time(port_.fd());
  wake_fd_ = ::eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
  epoll_fd_ = ::epoll_create1(EPOLL_CLOEXEC);
  const char* failed = wake_fd_ < 0 ? "eventfd" : epoll_fd_ < 0 ? "epoll_create1" : nullptr;
  if (failed == nullptr) {
    epoll_event ev{};
    ev.events = EPOLLIN;
    ev.data.fd = wake_fd_;
    if (::epoll_ctl(epoll_fd_, EPOLL_CTL_ADD, wake_fd_, &ev) != 0 ||
        !port_.watch_input(epoll_fd_)) {
      failed = "epoll_ctl";
    }
  }
  if (failed != nullptr) {
    std::lock_guard lock(mutex_);
    last_error_ = std::string(failed) + ": " + std::system_category().message(errno);
    state_.store(RunnerState::Failed, std::memory_order_release);
    port_.close();
    return false;
  }
  state_.store(RunnerState::Running, std::memory_order_release);
  running_.store(true, std::memory_order_release);
  try {
    thread_ = std::thread([this] { run(); });
  } catch (const std::system_error& e) {
    running_.store(false, std::memory_order_release);
    state_.store(RunnerState::Failed, std::memory_order_release);
    std::lock_guard lock(mutex_);
    last_error_ = std::string("thread: ") + e.what();
    port_.close();
    return false;
  }
  return true;
}

void SerialDriveRunner::stop() noexcept {
  stop_requested_.store(true, std::memory_order_release);
  wake();
  if (thread_.joinable()) thread_.join();
  running_.store(false, std::memory_order_release);
}

void SerialDriveRunner::wake() noexcept {
  if (wake_fd_ < 0) return;
  const std::uint64_t one = 1;
  (void)!::write(wake_fd_, &one, sizeof one);
}

io::PortFeatures SerialDriveRunner::port_features() const {
  std::lock_guard lock(mutex_);
  return features_;
}

std::string SerialDriveRunner::last_error() const {
  std::lock_guard lock(mutex_);
  return last_error_;
}

RunnerStatus SerialDriveRunner::status() const {
  RunnerStatus s;
  s.state = state();
  std::lock_guard lock(mutex_);
  s.phase = sim_.phase();
  s.travel = sim_.travel_kind();
  s.status_byte = sim_.status_byte();
  s.initialised = sim_.initialised();
  s.position_mm = sim_.position_mm();
  s.velocity_mps = sim_.velocity_mps();
  s.sim = sim_.counters();
  s.runner = counters_;
  return s;
}

std::size_t SerialDriveRunner::drain_events(std::vector<SimEvent>& out) {
  std::lock_guard lock(mutex_);
  const std::size_t n = events_.size();
  out.insert(out.end(), events_.begin(), events_.end());
  events_.clear();
  return n;
}

std::size_t SerialDriveRunner::drain_event_lines(std::vector<std::string>& out) {
  std::vector<SimEvent> events;
  drain_events(events);
  for (const auto& e : events) out.push_back(format_event(e, epoch_));
  return events.size();
}

void SerialDriveRunner::set_general_fault(bool on) {
  std::lock_guard lock(mutex_);
  sim_.set_general_fault(on, mono_now());
  collect_events();
}

void SerialDriveRunner::set_advance_warning(bool on) {
  std::lock_guard lock(mutex_);
  sim_.set_advance_warning(on);
}

void SerialDriveRunner::set_not_ready(bool on) {
  std::lock_guard lock(mutex_);
  sim_.set_not_ready(on);
}

void SerialDriveRunner::inject(ReplyFault fault, std::uint32_t frames) {
  std::lock_guard lock(mutex_);
  sim_.inject(fault, frames);
}

void SerialDriveRunner::refuse_next_target() {
  std::lock_guard lock(mutex_);
  sim_.refuse_next_target();
}

void SerialDriveRunner::inject_channel(ChannelFault fault) {
  std::lock_guard lock(mutex_);
  sim_.inject_channel(fault, mono_now());
}

std::chrono::microseconds pty_wire_time(int fd) noexcept {
  struct stat st {};
  if (fd < 0 || ::fstat(fd, &st) != 0 || !S_ISCHR(st.st_mode)) return {};
  // Linux devices.txt: major 5 is /dev/ptmx (the master side), 136..143 the /dev/pts slaves.
  const unsigned major_number = major(st.st_rdev);
  const bool pty = major_number == 5 || (major_number >= 136 && major_number <= 143);
  return pty ? 2 * kFrameWireTime : std::chrono::microseconds{};
}

bool parse_channel_fault(std::string_view name, ChannelFault& out) noexcept {
  if (name == "partial")
    out = ChannelFault::Partial;
  else if (name == "garbage")
    out = ChannelFault::Garbage;
  else if (name == "silence")
    out = ChannelFault::Silence;
  else
    return false;
  return true;
}

void SerialDriveRunner::set_fault_rate(ReplyFault fault, double probability) {
  std::lock_guard lock(mutex_);
  sim_.set_fault_rate(fault, probability);
}

void SerialDriveRunner::clear_reply_faults() {
  std::lock_guard lock(mutex_);
  sim_.clear_reply_faults();
}

void SerialDriveRunner::set_extended_flags(const dcp::ExtendedStatus& flags) {
  std::lock_guard lock(mutex_);
  sim_.set_extended_flags(flags);
}

void SerialDriveRunner::set_position_mm(double position_mm) {
  std::lock_guard lock(mutex_);
  sim_.set_position_mm(position_mm);
  publish(mono_now());
}

// Caller holds mutex_ (or is the constructor).
void SerialDriveRunner::publish(MonoTime now) noexcept {
  EncoderSample sample;
  sample.position_mm = sim_.position_mm();
  sample.velocity_mps = sim_.velocity_mps();
  sample.at = now;
  sample.motion = sim_.trajectory();
  position_mm_.store(sample.position_mm, std::memory_order_relaxed);
  velocity_mps_.store(sample.velocity_mps, std::memory_order_relaxed);
  encoder_.publish(sample);
}

// Caller holds mutex_. Moves the engine's events into the bounded queue.
void SerialDriveRunner::collect_events() noexcept {
  SimEvent e;
  while (sim_.pop_event(e)) {
    if (options_.quiet && !important(e)) continue;
    if (events_.size() >= options_.event_capacity) {
      events_.pop_front();
      ++counters_.dropped_events;
    }
    try {
      events_.push_back(e);
    } catch (...) {
      ++counters_.dropped_events;  // out of memory: the event is lost, the drive runs on
    }
  }
}

void SerialDriveRunner::finish(RunnerState state) noexcept {
  state_.store(state, std::memory_order_release);
}

bool SerialDriveRunner::wait_for_stop(MonoTime until) noexcept {
  while (!stop_requested_.load(std::memory_order_acquire)) {
    const MonoTime now = mono_now();
    if (now >= until) return false;
    pollfd pfd{wake_fd_, POLLIN, 0};
    (void)::poll(&pfd, 1, poll_timeout_ms(until - now));
  }
  return true;
}

// After a loss: waits and retries until the device is back (true) or stop() (false). The car
// model keeps advancing meanwhile (a drive does not freeze when its link does).
bool SerialDriveRunner::reopen() noexcept {
  const bool adopted = options_.device.empty();
  if (!adopted) port_.close();
  for (;;) {
    if (wait_for_stop(mono_now() + options_.reconnect_interval)) return false;
    {
      std::lock_guard lock(mutex_);
      const MonoTime now = mono_now();
      sim_.advance(now);
      publish(now);
      collect_events();
    }
    if (adopted) {
      // An adopted descriptor (a pty master) is back once its hang-up has cleared.
      pollfd pfd{port_.fd(), POLLIN, 0};
      if (::poll(&pfd, 1, 0) < 0) continue;
      if ((pfd.revents & (POLLHUP | POLLERR | POLLNVAL)) != 0) continue;
    } else {
      io::SerialSettings settings;  // DCP 7.1: 38400 8N1
      settings.rs485 = io::Rs485Mode::Auto;
      try {
        auto opened = io::SerialPort::open(options_.device, settings);
        if (!opened) {
          std::lock_guard lock(mutex_);
          last_error_ = opened.error().message();
          continue;
        }
        port_ = std::move(opened).value();
        if (!port_.watch_input(epoll_fd_)) {
          port_.close();
          continue;
        }
        std::lock_guard lock(mutex_);
        features_ = port_.features();
      } catch (...) {
        continue;  // out of memory while building the error text: try again later
      }
    }
    std::lock_guard lock(mutex_);
    ++counters_.reconnects;
    return true;
  }
}

void SerialDriveRunner::run() noexcept {
  if (options_.priority > 0) {
    sched_param param{};
    param.sched_priority = options_.priority;
    const bool realtime = ::pthread_setschedparam(::pthread_self(), SCHED_FIFO, &param) == 0;
    std::lock_guard lock(mutex_);
    counters_.realtime = realtime;
  }
  std::array<std::uint8_t, dcp::kFrameSize> frame{};
  std::size_t have = 0;
  MonoTime last_byte{};
  std::uint64_t frames = 0;
  RunnerState end = RunnerState::Stopped;
  bool hangup = false;  // the tty reported a hang-up: read(2) confirms it (EIO)

  // This thread stands for the drive and its encoder, separate hardware that a busy controller
  // board does not slow down. It never enters read(2) or poll(2) on a tty that holds nothing:
  // both wait there for the tty's flip-buffer worker, a normal-priority kernel thread that
  // other work on the machine can keep from running for hundreds of ms, and the car model and
  // the encoder would stand still meanwhile (docs/architecture.md, "What the cycle may wait
  // for"). It reads what the line discipline holds (TIOCINQ) and sleeps in epoll, which the tty
  // wakes when bytes arrive, until then, the gap of a partial frame, or idle_poll.
  while (!stop_requested_.load(std::memory_order_acquire)) {
    if (options_.max_frames != 0 && frames >= options_.max_frames) {
      end = RunnerState::FrameLimit;
      break;
    }
    std::array<std::uint8_t, 64> buf{};
    io::IoResult r = port_.read_queued(buf);
    if (r.status == io::IoStatus::Ok && r.bytes == 0 && hangup) {
      hangup = false;
      r = port_.read_available(buf);  // EIO on a hung-up tty, never a wait: it is hung up
    }
    const MonoTime now = mono_now();
    bool lost = r.status == io::IoStatus::DeviceLost || r.status == io::IoStatus::Error;
    if (r.bytes == 0 && have > 0 && now - last_byte > options_.gap) {
      have = 0;  // a look found nothing a gap after the last byte: resynchronise
      std::lock_guard lock(mutex_);
      ++counters_.resyncs;
    }
    if (r.bytes > 0 && !lost) {
      // The line as every receiver on it sees it: a collision changes a frame's second byte.
      for (std::size_t i = 0; i < r.bytes; ++i) {
        if ((have + i) % frame.size() != 1) continue;
        std::uint32_t left = collide_.load();
        while (left > 0 && !collide_.compare_exchange_weak(left, left - 1)) {
        }
        if (left == 0) continue;
        buf[i] ^= 0x10;
        std::lock_guard lock(mutex_);
        ++counters_.collisions;
      }
    }
    // The transceiver gives the master its own bytes back as they pass, so on the line a
    // frame's copy always stands before the reply to it, and the next frame's copy after that
    // reply. A look that found two frames (this thread was held up) gives each copy back just
    // before its reply, never both copies ahead of both replies.
    std::size_t echoed = 0;
    const auto echo_through = [&](std::size_t end_of) {
      if (!options_.echo || lost || end_of <= echoed) return;
      if (port_.write_frame(std::span(buf.data() + echoed, end_of - echoed)).status !=
          io::IoStatus::Ok) {
        std::lock_guard lock(mutex_);
        ++counters_.write_failures;
      }
      echoed = end_of;
    };
    for (std::size_t i = 0; i < r.bytes; ++i) {
      frame[have++] = buf[i];
      last_byte = now;
      if (have < frame.size()) continue;
      have = 0;
      echo_through(i + 1);
      Reply reply;
      {
        std::lock_guard lock(mutex_);
        reply = sim_.on_master_frame(frame, now);
        publish(now);
      }
      ++frames;
      if (reply.size > 0 && !lost) {
        sleep_until(now + reply.delay + wire_time_);
        if (port_.write_frame(reply.view()).status != io::IoStatus::Ok) {
          std::lock_guard lock(mutex_);
          ++counters_.write_failures;
        }
      }
    }
    echo_through(r.bytes);  // a partial frame's bytes pass the transceiver too
    {
      std::lock_guard lock(mutex_);
      const MonoTime t = mono_now();
      sim_.advance(t);
      publish(t);
      collect_events();
      if (lost) ++counters_.device_losses;
    }
    if (lost) {
      have = 0;
      hangup = false;
      if (!options_.reconnect) {
        end = RunnerState::DeviceLost;
        break;
      }
      state_.store(RunnerState::Reconnecting, std::memory_order_release);
      if (!reopen()) break;
      state_.store(RunnerState::Running, std::memory_order_release);
      continue;
    }
    if (r.bytes > 0) continue;  // more may have come while this look's bytes were answered
    // Wake for the gap deadline of a partial frame, else after idle_poll for the drive's timers.
    MonoTime wake_at = now + options_.idle_poll;
    if (have > 0)
      wake_at = std::min(wake_at, last_byte + options_.gap + std::chrono::microseconds(1));
    std::array<epoll_event, 2> events{};
    const timespec timeout = to_timespec(wake_at - mono_now());
    const int n = ::epoll_pwait2(epoll_fd_, events.data(), static_cast<int>(events.size()),
                                 &timeout, nullptr);
    for (int i = 0; i < n; ++i) {
      if (events[static_cast<std::size_t>(i)].data.fd == port_.fd() &&
          (events[static_cast<std::size_t>(i)].events & (EPOLLHUP | EPOLLERR)) != 0) {
        hangup = true;
      }
    }
  }
  finish(end);
  running_.store(false, std::memory_order_release);
}

}  // namespace liftd::dcp::sim
