#include "can/interface_info.hpp"

#include <linux/can/netlink.h>
#include <linux/netlink.h>
#include <linux/rtnetlink.h>
#include <net/if.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstring>

namespace liftd::can {
namespace {

// Walks the attributes in [data, data + length) and calls `each(type, payload, payload_length)`.
template <typename F>
void for_each_attribute(const std::uint8_t* data, std::size_t length, F&& each) {
  while (length >= sizeof(rtattr)) {
    rtattr a{};
    std::memcpy(&a, data, sizeof a);
    if (a.rta_len < sizeof(rtattr) || a.rta_len > length) return;
    each(static_cast<unsigned>(a.rta_type & NLA_TYPE_MASK), data + RTA_LENGTH(0),
         static_cast<std::size_t>(a.rta_len) - RTA_LENGTH(0));
    const std::size_t step = RTA_ALIGN(a.rta_len);
    if (step >= length) return;
    data += step;
    length -= step;
  }
}

}  // namespace

InterfaceInfo query_interface(const std::string& name) {
  InterfaceInfo info;
  const unsigned index = ::if_nametoindex(name.c_str());
  if (index == 0) {
    info.error = "no network interface \"" + name + "\"";
    return info;
  }
  info.found = true;
  const int fd = ::socket(AF_NETLINK, SOCK_RAW | SOCK_CLOEXEC, NETLINK_ROUTE);
  if (fd < 0) {
    info.error = std::string("netlink: ") + std::strerror(errno);
    return info;
  }
  const timeval timeout{1, 0};
  (void)::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof timeout);
  struct {
    nlmsghdr header;
    ifinfomsg body;
  } request{};
  request.header.nlmsg_len = sizeof request;
  request.header.nlmsg_type = RTM_GETLINK;
  request.header.nlmsg_flags = NLM_F_REQUEST;
  request.header.nlmsg_seq = 1;
  request.body.ifi_family = AF_UNSPEC;
  request.body.ifi_index = static_cast<int>(index);
  if (::send(fd, &request, sizeof request, 0) < 0) {
    info.error = std::string("netlink: ") + std::strerror(errno);
    ::close(fd);
    return info;
  }
  std::array<std::uint8_t, 16384> buffer{};
  const ssize_t n = ::recv(fd, buffer.data(), buffer.size(), 0);
  ::close(fd);
  if (n < static_cast<ssize_t>(NLMSG_LENGTH(sizeof(ifinfomsg)))) {
    info.error = n < 0 ? std::string("netlink: ") + std::strerror(errno) : "netlink: short reply";
    return info;
  }
  nlmsghdr header{};
  std::memcpy(&header, buffer.data(), sizeof header);
  if (header.nlmsg_type != RTM_NEWLINK || header.nlmsg_len > static_cast<std::uint32_t>(n)) {
    info.error = "netlink: unexpected reply";
    return info;
  }
  ifinfomsg link{};
  std::memcpy(&link, buffer.data() + NLMSG_LENGTH(0), sizeof link);
  info.up = (link.ifi_flags & IFF_UP) != 0;
  const std::size_t attributes = NLMSG_LENGTH(sizeof(ifinfomsg));
  for_each_attribute(
      buffer.data() + attributes, header.nlmsg_len - attributes,
      [&](unsigned type, const std::uint8_t* data, std::size_t length) {
        if (type != IFLA_LINKINFO) return;
        for_each_attribute(data, length, [&](unsigned t, const std::uint8_t* d, std::size_t l) {
          if (t != IFLA_INFO_DATA) return;
          for_each_attribute(d, l, [&](unsigned c, const std::uint8_t* p, std::size_t pl) {
            if (c != IFLA_CAN_BITTIMING || pl < sizeof(can_bittiming)) return;
            can_bittiming timing{};
            std::memcpy(&timing, p, sizeof timing);
            if (timing.bitrate != 0) info.bitrate = timing.bitrate;
          });
        });
      });
  return info;
}

}  // namespace liftd::can
