#include "io/serial_port.hpp"

// termios2 (arbitrary baud rates via BOTHER) lives in the kernel headers and clashes with
// glibc's <termios.h>, so this file talks to the tty through ioctl only.
#include <asm/termbits.h>
#include <fcntl.h>
#include <linux/serial.h>
#include <poll.h>
#include <sys/epoll.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <condition_variable>
#include <cstring>
#include <ctime>
#include <memory>
#include <mutex>
#include <thread>
#include <utility>

namespace liftd::io {
namespace {

struct BaudCode {
  std::uint32_t baud;
  unsigned code;
};

// Rates with a classic Bxxx code; any other rate (USS 187500) goes through BOTHER.
constexpr std::array<BaudCode, 13> kStandardBauds = {{{1200, B1200},
                                                      {2400, B2400},
                                                      {4800, B4800},
                                                      {9600, B9600},
                                                      {19200, B19200},
                                                      {38400, B38400},
                                                      {57600, B57600},
                                                      {115200, B115200},
                                                      {230400, B230400},
                                                      {460800, B460800},
                                                      {500000, B500000},
                                                      {921600, B921600},
                                                      {1000000, B1000000}}};

unsigned baud_code(std::uint32_t baud) noexcept {
  for (const auto& b : kStandardBauds) {
    if (b.baud == baud) return b.code;
  }
  return BOTHER;
}

timespec to_timespec(std::chrono::nanoseconds d) noexcept {
  const auto ns = d.count();
  constexpr std::int64_t kNsPerS = 1'000'000'000;
  return timespec{static_cast<time_t>(ns / kNsPerS), static_cast<long>(ns % kNsPerS)};
}

// Absolute sleep on the monotonic clock (no drift from a wake-up's own lateness).
void sleep_until(MonoTime t) noexcept {
  const timespec ts = to_timespec(t);
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
}

IoResult lost_or_error(int error_number, std::size_t bytes) noexcept {
  return IoResult{is_device_lost_errno(error_number) ? IoStatus::DeviceLost : IoStatus::Error,
                  bytes, error_number};
}

}  // namespace

std::string OpenError::message() const {
  std::string text = device + ": " + call;
  if (error_number != 0) {
    text += ": ";
    text += std::strerror(error_number);
  }
  if (!detail.empty()) text += " (" + detail + ")";
  return text;
}

std::string_view to_string(IoStatus status) noexcept {
  switch (status) {
    case IoStatus::Ok:
      return "ok";
    case IoStatus::Timeout:
      return "timeout";
    case IoStatus::WouldBlock:
      return "would-block";
    case IoStatus::DeviceLost:
      return "device-lost";
    case IoStatus::Error:
      return "error";
  }
  return "unknown";
}

bool is_device_lost_errno(int error_number) noexcept {
  // EIO: hung-up tty or pty whose other end closed; ENODEV/ENXIO: USB adapter unplugged;
  // EPIPE/ESHUTDOWN: the driver tore the port down.
  return error_number == EIO || error_number == ENODEV || error_number == ENXIO ||
         error_number == EPIPE || error_number == ESHUTDOWN;
}

std::chrono::nanoseconds character_time(const SerialSettings& settings) noexcept {
  const std::int64_t bits =
      1 + settings.data_bits + (settings.parity != Parity::None ? 1 : 0) + settings.stop_bits;
  const std::int64_t baud = settings.baud > 0 ? settings.baud : 1;
  return std::chrono::nanoseconds(bits * 1'000'000'000 / baud);
}

int configure_tty(int fd, const SerialSettings& settings, const char** failed_call) noexcept {
  const char* ignored = nullptr;
  const char** call = failed_call != nullptr ? failed_call : &ignored;
  if (settings.data_bits < 5 || settings.data_bits > 8 || settings.stop_bits < 1 ||
      settings.stop_bits > 2 || settings.baud == 0) {
    *call = "settings";
    return EINVAL;
  }
  termios2 tio{};
  if (ioctl(fd, TCGETS2, &tio) != 0) {
    *call = "TCGETS2";
    return errno;
  }
  // Raw mode: no break/parity marking, no CR/NL mapping, no flow control, no echo, no signals.
  tio.c_iflag &= ~static_cast<tcflag_t>(IGNBRK | BRKINT | PARMRK | ISTRIP | INLCR | IGNCR | ICRNL |
                                        IXON | IXOFF | IXANY | INPCK | IGNPAR);
  tio.c_oflag &= ~static_cast<tcflag_t>(OPOST);
  tio.c_lflag &= ~static_cast<tcflag_t>(ECHO | ECHONL | ICANON | ISIG | IEXTEN);
  tio.c_cflag &= ~static_cast<tcflag_t>(CSIZE | PARENB | PARODD | CSTOPB | CRTSCTS | CBAUD |
                                        (CBAUD << IBSHIFT));
  tio.c_cflag |= CLOCAL | CREAD;
  switch (settings.data_bits) {
    case 5:
      tio.c_cflag |= CS5;
      break;
    case 6:
      tio.c_cflag |= CS6;
      break;
    case 7:
      tio.c_cflag |= CS7;
      break;
    default:
      tio.c_cflag |= CS8;
      break;
  }
  if (settings.parity != Parity::None) {
    tio.c_cflag |= PARENB;
    if (settings.parity == Parity::Odd) tio.c_cflag |= PARODD;
    if (!settings.mark_errors) {
      // A character with a parity error is dropped, so the frame comes up short and is lost.
      tio.c_iflag |= INPCK | IGNPAR;
    }
  }
  if (settings.mark_errors) {
    // Parity and framing errors arrive as 0xFF 0x00 c, a break as 0xFF 0x00 0x00 (no IGNBRK,
    // no BRKINT: no signal, no flush), a data 0xFF doubled. INPCK also with no parity bit, so
    // framing errors are marked too.
    tio.c_iflag |= INPCK | PARMRK;
  }
  if (settings.stop_bits == 2) tio.c_cflag |= CSTOPB;
  const unsigned code = baud_code(settings.baud);
  tio.c_cflag |= code | (code << IBSHIFT);
  tio.c_ispeed = settings.baud;
  tio.c_ospeed = settings.baud;
  // Non-canonical: a read returns what is there; poll reports readable from the first byte.
  tio.c_cc[VMIN] = 1;
  tio.c_cc[VTIME] = 0;
  if (ioctl(fd, TCSETS2, &tio) != 0) {
    *call = "TCSETS2";
    return errno;
  }
  return 0;
}

int read_line_counts(int fd, LineCounts& out) noexcept {
  serial_icounter_struct counts{};
  if (ioctl(fd, TIOCGICOUNT, &counts) != 0) return errno;
  auto u = [](int v) { return static_cast<std::uint64_t>(static_cast<unsigned>(v)); };
  out.rx = u(counts.rx);
  out.tx = u(counts.tx);
  out.frame = u(counts.frame);
  out.parity = u(counts.parity);
  out.overrun = u(counts.overrun);
  out.brk = u(counts.brk);
  out.buf_overrun = u(counts.buf_overrun);
  return 0;
}

SerialPort::SerialPort(SerialPort&& other) noexcept
    : fd_(std::exchange(other.fd_, -1)),
      features_(other.features_),
      looks_(std::exchange(other.looks_, 0)) {}

SerialPort& SerialPort::operator=(SerialPort&& other) noexcept {
  if (this != &other) {
    close();
    fd_ = std::exchange(other.fd_, -1);
    features_ = other.features_;
    looks_ = std::exchange(other.looks_, 0);
  }
  return *this;
}

SerialPort::~SerialPort() {
  close();
}

Expected<SerialPort, OpenError> SerialPort::open(std::string_view path,
                                                 const SerialSettings& settings) {
  const std::string device(path);
  auto fail = [&device](const char* call, int error_number, std::string detail = {}) {
    return OpenError{device, call, error_number, std::move(detail)};
  };
  const int fd = ::open(device.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) return fail("open", errno);
  SerialPort port(fd);
  if (ioctl(fd, TIOCEXCL) != 0) return fail("TIOCEXCL", errno);
  const char* call = nullptr;
  if (const int err = configure_tty(fd, settings, &call); err != 0) {
    return fail(call, err,
                err == EINVAL ? "baud " + std::to_string(settings.baud) + " or framing refused"
                              : std::string{});
  }
  termios2 check{};
  if (ioctl(fd, TCGETS2, &check) != 0) return fail("TCGETS2", errno);
  // The driver rounds the rate to what its clock divider can make; more than 3 % off means
  // the characters are not readable by the other end (a UART samples mid-bit).
  const auto got = static_cast<double>(check.c_ospeed);
  const auto want = static_cast<double>(settings.baud);
  if (got < want * 0.97 || got > want * 1.03) {
    return fail("TCSETS2", 0,
                "driver set " + std::to_string(check.c_ospeed) + " baud instead of " +
                    std::to_string(settings.baud));
  }

  if (settings.rs485 != Rs485Mode::Off) {
    serial_rs485 rs{};
    int err = 0;
    if (ioctl(fd, TIOCGRS485, &rs) != 0) err = errno;
    if (err == 0) {
      // Driver enable (RTS) high while sending, low after; no extra delays (the DCP budget
      // of DCP 7.2 has no room for them).
      rs.flags |= SER_RS485_ENABLED | SER_RS485_RTS_ON_SEND;
      rs.flags &= ~static_cast<std::uint32_t>(SER_RS485_RTS_AFTER_SEND | SER_RS485_RX_DURING_TX);
      rs.delay_rts_before_send = 0;
      rs.delay_rts_after_send = 0;
      if (ioctl(fd, TIOCSRS485, &rs) != 0) err = errno;
    }
    if (err != 0) {
      if (settings.rs485 == Rs485Mode::Required) {
        return fail("TIOCSRS485", err, "rs485 mode required by the settings");
      }
      port.features_.rs485_errno = err;
    } else {
      port.features_.rs485_enabled = true;
    }
  }

  if (settings.low_latency) {
    serial_struct ss{};
    int err = 0;
    if (ioctl(fd, TIOCGSERIAL, &ss) != 0) err = errno;
    if (err == 0) {
      ss.flags |= static_cast<int>(ASYNC_LOW_LATENCY);
      if (ioctl(fd, TIOCSSERIAL, &ss) != 0) err = errno;
    }
    port.features_.low_latency_enabled = err == 0;
    port.features_.low_latency_errno = err;
  }

  if (ioctl(fd, TCFLSH, TCIOFLUSH) != 0) return fail("TCFLSH", errno);
  return port;
}

SerialPort SerialPort::adopt(int fd) noexcept {
  const int flags = fcntl(fd, F_GETFL);
  if (flags >= 0) fcntl(fd, F_SETFL, flags | O_NONBLOCK);
  return SerialPort(fd);
}

IoResult SerialPort::write_frame(std::span<const std::uint8_t> frame) noexcept {
  std::size_t done = 0;
  while (done < frame.size()) {
    const ssize_t n = ::write(fd_, frame.data() + done, frame.size() - done);
    if (n > 0) {
      done += static_cast<std::size_t>(n);
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && errno != EAGAIN) return lost_or_error(errno, done);
    return IoResult{IoStatus::WouldBlock, done, 0};
  }
  return IoResult{IoStatus::Ok, done, 0};
}

IoResult SerialPort::read_available(std::span<std::uint8_t> buffer) noexcept {
  std::size_t got = 0;
  while (got < buffer.size()) {
    const ssize_t n = ::read(fd_, buffer.data() + got, buffer.size() - got);
    if (n > 0) {
      got += static_cast<std::size_t>(n);
      continue;
    }
    if (n == 0) return IoResult{IoStatus::DeviceLost, got, 0};  // EOF: hung up
    if (errno == EINTR) continue;
    if (errno == EAGAIN) break;
    return lost_or_error(errno, got);
  }
  return IoResult{IoStatus::Ok, got, 0};
}

IoResult SerialPort::wait_readable(MonoTime deadline) noexcept {
  for (;;) {
    const MonoTime left = deadline - mono_now();
    if (left <= MonoTime::zero()) return IoResult{IoStatus::Timeout, 0, 0};
    pollfd pfd{fd_, POLLIN, 0};
    const timespec ts = to_timespec(left);
    const int r = ppoll(&pfd, 1, &ts, nullptr);
    if (r < 0) {
      if (errno == EINTR) continue;
      return lost_or_error(errno, 0);
    }
    if (r == 0) return IoResult{IoStatus::Timeout, 0, 0};
    // A hung-up tty also reports POLLIN (its read answers EIO): the hang-up decides.
    if ((pfd.revents & (POLLHUP | POLLERR | POLLNVAL)) != 0) {
      return IoResult{IoStatus::DeviceLost, 0, EIO};
    }
    if ((pfd.revents & POLLIN) != 0) return IoResult{IoStatus::Ok, 0, 0};
  }
}

IoResult SerialPort::read_until(std::span<std::uint8_t> buffer, MonoTime deadline) noexcept {
  std::size_t got = 0;
  while (got < buffer.size()) {
    const IoResult r = read_available(buffer.subspan(got));
    got += r.bytes;
    if (r.status != IoStatus::Ok) return IoResult{r.status, got, r.error_number};
    if (got == buffer.size()) break;
    const IoResult w = wait_readable(deadline);
    if (w.status != IoStatus::Ok) return IoResult{w.status, got, w.error_number};
  }
  return IoResult{IoStatus::Ok, got, 0};
}

bool SerialPort::watch_input(int epoll_fd) const noexcept {
  epoll_event ev{};
  ev.events = EPOLLIN | EPOLLET;
  ev.data.fd = fd_;
  return ::epoll_ctl(epoll_fd, EPOLL_CTL_ADD, fd_, &ev) == 0;
}

IoResult SerialPort::input_queued() const noexcept {
  int queued = 0;
  // TIOCINQ (= FIONREAD): n_tty counts its read buffer under the termios lock; it neither
  // flushes the flip-buffer work nor sleeps for input.
  if (ioctl(fd_, TIOCINQ, &queued) != 0) return lost_or_error(errno, 0);
  return IoResult{IoStatus::Ok, queued > 0 ? static_cast<std::size_t>(queued) : 0, 0};
}

IoResult SerialPort::read_queued(std::span<std::uint8_t> buffer) noexcept {
  const IoResult queued = input_queued();
  if (queued.status != IoStatus::Ok || queued.bytes == 0 || buffer.empty()) {
    return IoResult{queued.status, 0, queued.error_number};
  }
  const std::size_t want = std::min(queued.bytes, buffer.size());
  for (;;) {
    // n_tty_read returns what it holds once it has one byte (VMIN 1): it never reaches its
    // flush of the worker while the bytes asked for are there.
    const ssize_t n = ::read(fd_, buffer.data(), want);
    if (n > 0) return IoResult{IoStatus::Ok, static_cast<std::size_t>(n), 0};
    if (n == 0) return IoResult{IoStatus::DeviceLost, 0, 0};  // EOF: hung up
    if (errno == EINTR) continue;
    if (errno == EAGAIN) return IoResult{IoStatus::Ok, 0, 0};
    return lost_or_error(errno, 0);
  }
}

IoResult SerialPort::wait_queued(MonoTime deadline, std::chrono::nanoseconds step) noexcept {
  if (step.count() <= 0) step = std::chrono::microseconds(100);
  for (;;) {
    const IoResult queued = input_queued();
    ++looks_;
    if (queued.status != IoStatus::Ok) return IoResult{queued.status, 0, queued.error_number};
    if (queued.bytes > 0) return IoResult{IoStatus::Ok, 0, 0};
    const MonoTime now = mono_now();
    if (now >= deadline) return IoResult{IoStatus::Timeout, 0, 0};
    sleep_until(std::min(deadline, now + step));
  }
}

IoResult SerialPort::read_queued_until(std::span<std::uint8_t> buffer, MonoTime deadline,
                                       std::chrono::nanoseconds step, MonoTime* complete_by,
                                       MonoTime first_look) noexcept {
  if (step.count() <= 0) step = std::chrono::microseconds(100);
  std::size_t got = 0;
  if (first_look > mono_now()) sleep_until(std::min(deadline, first_look));
  for (;;) {
    // The time a look starts is the time its bytes are known to be there by.
    const MonoTime look = mono_now();
    const IoResult r = read_queued(buffer.subspan(got));
    ++looks_;
    got += r.bytes;
    if (r.status != IoStatus::Ok) return IoResult{r.status, got, r.error_number};
    if (got == buffer.size()) {
      if (complete_by != nullptr) *complete_by = look;
      // Complete, but only a look started by the deadline proves it was complete in time.
      return IoResult{look <= deadline ? IoStatus::Ok : IoStatus::Timeout, got, 0};
    }
    if (r.bytes > 0) continue;  // more may be queued behind what the first look saw
    if (look >= deadline) return IoResult{IoStatus::Timeout, got, 0};
    // The line carries at most one character per character time (`step`): the bytes still
    // missing cannot all be there before that many character times from this look. A look
    // earlier finds the buffer short, whatever the drive does; the deadline gets its own look.
    const auto missing = static_cast<std::int64_t>(buffer.size() - got);
    sleep_until(std::min(deadline, look + step * missing));
  }
}

IoResult SerialPort::drain_queued() noexcept {
  std::array<std::uint8_t, 64> sink{};
  std::size_t dropped = 0;
  for (;;) {
    const IoResult r = read_queued(sink);
    dropped += r.bytes;
    if (r.status != IoStatus::Ok) return IoResult{r.status, dropped, r.error_number};
    if (r.bytes == 0) return IoResult{IoStatus::Ok, dropped, 0};
  }
}

IoResult SerialPort::flush_queued() noexcept {
  const IoResult held = input_queued();
  if (held.status != IoStatus::Ok) return IoResult{held.status, 0, held.error_number};
  if (ioctl(fd_, TCFLSH, TCIFLUSH) != 0) return lost_or_error(errno, 0);
  const IoResult rest = drain_queued();
  return IoResult{rest.status, held.bytes + rest.bytes, rest.error_number};
}

IoResult SerialPort::flush_input() noexcept {
  // Count what the flush throws away, for the stray-byte statistics.
  int queued = 0;
  if (ioctl(fd_, FIONREAD, &queued) != 0) queued = 0;
  if (ioctl(fd_, TCFLSH, TCIFLUSH) != 0) return lost_or_error(errno, 0);
  std::array<std::uint8_t, 64> sink{};
  std::size_t dropped = queued > 0 ? static_cast<std::size_t>(queued) : 0;
  for (;;) {
    const IoResult r = read_available(sink);
    dropped += r.bytes;
    if (r.status != IoStatus::Ok) return IoResult{r.status, dropped, r.error_number};
    if (r.bytes < sink.size()) break;
  }
  // A hung-up tty with nothing to read still answers EAGAIN on some drivers; poll tells.
  pollfd pfd{fd_, POLLIN, 0};
  if (poll(&pfd, 1, 0) > 0 && (pfd.revents & (POLLHUP | POLLERR | POLLNVAL)) != 0) {
    return IoResult{IoStatus::DeviceLost, dropped, EIO};
  }
  return IoResult{IoStatus::Ok, dropped, 0};
}

void SerialPort::close() noexcept {
  if (fd_ >= 0) {
    close_port_fd(fd_);
    fd_ = -1;
  }
}

int SerialPort::release() noexcept {
  return std::exchange(fd_, -1);
}

bool close_port_fd(int fd, std::chrono::milliseconds limit,
                   const std::function<int(int)>& closer) noexcept {
  if (fd < 0) return true;
  // A hung-up or lost device refuses these; its close does not wait either.
  ::ioctl(fd, TCFLSH, TCOFLUSH);
  int pending = 0;
  if (!closer && (::ioctl(fd, TIOCOUTQ, &pending) != 0 || pending <= 0)) {
    ::close(fd);
    return true;
  }
  struct Done {
    std::mutex mutex;
    std::condition_variable cv;
    bool done = false;
  };
  try {
    std::function<int(int)> close_fn = closer ? closer : [](int f) { return ::close(f); };
    auto state = std::make_shared<Done>();
    // The thread owns copies of everything it touches: it may outlive this call.
    std::thread([fd, state, close_fn = std::move(close_fn)] {
      close_fn(fd);
      const std::lock_guard lock(state->mutex);
      state->done = true;
      state->cv.notify_all();
    }).detach();
    std::unique_lock lock(state->mutex);
    return state->cv.wait_for(lock, limit, [&] { return state->done; });
  } catch (...) {
    if (closer) {
      closer(fd);
    } else {
      ::close(fd);  // no thread to spare: close here, as before
    }
    return true;
  }
}

}  // namespace liftd::io
