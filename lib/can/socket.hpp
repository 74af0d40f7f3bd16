// One CAN endpoint for the protocol code: a SocketCAN raw socket bound to an interface, or a
// Unix SOCK_SEQPACKET socket carrying one `struct can_frame` per packet (a socketpair inside
// one process, or `unix:PATH` where a simulator listens). Only opening differs: reading,
// writing, filtering and error frames take the same path for both.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "can/frame.hpp"
#include "io/expected.hpp"

struct msghdr;

namespace liftd::can {

/// A decoded CAN error frame (linux/can/error.h). Over a Unix socket a simulator sends the same
/// records to inject bus faults.
struct ErrorReport {
  bool tx_timeout = false;          ///< the driver timed out a transmission
  bool lost_arbitration = false;    ///< arbitration lost
  bool controller_problem = false;  ///< the controller reported a problem (see below)
  bool rx_overflow = false;         ///< controller: receive buffer overflow
  bool tx_overflow = false;         ///< controller: transmit buffer overflow
  bool error_warning = false;       ///< controller: error counters reached the warning level
  bool error_passive = false;       ///< controller: error passive (counters above 127)
  bool back_to_active = false;      ///< controller: recovered to error active
  bool protocol_violation = false;  ///< bit, form or stuff error on the bus
  bool transceiver = false;         ///< transceiver problem (wiring)
  bool no_ack = false;              ///< nobody acknowledged our frame (nobody else on the bus)
  bool bus_off = false;             ///< the controller went bus-off: nothing is sent any more
  bool restarted = false;           ///< the controller was restarted after bus-off
  std::uint8_t tx_errors = 0;       ///< transmit error counter, where reported
  std::uint8_t rx_errors = 0;       ///< receive error counter, where reported
  /// A fault for the link: bus-off, error passive, no ACK or a transmit timeout. Warnings,
  /// overflows, protocol errors and recovery notes are counted and logged only.
  bool is_fault() const noexcept { return bus_off || error_passive || no_ack || tx_timeout; }
  /// "bus-off, no ACK" and so on, for the journal.
  std::string describe() const;
  bool operator==(const ErrorReport&) const = default;
};

/// Decodes an error frame's class bits (`can_id` without CAN_ERR_FLAG) and data.
ErrorReport decode_error_frame(std::uint32_t error_class,
                               std::span<const std::uint8_t, kMaxData> data) noexcept;
/// The error frame a kernel would deliver for `report` (can_id with CAN_ERR_FLAG, and data), for
/// simulators injecting bus faults over a Unix socket.
std::pair<std::uint32_t, std::array<std::uint8_t, kMaxData>> encode_error_frame(
    const ErrorReport& report) noexcept;

/// Why opening, reading or writing failed: the errno value and what was being done.
struct SocketError {
  int code = 0;
  std::string what;
};

/// The step of opening an endpoint that failed (EndpointOpener::open()), named without
/// building text so that a real-time thread can report it; describe() makes the words.
enum class OpenStep : std::uint8_t {
  UnixPath,        ///< the unix: path is empty or too long for sockaddr_un
  UnixSocket,      ///< socket(AF_UNIX, SOCK_SEQPACKET)
  UnixConnect,     ///< connect() to the path (nobody listens, no such file)
  InterfaceName,   ///< the interface name is empty or too long (IFNAMSIZ)
  CanSocket,       ///< socket(PF_CAN, SOCK_RAW, CAN_RAW)
  NoInterface,     ///< if_nametoindex(): no network interface of that name
  ReceiveFilter,   ///< setsockopt(CAN_RAW_FILTER)
  ErrorFilter,     ///< setsockopt(CAN_RAW_ERR_FILTER)
  OverflowOption,  ///< setsockopt(SO_RXQ_OVFL)
  Bind,            ///< bind() to the interface
};

/// Why one open failed: the errno value and the step.
struct OpenFailure {
  int code = 0;
  OpenStep step = OpenStep::UnixPath;
};

/// Everything opening one endpoint needs ("can0" or "unix:PATH", the identifiers to receive),
/// prepared once when it is built (which allocates), so that open() can be called again and
/// again from a real-time thread without allocating or building text: the CAN runner reopens a
/// lost endpoint with it. The interface index is looked up at every open (an adapter plugged
/// in again may get a new one).
class EndpointOpener {
 public:
  EndpointOpener(std::string_view endpoint, std::span<const std::uint32_t> ids);
  /// A fresh connected (unix:) or bound (CAN) non-blocking descriptor, or the failed step.
  /// Never allocates.
  io::Expected<int, OpenFailure> open() const noexcept;
  /// The words of a failure, as CanSocket::open() reports them ("connect to PATH"), without
  /// the errno text. Allocates: call it off the real-time thread.
  std::string describe(const OpenFailure& failure) const;
  const std::string& endpoint() const noexcept { return endpoint_; }

 private:
  /// struct can_filter's layout (linux/can.h: two canid_t), so no kernel header is needed here.
  struct Filter {
    std::uint32_t id;
    std::uint32_t mask;
  };

