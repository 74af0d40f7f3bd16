// An RS485/RS232 serial port (termios) with non-blocking writes and deadline reads.
// Opening may allocate and reports rich errors; everything after open is noexcept, allocation
// free and suitable for the real-time cycle.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <string_view>

#include "common/mono_time.hpp"
#include "io/expected.hpp"

namespace liftd::io {

/// Parity bit of each character.
enum class Parity : std::uint8_t {
  None,  ///< no parity bit (DCP 7.1: 8N1)
  Even,  ///< even parity (USS: 8E1)
  Odd,   ///< odd parity
};

/// How the kernel's RS485 mode (TIOCSRS485: driver enable on RTS while sending) is used.
enum class Rs485Mode : std::uint8_t {
  Auto,      ///< enable it where the driver supports it; carry on without it otherwise
  Required,  ///< enable it or fail to open
  Off,       ///< leave the port's RS485 setting alone (RS232 adapters, auto-direction RS485)
};

/// Line settings of a serial port.
struct SerialSettings {
  std::uint32_t baud = 38400;         ///< DCP 7.1: 38400 baud; any rate via termios2/BOTHER
  std::uint8_t data_bits = 8;         ///< 5..8
  Parity parity = Parity::None;       ///< DCP: none; USS: even
  std::uint8_t stop_bits = 1;         ///< 1 or 2
  Rs485Mode rs485 = Rs485Mode::Auto;  ///< kernel RS485 mode policy
  bool low_latency = true;            ///< ask the driver for ASYNC_LOW_LATENCY where it has it
  /// Deliver characters received with a parity or framing error, and breaks, marked in the
  /// data stream instead of dropping them (termios INPCK | PARMRK, without IGNPAR, IGNBRK and
  /// BRKINT): a bad character c arrives as 0xFF 0x00 c, a break as 0xFF 0x00 0x00 and a data
  /// byte 0xFF as 0xFF 0xFF. The reader must undo the marking (uss::ParmrkDecoder); USS A 5.2.2
  /// counts parity and framing errors. Off: such characters are dropped (IGNPAR) and 0xFF is
  /// plain data.
  bool mark_errors = false;
};

/// The UART's own error counters (TIOCGICOUNT), counting since the driver loaded.
struct LineCounts {
  std::uint64_t rx = 0;           ///< characters received
  std::uint64_t tx = 0;           ///< characters sent
  std::uint64_t frame = 0;        ///< framing errors
  std::uint64_t parity = 0;       ///< parity errors
  std::uint64_t overrun = 0;      ///< UART receive overruns (characters lost in hardware)
  std::uint64_t brk = 0;          ///< breaks received
  std::uint64_t buf_overrun = 0;  ///< tty buffer overruns (characters lost in the kernel)
};

/// Reads the driver's line counters of a tty into `out`. Returns 0, or an errno: EINVAL or
/// ENOTTY when the driver keeps none (a pty never has them). No allocation, never blocks.
int read_line_counts(int fd, LineCounts& out) noexcept;

/// Why an open (or pty creation) failed: the device, the call that failed and errno.
struct OpenError {
  std::string device;    ///< path that was opened
  std::string call;      ///< the failing call, e.g. "open", "TCSETS2", "TIOCSRS485"
  int error_number = 0;  ///< errno of the failing call (0 when the failure is not a syscall's)
  std::string detail;    ///< extra words when errno alone does not explain it (may be empty)

  /// One readable line: "<device>: <call>: <strerror>[ (<detail>)]".
  std::string message() const;
};

/// What the port ended up with after open, for the non-real-time side to log once.
struct PortFeatures {
  bool rs485_enabled = false;        ///< kernel RS485 mode is on (RTS on send, no delays)
  int rs485_errno = 0;               ///< why it is off in Auto mode (ENOTTY: driver lacks it)
  bool low_latency_enabled = false;  ///< ASYNC_LOW_LATENCY is set
  int low_latency_errno = 0;         ///< why it is not (ENOTTY/EINVAL: driver lacks it)
};

/// Outcome class of one I/O call.
enum class IoStatus : std::uint8_t {
  Ok,          ///< done: all bytes written / buffer filled / flushed
  Timeout,     ///< deadline passed before the buffer was full (bytes says how many arrived)
  WouldBlock,  ///< the kernel buffer is full: only part of the frame was written
  DeviceLost,  ///< the device is gone or hung up (EIO, ENODEV, ENXIO, POLLHUP/POLLERR, EOF)
  Error,       ///< any other failure (error_number has errno)
};

/// Result of one I/O call.
struct IoResult {
  IoStatus status = IoStatus::Ok;  ///< outcome
  std::size_t bytes = 0;           ///< bytes moved
  int error_number = 0;            ///< errno for DeviceLost / Error, else 0
};

/// Short name of an I/O status for logs ("ok", "timeout", ...).
std::string_view to_string(IoStatus status) noexcept;

/// An open serial port; move-only, closes on destruction. The file descriptor is non-blocking.
class SerialPort {
 public:
  /// A closed port.
  SerialPort() noexcept = default;
  /// Takes the other port's descriptor; the other is closed afterwards.
  SerialPort(SerialPort&& other) noexcept;
  /// Closes this port, then takes the other's descriptor.
  SerialPort& operator=(SerialPort&& other) noexcept;
  SerialPort(const SerialPort&) = delete;
  SerialPort& operator=(const SerialPort&) = delete;
  /// Closes the descriptor.
  ~SerialPort();

