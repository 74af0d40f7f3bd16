// journald native protocol: field building, encoding, and the datagram writer.
#include "log/journal.hpp"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <ctime>

namespace liftd::log {
namespace {

// journald rejects field names longer than 64 characters.
constexpr std::size_t kMaxFieldNameLength = 64;
// The binary form carries the value length as a 64-bit little-endian integer.
constexpr std::size_t kLengthBytes = 8;

bool needs_quotes(std::string_view value) {
  if (value.empty()) return true;
  for (char c : value) {
    if (c == ' ' || c == '"' || c == '=' || c == '\n' || c == '\t') return true;
  }
  return false;
}

void append_text_value(std::string& out, std::string_view value) {
  if (!needs_quotes(value)) {
    out += value;
    return;
  }
  out += '"';
  for (char c : value) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (c == '\n') {
      out += "\\n";
    } else {
      out += c;
    }
  }
  out += '"';
}

std::string_view level_label(Level level) {
  switch (level) {
    case Level::trace:
      return "TRACE";
    case Level::debug:
      return "DEBUG";
    case Level::info:
      return "INFO ";
    case Level::warn:
      return "WARN ";
    case Level::error:
      return "ERROR";
  }
  return "?    ";
}

// Sends `data` as a sealed memfd: journald's way for records too large for one datagram.
int send_as_memfd(int socket_fd, const sockaddr_un& address, socklen_t address_length,
                  std::string_view data) {
  const int memfd = memfd_create("liftd-journal", MFD_CLOEXEC | MFD_ALLOW_SEALING);
  if (memfd < 0) return errno;
  std::size_t written = 0;
  while (written < data.size()) {
    const ssize_t n = ::write(memfd, data.data() + written, data.size() - written);
    if (n < 0) {
      const int error = errno;
      if (error == EINTR) continue;
      ::close(memfd);
      return error;
    }
    written += static_cast<std::size_t>(n);
  }
  ::fcntl(memfd, F_ADD_SEALS, F_SEAL_SHRINK | F_SEAL_GROW | F_SEAL_WRITE | F_SEAL_SEAL);
  alignas(cmsghdr) char control[CMSG_SPACE(sizeof(int))] = {};
  msghdr message{};
  message.msg_name = const_cast<sockaddr_un*>(&address);
  message.msg_namelen = address_length;
  message.msg_control = control;
  message.msg_controllen = sizeof(control);
  cmsghdr* header = CMSG_FIRSTHDR(&message);
  header->cmsg_level = SOL_SOCKET;
  header->cmsg_type = SCM_RIGHTS;
  header->cmsg_len = CMSG_LEN(sizeof(int));
  std::memcpy(CMSG_DATA(header), &memfd, sizeof(int));
  const ssize_t sent = ::sendmsg(socket_fd, &message, MSG_NOSIGNAL | MSG_DONTWAIT);
  const int error = sent < 0 ? errno : 0;
  ::close(memfd);
  return error;
}

}  // namespace

int journal_priority(Level level) {
  // syslog(3) priorities: LOG_ERR 3, LOG_WARNING 4, LOG_INFO 6, LOG_DEBUG 7.
  switch (level) {
    case Level::error:
      return 3;
    case Level::warn:
      return 4;
    case Level::info:
      return 6;
    case Level::debug:
    case Level::trace:
      return 7;
  }
  return 6;
}

