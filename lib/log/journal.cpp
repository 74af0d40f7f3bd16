// Journal records: field building (pure), the stderr line forms, and sd_journal_sendv(3).
#include "log/journal.hpp"

#include <sys/stat.h>
#include <sys/uio.h>
// The record carries the caller's CODE_FILE/CODE_LINE/CODE_FUNC (journal_fields); without this
// the header's sd_journal_sendv macro would add this file's location instead.
#define SD_JOURNAL_SUPPRESS_LOCATION
#include <systemd/sd-journal.h>

#include <cerrno>
#include <cstdio>
#include <ctime>

#include "log/catalog.hpp"

namespace liftd::log {
namespace {

// Where sd_journal_sendv(3) sends: journald's native socket (systemd-journald.service(8)).
constexpr const char* kJournalSocket = "/run/systemd/journal/socket";
// journald rejects field names longer than 64 characters.
constexpr std::size_t kMaxFieldNameLength = 64;

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

// "component: text [event=... k=v]", the part both line forms share.
void append_body(std::string& out, const Record& record) {
  out += record.component.empty() ? std::string_view("liftd") : record.component;
  out += ": ";
  out += record.text;
  const bool has_fields = record.fields != nullptr && !record.fields->empty();
  if (record.event.empty() && !has_fields) return;
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
  if (record.catalogued) {
    if (const std::string_view id = message_id(*record.catalogued); !id.empty()) {
      out.emplace_back("MESSAGE_ID", std::string(id));
    }
  }
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

int send_to_journal(const std::vector<JournalField>& fields) {
  // sd_journal_sendv(3) returns success without a word when no journald listens (ENOENT on its
  // socket); a record must never vanish, so look first.
  struct stat socket_file {};
  if (::stat(kJournalSocket, &socket_file) != 0) return errno;
  std::vector<std::string> lines;
  lines.reserve(fields.size());
  std::vector<iovec> vector;
  vector.reserve(fields.size());
  for (const auto& [name, value] : fields) {
    lines.push_back(name + "=" + value);  // sd_journal_sendv(3): one "FIELD=value" per iovec
  }
  for (auto& line : lines) vector.push_back({line.data(), line.size()});
  const int result = sd_journal_sendv(vector.data(), static_cast<int>(vector.size()));
  return result < 0 ? -result : 0;
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
  append_body(out, record);
  return out;
}

std::string format_stream_line(const Record& record) {
  // sd-daemon(3): "<N>" at the start of a line sets its syslog priority.
  std::string out = "<" + std::to_string(journal_priority(record.level)) + ">";
  append_body(out, record);
  for (std::size_t i = 1; i < out.size(); ++i) {
    if (out[i] == '\n') out[i] = ' ';
  }
  return out;
}

}  // namespace liftd::log