  /// Opens `path` exclusively (TIOCEXCL), in raw mode with `settings`, flushes both directions,
  /// applies the RS485 and low-latency policy. Errors name the device, the call and errno.
  static Expected<SerialPort, OpenError> open(std::string_view path,
                                              const SerialSettings& settings);

  /// Takes ownership of an already configured descriptor (e.g. a pty master) and makes it
  /// non-blocking. No termios changes.
  static SerialPort adopt(int fd) noexcept;

  /// True while a descriptor is held.
  bool is_open() const noexcept { return fd_ >= 0; }
  /// The descriptor (for poll loops of callers); -1 when closed.
  int fd() const noexcept { return fd_; }
  /// What RS485 / low-latency settings took effect at open.
  const PortFeatures& features() const noexcept { return features_; }

  /// Writes the whole frame without blocking. Ok when every byte went to the kernel.
  IoResult write_frame(std::span<const std::uint8_t> frame) noexcept;

  /// Reads until `buffer` is full or the monotonic `deadline` passes (ppoll). Ok when full,
  /// Timeout with the partial count otherwise, DeviceLost on hang-up.
  IoResult read_until(std::span<std::uint8_t> buffer, MonoTime deadline) noexcept;

  /// Reads whatever is available now, without waiting (up to buffer.size()).
  IoResult read_available(std::span<std::uint8_t> buffer) noexcept;

  // The real-time side reads through the four calls below. On Linux, read(2) and poll(2) on a
  // tty whose line discipline holds no data call tty_buffer_flush_work(): they wait for the
  // tty's flip-buffer work item, which a kernel worker at normal priority runs, so a real-time
  // thread there waits for whatever normal threads fill the CPUs (priority inversion through
  // the kernel; docs/architecture.md, "What the cycle may wait for"). TCFLSH takes the flip
  // buffer's lock, which that worker holds while it delivers. These calls never do either: they
  // ask TIOCINQ (FIONREAD) how much the line discipline holds and read only that, and they wait
  // with absolute clock_nanosleep() between two looks. A byte that has not reached the line
  // discipline by the deadline is not seen: for the protocol it is late (DCP 7.3, USS A 5.2.1).

  /// Bytes the line discipline holds now (TIOCINQ), in `bytes`. Never waits for the flip-buffer
  /// worker. DeviceLost on a hung-up tty (EIO), e.g. a pty whose master closed.
  IoResult input_queued() const noexcept;

  /// Adds this port to `epoll_fd` as an edge-triggered input watch (data: the port's fd). epoll
  /// then looks at the tty only when the line discipline has just woken its readers, i.e. when
  /// it holds bytes; a level-triggered watch, like poll(2), looks again while it holds nothing,
  /// and that look waits for the flip-buffer worker (docs/architecture.md, "What the cycle may
  /// wait for"). Pair it with read_queued() until that returns 0. False with errno on failure.
  bool watch_input(int epoll_fd) const noexcept;

  /// Reads what the line discipline already holds, at most buffer.size() bytes, without ever
  /// entering read(2) with nothing queued. Ok with the count (0: nothing there).
  IoResult read_queued(std::span<std::uint8_t> buffer) noexcept;

  /// Waits until the line discipline holds input or `deadline` passes, looking every `step`
  /// (absolute sleeps; the last look is at the deadline). Ok, Timeout or DeviceLost.
  IoResult wait_queued(MonoTime deadline, std::chrono::nanoseconds step) noexcept;

  /// Looks at the line discipline wait_queued() and read_queued_until() made so far: each is a
  /// wake-up of the calling thread (a cycle's cost on a small board, issue #43).
  std::uint64_t looks() const noexcept { return looks_; }

