// A pseudo-terminal pair standing in for an RS485 link: the daemon opens the slave path as its
// serial port, a simulator (or test responder) talks through the master descriptor.
#pragma once

#include <string>

#include "io/expected.hpp"
#include "io/serial_port.hpp"

namespace liftd::io {

/// A pty master plus the path of its slave, both ends in raw mode. Move-only; closes on
/// destruction. By default a slave descriptor is held open too, so the master does not see a
/// hang-up while the daemon closes and reopens the slave.
class PtyPair {
 public:
  /// Takes the other pair's descriptors.
  PtyPair(PtyPair&& other) noexcept;
  /// Closes this pair, then takes the other's descriptors.
  PtyPair& operator=(PtyPair&& other) noexcept;
  PtyPair(const PtyPair&) = delete;
  PtyPair& operator=(const PtyPair&) = delete;
  /// Closes both ends.
  ~PtyPair();

  /// posix_openpt + grantpt + unlockpt, raw mode with `settings` on both ends. With
  /// `hold_slave`, keeps a slave descriptor open for the pair's lifetime.
  static Expected<PtyPair, OpenError> create(const SerialSettings& settings = {},
                                             bool hold_slave = true);

  /// The master descriptor (non-blocking); -1 after take_master()/close().
  int master_fd() const noexcept { return master_fd_; }
  /// Path of the slave, e.g. /dev/pts/7.
  const std::string& slave_path() const noexcept { return slave_path_; }

  /// Moves the master descriptor into a SerialPort (for read_until/write_frame on it).
  SerialPort take_master() noexcept;

  /// Closes the master (the slave side then sees a hang-up) and the held slave descriptor.
  void close() noexcept;

 private:
  PtyPair() = default;

  int master_fd_ = -1;
  int held_slave_fd_ = -1;
  std::string slave_path_;
};

}  // namespace liftd::io