std::string journal_field_name(std::string_view key) {
  std::string name = "LIFTD_";
  for (char c : key) {
    if (c >= 'a' && c <= 'z') {
      name += static_cast<char>(c - 'a' + 'A');
    } else if ((c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_') {
      name += c;
    } else {
      name += '_';
    }
  }
  if (name.size() > kMaxFieldNameLength) name.resize(kMaxFieldNameLength);
  return name;
}

std::vector<JournalField> journal_fields(const Record& record, std::string_view identifier) {
  std::vector<JournalField> out;
  out.emplace_back("MESSAGE", std::string(record.text));
  out.emplace_back("PRIORITY", std::to_string(journal_priority(record.level)));
  out.emplace_back("SYSLOG_IDENTIFIER", std::string(identifier));
  if (!record.component.empty()) {
    out.emplace_back("LIFTD_COMPONENT", std::string(record.component));
  }
  if (!record.event.empty()) out.emplace_back("LIFTD_EVENT", std::string(record.event));
  if (record.fields != nullptr) {
    for (const auto& field : *record.fields) {
      out.emplace_back(journal_field_name(field.key), field.value);
    }
  }
  if (!record.file.empty() && record.line != 0) {
    out.emplace_back("CODE_FILE", std::string(record.file));
    out.emplace_back("CODE_LINE", std::to_string(record.line));
    if (!record.function.empty()) out.emplace_back("CODE_FUNC", std::string(record.function));
  }
  return out;
}

std::string encode_journal_datagram(const std::vector<JournalField>& fields) {
  std::string out;
  for (const auto& [name, value] : fields) {
    out += name;
    if (value.find('\n') == std::string::npos) {
      out += '=';
      out += value;
    } else {
      out += '\n';
      std::uint64_t length = value.size();
      for (std::size_t i = 0; i < kLengthBytes; ++i) {
        out += static_cast<char>(length & 0xFFU);
        length >>= 8U;
      }
      out += value;
    }
    out += '\n';
  }
  return out;
}

bool decode_journal_datagram(std::string_view datagram, std::vector<JournalField>& out) {
  out.clear();
  std::size_t pos = 0;
  while (pos < datagram.size()) {
    const std::size_t end = datagram.find_first_of("=\n", pos);
    if (end == std::string_view::npos) return false;
    std::string name(datagram.substr(pos, end - pos));
    if (name.empty()) return false;
    if (datagram[end] == '=') {
      const std::size_t newline = datagram.find('\n', end + 1);
      if (newline == std::string_view::npos) return false;
      out.emplace_back(std::move(name), std::string(datagram.substr(end + 1, newline - end - 1)));
      pos = newline + 1;
      continue;
    }
    if (datagram.size() - end - 1 < kLengthBytes) return false;
    std::uint64_t length = 0;
    for (std::size_t i = 0; i < kLengthBytes; ++i) {
      length |= static_cast<std::uint64_t>(static_cast<unsigned char>(datagram[end + 1 + i]))
                << (8U * i);
    }
    const std::size_t start = end + 1 + kLengthBytes;
    if (length > datagram.size() - start || datagram.size() - start - length < 1 ||
        datagram[start + length] != '\n') {
      return false;
    }
    out.emplace_back(std::move(name), std::string(datagram.substr(start, length)));
    pos = start + length + 1;
  }
  return true;
}

std::string format_text_line(const Record& record, std::chrono::system_clock::time_point when) {
  const std::time_t seconds = std::chrono::system_clock::to_time_t(when);
  const auto millis = std::chrono::duration_cast<std::chrono::milliseconds>(
                          when.time_since_epoch() % std::chrono::seconds(1))
                          .count();
  std::tm local{};
  ::localtime_r(&seconds, &local);
  char stamp[32];
  const std::size_t length = std::strftime(stamp, sizeof(stamp), "%Y-%m-%d %H:%M:%S", &local);
  std::string out(stamp, length);
  char fraction[8];
  std::snprintf(fraction, sizeof(fraction), ".%03d", static_cast<int>(millis));
  out += fraction;
  out += ' ';
  out += level_label(record.level);
  out += ' ';
  out += record.component.empty() ? std::string_view("liftd") : record.component;
  out += ": ";
  out += record.text;
  const bool has_fields = record.fields != nullptr && !record.fields->empty();
  if (!record.event.empty() || has_fields) {
    out += " [";
    bool first = true;
    if (!record.event.empty()) {
      out += "event=";
      out += record.event;
      first = false;
    }
    if (has_fields) {
      for (const auto& field : *record.fields) {
        if (!first) out += ' ';
        first = false;
        out += field.key;
        out += '=';
        append_text_value(out, field.value);
      }
    }
    out += ']';
  }
  return out;
}

JournalWriter::JournalWriter(std::string socket_path) : socket_path_(std::move(socket_path)) {}

JournalWriter::~JournalWriter() {
  if (fd_ >= 0) ::close(fd_);
}

int JournalWriter::send(std::string_view datagram) {
  sockaddr_un address{};
  address.sun_family = AF_UNIX;
  if (socket_path_.size() >= sizeof(address.sun_path)) return ENAMETOOLONG;
  std::memcpy(address.sun_path, socket_path_.data(), socket_path_.size());
  const auto address_length =
      static_cast<socklen_t>(offsetof(sockaddr_un, sun_path) + socket_path_.size() + 1);
  if (fd_ < 0) {
    fd_ = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    if (fd_ < 0) return errno;
  }
  const ssize_t sent = ::sendto(fd_, datagram.data(), datagram.size(), MSG_NOSIGNAL | MSG_DONTWAIT,
                                reinterpret_cast<const sockaddr*>(&address), address_length);
  if (sent >= 0) return 0;
  const int error = errno;
  if (error == EMSGSIZE || error == ENOBUFS) {
    return send_as_memfd(fd_, address, address_length, datagram);
  }
  return error;
}

}  // namespace liftd::log
