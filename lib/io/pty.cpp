#include "io/pty.hpp"

#include <fcntl.h>
#include <stdlib.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <utility>

namespace liftd::io {

PtyPair::PtyPair(PtyPair&& other) noexcept
    : master_fd_(std::exchange(other.master_fd_, -1)),
      held_slave_fd_(std::exchange(other.held_slave_fd_, -1)),
      slave_path_(std::move(other.slave_path_)) {}

PtyPair& PtyPair::operator=(PtyPair&& other) noexcept {
  if (this != &other) {
    close();
    master_fd_ = std::exchange(other.master_fd_, -1);
    held_slave_fd_ = std::exchange(other.held_slave_fd_, -1);
    slave_path_ = std::move(other.slave_path_);
  }
  return *this;
}

PtyPair::~PtyPair() {
  close();
}

Expected<PtyPair, OpenError> PtyPair::create(const SerialSettings& settings, bool hold_slave) {
  PtyPair pair;
  auto fail = [&pair](const char* call, int error_number) {
    return OpenError{pair.slave_path_.empty() ? std::string("/dev/ptmx") : pair.slave_path_,
                     call,
                     error_number,
                     {}};
  };
  pair.master_fd_ = posix_openpt(O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (pair.master_fd_ < 0) return fail("posix_openpt", errno);
  if (grantpt(pair.master_fd_) != 0) return fail("grantpt", errno);
  if (unlockpt(pair.master_fd_) != 0) return fail("unlockpt", errno);
  std::array<char, 128> name{};
  if (const int err = ptsname_r(pair.master_fd_, name.data(), name.size()); err != 0) {
    return fail("ptsname_r", err);
  }
  pair.slave_path_ = name.data();
  // The pty carries no real line, so the rate is only recorded; raw mode is what matters.
  SerialSettings raw = settings;
  raw.rs485 = Rs485Mode::Off;
  const char* call = nullptr;
  if (const int err = configure_tty(pair.master_fd_, raw, &call); err != 0) return fail(call, err);
  const int slave = ::open(pair.slave_path_.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (slave < 0) return fail("open", errno);
  if (const int err = configure_tty(slave, raw, &call); err != 0) {
    ::close(slave);
    return fail(call, err);
  }
  if (hold_slave) {
    pair.held_slave_fd_ = slave;
  } else {
    ::close(slave);
  }
  return pair;
}

SerialPort PtyPair::take_master() noexcept {
  return SerialPort::adopt(std::exchange(master_fd_, -1));
}

void PtyPair::close() noexcept {
  if (master_fd_ >= 0) ::close(std::exchange(master_fd_, -1));
  if (held_slave_fd_ >= 0) ::close(std::exchange(held_slave_fd_, -1));
}

}  // namespace liftd::io
