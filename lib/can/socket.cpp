#include "can/socket.hpp"

#include <linux/can.h>
#include <linux/can/error.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/uio.h>
#include <sys/un.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstddef>
#include <cstring>

namespace liftd::can {
namespace {

constexpr std::string_view kUnixPrefix = "unix:";

SocketError error_of(int code, std::string what) {
  return {code, std::move(what)};
}

bool fill_unix_address(const std::string& path, sockaddr_un& address) {
  address = {};
  address.sun_family = AF_UNIX;
  if (path.empty() || path.size() >= sizeof address.sun_path) return false;
  std::memcpy(address.sun_path, path.c_str(), path.size() + 1);
  return true;
}

}  // namespace

std::string ErrorReport::describe() const {
  std::string out;
  const auto add = [&out](bool set, const char* text) {
    if (set) out += (out.empty() ? "" : ", ") + std::string(text);
  };
  add(bus_off, "bus-off");
  add(error_passive, "error passive");
  add(no_ack, "no ACK (no other node on the bus?)");
  add(tx_timeout, "transmit timeout");
  add(error_warning, "error warning level");
  add(rx_overflow, "receive overflow");
  add(tx_overflow, "transmit overflow");
  add(lost_arbitration, "lost arbitration");
  add(protocol_violation, "protocol violation");
  add(transceiver, "transceiver problem");
  add(restarted, "controller restarted");
  add(back_to_active, "back to error active");
  if (controller_problem && !rx_overflow && !tx_overflow && !error_warning && !error_passive &&
      !back_to_active) {
    add(true, "controller problem");
  }
  return out.empty() ? "error frame without a known cause" : out;
}

ErrorReport decode_error_frame(std::uint32_t error_class,
                               std::span<const std::uint8_t, kMaxData> data) noexcept {
  ErrorReport r;
  r.tx_timeout = (error_class & CAN_ERR_TX_TIMEOUT) != 0;
  r.lost_arbitration = (error_class & CAN_ERR_LOSTARB) != 0;
  r.controller_problem = (error_class & CAN_ERR_CRTL) != 0;
  if (r.controller_problem) {  // details in data[1]
    const std::uint8_t c = data[1];
    r.rx_overflow = (c & CAN_ERR_CRTL_RX_OVERFLOW) != 0;
    r.tx_overflow = (c & CAN_ERR_CRTL_TX_OVERFLOW) != 0;
    r.error_warning = (c & (CAN_ERR_CRTL_RX_WARNING | CAN_ERR_CRTL_TX_WARNING)) != 0;
    r.error_passive = (c & (CAN_ERR_CRTL_RX_PASSIVE | CAN_ERR_CRTL_TX_PASSIVE)) != 0;
    r.back_to_active = (c & CAN_ERR_CRTL_ACTIVE) != 0;
  }
  r.protocol_violation = (error_class & CAN_ERR_PROT) != 0;
  r.transceiver = (error_class & CAN_ERR_TRX) != 0;
  r.no_ack = (error_class & CAN_ERR_ACK) != 0;
  r.bus_off = (error_class & CAN_ERR_BUSOFF) != 0;
  r.restarted = (error_class & CAN_ERR_RESTARTED) != 0;
  if ((error_class & CAN_ERR_CNT) != 0) {  // counters in data[6] (tx) and data[7] (rx)
    r.tx_errors = data[6];
    r.rx_errors = data[7];
  }
  return r;
}

std::pair<std::uint32_t, std::array<std::uint8_t, kMaxData>> encode_error_frame(
    const ErrorReport& r) noexcept {
  std::uint32_t id = CAN_ERR_FLAG;
  std::array<std::uint8_t, kMaxData> data{};
  if (r.tx_timeout) id |= CAN_ERR_TX_TIMEOUT;
  if (r.lost_arbitration) id |= CAN_ERR_LOSTARB;
  std::uint8_t crtl = 0;
  if (r.rx_overflow) crtl |= CAN_ERR_CRTL_RX_OVERFLOW;
  if (r.tx_overflow) crtl |= CAN_ERR_CRTL_TX_OVERFLOW;
  if (r.error_warning) crtl |= CAN_ERR_CRTL_TX_WARNING;
  if (r.error_passive) crtl |= CAN_ERR_CRTL_TX_PASSIVE;
  if (r.back_to_active) crtl |= CAN_ERR_CRTL_ACTIVE;
  if (r.controller_problem || crtl != 0) {
    id |= CAN_ERR_CRTL;
    data[1] = crtl;
  }
  if (r.protocol_violation) id |= CAN_ERR_PROT;
  if (r.transceiver) id |= CAN_ERR_TRX;
  if (r.no_ack) id |= CAN_ERR_ACK;
  if (r.bus_off) id |= CAN_ERR_BUSOFF;
  if (r.restarted) id |= CAN_ERR_RESTARTED;
  if (r.tx_errors != 0 || r.rx_errors != 0) {
    id |= CAN_ERR_CNT;
    data[6] = r.tx_errors;
    data[7] = r.rx_errors;
  }
  return {id, data};
}

EndpointOpener::EndpointOpener(std::string_view endpoint, std::span<const std::uint32_t> ids)
    : endpoint_(endpoint), unix_(endpoint.substr(0, kUnixPrefix.size()) == kUnixPrefix) {
  target_ = unix_ ? std::string(endpoint.substr(kUnixPrefix.size())) : std::string(endpoint);
  // Kernel receive filters (CAN interfaces): exactly the identifiers we read, 11-bit data
  // frames only.
  filters_.reserve(ids.size());
  for (const std::uint32_t id : ids) {
    filters_.push_back({id, CAN_SFF_MASK | CAN_EFF_FLAG | CAN_RTR_FLAG});
  }
}

io::Expected<int, OpenFailure> EndpointOpener::open() const noexcept {
  static_assert(sizeof(Filter) == sizeof(can_filter) &&
                offsetof(can_filter, can_mask) == offsetof(Filter, mask));
  if (unix_) {
    sockaddr_un address{};
    if (!fill_unix_address(target_, address)) return OpenFailure{ENAMETOOLONG, OpenStep::UnixPath};
    const int fd = ::socket(AF_UNIX, SOCK_SEQPACKET | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
    if (fd < 0) return OpenFailure{errno, OpenStep::UnixSocket};
    // NOLINTNEXTLINE(cppcoreguidelines-pro-type-reinterpret-cast): the sockets API
    if (::connect(fd, reinterpret_cast<const sockaddr*>(&address), sizeof address) != 0) {
      const int code = errno;
      ::close(fd);
      return OpenFailure{code, OpenStep::UnixConnect};
    }
    return fd;
  }
  if (target_.empty() || target_.size() >= IFNAMSIZ) {
    return OpenFailure{ENODEV, OpenStep::InterfaceName};
  }
  const int fd = ::socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW);
  if (fd < 0) return OpenFailure{errno, OpenStep::CanSocket};
  const auto fail = [fd](OpenStep step) noexcept {
    const int code = errno;
    ::close(fd);
    return OpenFailure{code, step};
  };
  const unsigned index = ::if_nametoindex(target_.c_str());
  if (index == 0) return fail(OpenStep::NoInterface);
  if (!filters_.empty() &&
      ::setsockopt(fd, SOL_CAN_RAW, CAN_RAW_FILTER, filters_.data(),
                   static_cast<socklen_t>(filters_.size() * sizeof(can_filter))) != 0) {
    return fail(OpenStep::ReceiveFilter);
  }
  // Error frames: everything but CAN_ERR_BUSERROR, which may flood a broken bus.
  const can_err_mask_t errors = CAN_ERR_TX_TIMEOUT | CAN_ERR_LOSTARB | CAN_ERR_CRTL | CAN_ERR_PROT |
                                CAN_ERR_TRX | CAN_ERR_ACK | CAN_ERR_BUSOFF | CAN_ERR_RESTARTED |
                                CAN_ERR_CNT;
  if (::setsockopt(fd, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &errors, sizeof errors) != 0) {
    return fail(OpenStep::ErrorFilter);
  }
  // Each record then carries the kernel's count of frames dropped on this socket's full
  // receive queue, so a reader that falls behind the bus is seen, not guessed.
  const int on = 1;
  if (::setsockopt(fd, SOL_SOCKET, SO_RXQ_OVFL, &on, sizeof on) != 0) {
    return fail(OpenStep::OverflowOption);
  }
  sockaddr_can address{};
  address.can_family = AF_CAN;
  address.can_ifindex = static_cast<int>(index);
  // NOLINTNEXTLINE(cppcoreguidelines-pro-type-reinterpret-cast): the sockets API
  if (::bind(fd, reinterpret_cast<const sockaddr*>(&address), sizeof address) != 0) {
    return fail(OpenStep::Bind);
  }
  return fd;
}

std::string EndpointOpener::describe(const OpenFailure& failure) const {
  switch (failure.step) {
    case OpenStep::UnixPath:
      return "unix socket path \"" + target_ + "\" is empty or too long";
    case OpenStep::UnixSocket:
      return "socket(AF_UNIX, SOCK_SEQPACKET)";
    case OpenStep::UnixConnect:
      return "connect to " + target_;
    case OpenStep::InterfaceName:
      return "CAN interface name \"" + target_ + "\" is empty or too long";
    case OpenStep::CanSocket:
      return "socket(PF_CAN, SOCK_RAW, CAN_RAW)";
    case OpenStep::NoInterface:
      return "no network interface \"" + target_ + "\"";
    case OpenStep::ReceiveFilter:
      return "setsockopt(CAN_RAW_FILTER)";
    case OpenStep::ErrorFilter:
      return "setsockopt(CAN_RAW_ERR_FILTER)";
    case OpenStep::OverflowOption:
      return "setsockopt(SO_RXQ_OVFL)";
    case OpenStep::Bind:
      return "bind to CAN interface " + target_;
  }
  return "opening " + endpoint_;
}

io::Expected<CanSocket, SocketError> CanSocket::open(std::string_view endpoint,
                                                     std::vector<std::uint32_t> ids) {
  const EndpointOpener opener(endpoint, ids);
  const auto opened = opener.open();
  if (!opened) return error_of(opened.error().code, opener.describe(opened.error()));
  return CanSocket(opened.value(), std::move(ids));
}

io::Expected<std::pair<CanSocket, CanSocket>, SocketError> CanSocket::pair() {
  int fds[2];
  if (::socketpair(AF_UNIX, SOCK_SEQPACKET | SOCK_NONBLOCK | SOCK_CLOEXEC, 0, fds) != 0) {
    return error_of(errno, "socketpair(AF_UNIX, SOCK_SEQPACKET)");
  }
  return std::pair<CanSocket, CanSocket>(CanSocket(fds[0], {}), CanSocket(fds[1], {}));
}

CanSocket CanSocket::adopt(int fd, std::vector<std::uint32_t> ids) {
  return CanSocket(fd, std::move(ids));
}

CanSocket CanSocket::unattached(std::vector<std::uint32_t> ids) {
  return CanSocket(-1, std::move(ids));
}

void CanSocket::attach(int fd) noexcept {
  close();
  fd_ = fd;
  kernel_overflow_total_ = 0;  // SO_RXQ_OVFL counts per socket, from 0
}

void CanSocket::close() noexcept {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

CanSocket::CanSocket(CanSocket&& other) noexcept
    : fd_(std::exchange(other.fd_, -1)),
      ids_(std::move(other.ids_)),
      drops_(other.drops_),
      kernel_overflow_total_(other.kernel_overflow_total_) {}

CanSocket& CanSocket::operator=(CanSocket&& other) noexcept {
  if (this != &other) {
    if (fd_ >= 0) ::close(fd_);
    fd_ = std::exchange(other.fd_, -1);
    ids_ = std::move(other.ids_);
    drops_ = other.drops_;
    kernel_overflow_total_ = other.kernel_overflow_total_;
  }
  return *this;
}

CanSocket::~CanSocket() {
  if (fd_ >= 0) ::close(fd_);
}

bool CanSocket::wanted(std::uint32_t id) const noexcept {
  return ids_.empty() || std::find(ids_.begin(), ids_.end(), id) != ids_.end();
}

Received CanSocket::read() noexcept {
  Received out;
  can_frame record{};
  iovec part{&record, sizeof record};
  alignas(cmsghdr) std::array<char, CMSG_SPACE(sizeof(std::uint32_t))> control{};
  msghdr message{};
  message.msg_iov = &part;
  message.msg_iovlen = 1;
  message.msg_control = control.data();
  message.msg_controllen = control.size();
  const ssize_t n = ::recvmsg(fd_, &message, MSG_DONTWAIT | MSG_TRUNC);
  if (n > 0) note_overflow(message);
  if (n < 0) {
    if (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR) return out;
    out.kind = Received::Kind::Failed;
    out.errno_value = errno;
    return out;
  }
  if (n == 0) {
    // SOCK_SEQPACKET: 0 is the peer's end of file, or an empty record, which is a record (a
    // malformed one) and no reason to drop the connection. Only a peer that hung up with
    // nothing more queued has closed it.
    if (peer_closed()) {
      out.kind = Received::Kind::Closed;
      return out;
    }
    ++drops_.malformed;
    return out;
  }
  // MSG_TRUNC: n is the packet's real size, so a longer record (CAN FD, garbage) is seen.
  if (static_cast<std::size_t>(n) != sizeof record || record.len > kMaxData) {
    ++drops_.malformed;
    return out;
  }
  std::array<std::uint8_t, kMaxData> data{};
  std::copy_n(record.data, kMaxData, data.begin());
  if ((record.can_id & CAN_ERR_FLAG) != 0) {
    out.kind = Received::Kind::Error;
    out.error = decode_error_frame(record.can_id & CAN_ERR_MASK, data);
    return out;
  }
  if ((record.can_id & (CAN_EFF_FLAG | CAN_RTR_FLAG)) != 0) {
    ++drops_.extended;
    return out;
  }
  const std::uint32_t id = record.can_id & CAN_SFF_MASK;
  if (!wanted(id)) {
    ++drops_.filtered;
    return out;
  }
  out.kind = Received::Kind::Frame;
  out.frame = make_frame(id, std::span<const std::uint8_t>(data.data(), record.len));
  return out;
}

void CanSocket::note_overflow(const msghdr& message) noexcept {
  // SO_RXQ_OVFL: the socket's total of dropped frames so far, a 32-bit count that wraps.
  // The cmsg macros cast and step through the control buffer:
  // NOLINTBEGIN(cppcoreguidelines-pro-type-reinterpret-cast,cppcoreguidelines-pro-bounds-pointer-arithmetic)
  for (const cmsghdr* c = CMSG_FIRSTHDR(&message); c != nullptr;
       c = CMSG_NXTHDR(const_cast<msghdr*>(&message), const_cast<cmsghdr*>(c))) {
    if (c->cmsg_level != SOL_SOCKET || c->cmsg_type != SO_RXQ_OVFL) continue;
    std::uint32_t total = 0;
    std::memcpy(&total, CMSG_DATA(c), sizeof total);
    drops_.overflowed += static_cast<std::uint32_t>(total - kernel_overflow_total_);
    kernel_overflow_total_ = total;
  }
  // NOLINTEND(cppcoreguidelines-pro-type-reinterpret-cast,cppcoreguidelines-pro-bounds-pointer-arithmetic)
}

bool CanSocket::peer_closed() const noexcept {
  pollfd p{fd_, POLLRDHUP, 0};
  if (::poll(&p, 1, 0) <= 0 || (p.revents & (POLLHUP | POLLRDHUP)) == 0) return false;
  char byte = 0;
  return ::recv(fd_, &byte, sizeof byte, MSG_DONTWAIT | MSG_PEEK | MSG_TRUNC) <= 0;
}

int CanSocket::send_record(std::uint32_t can_id, std::span<const std::uint8_t> data) noexcept {
  can_frame record{};
  record.can_id = can_id;
  record.len = static_cast<std::uint8_t>(std::min(data.size(), kMaxData));
  std::copy_n(data.begin(), record.len, record.data);
  const ssize_t n = ::send(fd_, &record, sizeof record, MSG_DONTWAIT | MSG_NOSIGNAL);
  if (n < 0) return errno;
  return n == static_cast<ssize_t>(sizeof record) ? 0 : EIO;
}

int CanSocket::write(const Frame& frame) noexcept {
  if (frame.id > kMaxStandardId || frame.length > kMaxData) return EINVAL;
  return send_record(frame.id, frame.bytes());
}

int CanSocket::write_error(const ErrorReport& report) noexcept {
  const auto [id, data] = encode_error_frame(report);
  return send_record(id, data);
}

io::Expected<int, SocketError> listen_unix(const std::string& path) {
  sockaddr_un address{};
  if (!fill_unix_address(path, address)) {
    return error_of(ENAMETOOLONG, "unix socket path \"" + path + "\" is empty or too long");
  }
  const int fd = ::socket(AF_UNIX, SOCK_SEQPACKET | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd < 0) return error_of(errno, "socket(AF_UNIX, SOCK_SEQPACKET)");
  ::unlink(path.c_str());  // a stale socket file from an earlier run
  // NOLINTNEXTLINE(cppcoreguidelines-pro-type-reinterpret-cast): the sockets API
  if (::bind(fd, reinterpret_cast<const sockaddr*>(&address), sizeof address) != 0 ||
      ::listen(fd, 1) != 0) {
    const int code = errno;
    ::close(fd);
    return error_of(code, "listen on " + path);
  }
  return fd;
}

bool kernel_has_can() noexcept {
  const int fd = ::socket(PF_CAN, SOCK_RAW | SOCK_CLOEXEC, CAN_RAW);
  if (fd < 0) return false;
  ::close(fd);
  return true;
}

}  // namespace liftd::can