  /// read_until() through read_queued(): fills `buffer` from what the line discipline holds
  /// until `deadline`, with absolute sleeps between looks. `step` is one character time: after
  /// a look that left n bytes missing, the next is n character times later (no line delivers
  /// them sooner), the last at the deadline. Ok when a look started by the deadline completed it;
  /// Timeout otherwise, with the count (buffer.size() when it was complete only at a look after the
  /// deadline: a late reply); DeviceLost on hang-up. When complete, `complete_by` (if given) gets
  /// the start of the look that completed it: the bytes were there by then, however long this
  /// thread was held up before it returned. The first look is at `first_look` (or the
  /// deadline, if sooner): before it the bytes cannot all be there (the cycle knows when a
  /// reply can first be complete); the default looks at once.
  IoResult read_queued_until(std::span<std::uint8_t> buffer, MonoTime deadline,
                             std::chrono::nanoseconds step, MonoTime* complete_by = nullptr,
                             MonoTime first_look = MonoTime{}) noexcept;

  /// Reads away everything the line discipline holds (stray bytes before a new request);
  /// `bytes` says how many. Unlike flush_input() no TCFLSH and no poll(2): bytes still in the
  /// flip buffer are not dropped (they arrive later and make that reply bad or late, which
  /// the link counts). DeviceLost on hang-up.
  IoResult drain_queued() noexcept;

  /// Discards input with TCFLSH (TCIFLUSH: the line discipline and the flip buffer, so bytes a
  /// late reply left on their way are gone too), then drain_queued(); `bytes` counts what the
  /// line discipline held. No read(2) or poll(2) of an empty tty, but TCFLSH takes the flip
  /// buffer's lock, which the worker holds while it delivers: use it only where stray bytes
  /// may be on their way (after a missing or bad reply), drain_queued() otherwise.
  IoResult flush_queued() noexcept;

  /// Discards unread input (tcflush TCIFLUSH), then reads away anything still queued.
  /// `bytes` says how many were dropped. Reports DeviceLost when the device has gone.
  IoResult flush_input() noexcept;

  /// Waits until the port is readable or `deadline` passes. Ok (readable), Timeout, or
  /// DeviceLost as soon as the device reports a hang-up or error (even with data pending).
  IoResult wait_readable(MonoTime deadline) noexcept;

  /// The driver's line error counters (read_line_counts()); 0 or an errno (EINVAL/ENOTTY:
  /// not kept by this driver, e.g. a pty; EBADF: closed).
  int line_counts(LineCounts& out) const noexcept { return read_line_counts(fd_, out); }

  /// Closes the descriptor (no-op when closed) with close_port_fd(): output still pending is
  /// discarded, and a close the line cannot finish is left behind after kPortCloseLimit.
  void close() noexcept;

  /// Gives the descriptor up without closing it; the port is closed afterwards.
  int release() noexcept;

 private:
  explicit SerialPort(int fd) noexcept : fd_(fd) {}

  int fd_ = -1;
  PortFeatures features_{};
  std::uint64_t looks_ = 0;  ///< looks of wait_queued() and read_queued_until() (one thread)
};

/// How long one character takes on the line: start bit, data bits, parity bit, stop bits at
/// the baud rate (DCP 7.1: 10 bits at 38400 = 260 us; USS A 6.1: 11 bits).
std::chrono::nanoseconds character_time(const SerialSettings& settings) noexcept;

/// Sets raw mode and the line settings on any tty descriptor (used for both pty ends too).
/// Returns 0 or an errno; `failed_call` names the call that failed.
int configure_tty(int fd, const SerialSettings& settings, const char** failed_call) noexcept;

/// Whether an errno from a read/write/ioctl means the device has gone away.
bool is_device_lost_errno(int error_number) noexcept;

/// How long close_port_fd() waits for a close that the kernel holds back because output cannot
/// drain (the tty's closing_wait: 30 s by default, as long as systemd's stop timeout).
inline constexpr std::chrono::milliseconds kPortCloseLimit{500};

/// Closes a serial port descriptor without hanging on output the line cannot send (a stalled
/// transceiver, a cable pulled mid-frame, flow control that never releases): pending output is
/// discarded first (TCOFLUSH), which empties a UART's transmit buffer so close() has nothing to
/// wait for. A driver whose flush cannot drop it (TIOCOUTQ still counts bytes) is closed on a
/// helper thread, waited for at most `limit`, then left behind: the kernel ends that close
/// after the port's closing_wait, or at once when the process exits. Returns false when it was
/// left behind. `closer` stands for close(2) (tests put a close that blocks there). Not for the
/// real-time thread (it may start a thread).
bool close_port_fd(int fd, std::chrono::milliseconds limit = kPortCloseLimit,
                   const std::function<int(int)>& closer = {}) noexcept;

}  // namespace liftd::io
