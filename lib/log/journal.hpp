// journald's native protocol, written by hand so the socket path is configurable and the send
// path can be tested against a socket the test binds. Field building and encoding are pure.
#pragma once

#include <chrono>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "log/log.hpp"

namespace liftd::log {

/// Everything a sink needs to write one record.
struct Record {
  Level level = Level::info;       ///< severity
  std::string_view component;      ///< LIFTD_COMPONENT, e.g. "dcp"
  std::string_view event;          ///< LIFTD_EVENT, e.g. "link_fault"; empty for plain records
  const Fields* fields = nullptr;  ///< extra fields, may be null
  std::string_view text;           ///< MESSAGE
  std::string_view file;           ///< CODE_FILE; empty when unknown
  unsigned line = 0;               ///< CODE_LINE; 0 when unknown
  std::string_view function;       ///< CODE_FUNC; empty when unknown
};

/// One journal field: name (A-Z, 0-9, _) and value.
using JournalField = std::pair<std::string, std::string>;

/// The syslog priority of a level (journald's PRIORITY): error 3, warn 4, info 6, debug and
/// trace 7 (syslog has nothing below debug).
int journal_priority(Level level);

/// Turns an extra field's key into a journal field name: "cause" -> "LIFTD_CAUSE". Characters
/// outside A-Z 0-9 _ become _, and the name is cut to journald's 64-character limit.
std::string journal_field_name(std::string_view key);

/// The fields of one record, in order: MESSAGE, PRIORITY, SYSLOG_IDENTIFIER, LIFTD_COMPONENT,
/// LIFTD_EVENT (when set), the extra fields, CODE_FILE/CODE_LINE/CODE_FUNC (when known).
std::vector<JournalField> journal_fields(const Record& record, std::string_view identifier);

/// Encodes fields as one native-protocol datagram: "NAME=value\n" per field, or, for values
/// containing a newline, "NAME\n" + 64-bit little-endian length + value + "\n".
std::string encode_journal_datagram(const std::vector<JournalField>& fields);

/// Decodes a native-protocol datagram (both forms), for tests and diagnostics. Returns false
/// when the datagram is malformed.
bool decode_journal_datagram(std::string_view datagram, std::vector<JournalField>& out);

/// One readable line for stderr: "2026-11-22 03:00:43.123 WARN  dcp: text [event=... k=v]".
std::string format_text_line(const Record& record, std::chrono::system_clock::time_point when);

/// Sends datagrams to a journald socket (a Unix datagram socket path).
class JournalWriter {
 public:
  /// A writer for the socket at `socket_path`; nothing is opened until the first send.
  explicit JournalWriter(std::string socket_path);
  ~JournalWriter();
  JournalWriter(const JournalWriter&) = delete;
  JournalWriter& operator=(const JournalWriter&) = delete;

  /// Sends one datagram; returns 0 or the errno of the failure.
  int send(std::string_view datagram);

  /// The socket path.
  const std::string& socket_path() const { return socket_path_; }

 private:
  std::string socket_path_;
  int fd_ = -1;
};

}  // namespace liftd::log