  std::string endpoint_;
  bool unix_ = false;
  std::string target_;  ///< the unix socket path, or the interface name
  std::vector<Filter> filters_;
};

/// What one read() found.
struct Received {
  enum class Kind : std::uint8_t {
    Frame,    ///< `frame` holds a data frame with one of the filtered identifiers
    Error,    ///< `error` holds a decoded error frame
    Nothing,  ///< nothing to read now (or a record that was dropped, see counters)
    Closed,   ///< the peer closed the connection (Unix sockets)
    Failed,   ///< the socket failed: `errno_value` (e.g. ENETDOWN); reopen it
  };
  Kind kind = Kind::Nothing;
  Frame frame{};
  ErrorReport error{};
  int errno_value = 0;
};

/// Records read but not passed on.
struct DropCounters {
  std::uint64_t filtered = 0;  ///< data frames with an identifier outside the filter
  std::uint64_t malformed =
      0;  ///< records that are not one struct can_frame (empty ones too), or length > 8
  std::uint64_t extended = 0;  ///< 29-bit or remote frames (the protocols here use neither)
  /// Frames the kernel dropped before we read them because this socket's receive queue was
  /// full (SO_RXQ_OVFL; CAN interfaces only): a reader too slow for the bus.
  std::uint64_t overflowed = 0;
};

/// A non-blocking CAN endpoint. Move-only; closes its descriptor.
class CanSocket {
 public:
  /// "unix:PATH" connects to a simulator listening there; anything else is a CAN interface
  /// name ("can0") for a raw SocketCAN socket with error frames enabled. Only frames whose
  /// identifier is in `ids` are passed on (empty: all). On a kernel without AF_CAN opening an
  /// interface fails with EAFNOSUPPORT.
  static io::Expected<CanSocket, SocketError> open(std::string_view endpoint,
                                                   std::vector<std::uint32_t> ids);
  /// Two connected endpoints (socketpair, SOCK_SEQPACKET), e.g. the daemon and the card
  /// simulator inside `liftd --simulate`.
  static io::Expected<std::pair<CanSocket, CanSocket>, SocketError> pair();
  /// Takes a connected SOCK_SEQPACKET descriptor (from accept()).
  static CanSocket adopt(int fd, std::vector<std::uint32_t> ids = {});
  /// An endpoint with no descriptor yet that will pass on the frames of `ids` (empty: all)
  /// once attach() gives it one: a real-time thread builds it up front and then attaches and
  /// closes descriptors without allocating.
  static CanSocket unattached(std::vector<std::uint32_t> ids);

  CanSocket(CanSocket&& other) noexcept;
  CanSocket& operator=(CanSocket&& other) noexcept;
  CanSocket(const CanSocket&) = delete;
  CanSocket& operator=(const CanSocket&) = delete;
  ~CanSocket();

  /// The descriptor, for poll(); -1 after a move, close() or before attach().
  int fd() const noexcept { return fd_; }
  bool is_open() const noexcept { return fd_ >= 0; }
  /// Takes `fd` (from EndpointOpener::open()), closing the descriptor held, if any. The
  /// identifier filter and the drop counters stay: they count over every descriptor this
  /// endpoint had. Never allocates.
  void attach(int fd) noexcept;
  /// Closes the descriptor; the filter and the drop counters stay. Never allocates.
  void close() noexcept;
  /// Reads at most one record, never blocks.
  Received read() noexcept;
  /// Sends one frame, never blocks; 0 or the errno value (EAGAIN: the queue is full).
  int write(const Frame& frame) noexcept;
  /// Sends one raw error frame (simulators over Unix sockets only).
  int write_error(const ErrorReport& report) noexcept;
  const DropCounters& drops() const noexcept { return drops_; }

 private:
  CanSocket(int fd, std::vector<std::uint32_t> ids) noexcept : fd_(fd), ids_(std::move(ids)) {}
  int send_record(std::uint32_t can_id, std::span<const std::uint8_t> data) noexcept;
  bool wanted(std::uint32_t id) const noexcept;
  /// The peer hung up and nothing more is queued (a read of 0 bytes was its end of file).
  bool peer_closed() const noexcept;
  /// Adds the frames the kernel dropped since the last record (SO_RXQ_OVFL's running total).
  void note_overflow(const msghdr& message) noexcept;

  int fd_ = -1;
  std::vector<std::uint32_t> ids_;
  DropCounters drops_{};
  std::uint32_t kernel_overflow_total_ = 0;  // SO_RXQ_OVFL's last running total
};

/// Listens on a Unix SOCK_SEQPACKET socket at `path` (replacing a stale socket file) for one
/// controller at a time; returns the listening descriptor (non-blocking, close-on-exec).
io::Expected<int, SocketError> listen_unix(const std::string& path);

/// True when the kernel offers AF_CAN (a raw CAN socket can be created).
bool kernel_has_can() noexcept;

}  // namespace liftd::can
