// What the journal sink writes: the fields of one record (pure, table-tested), the stderr line
// forms, and the send itself through libsystemd's sd_journal_sendv(3).
#pragma once

#include <chrono>
#include <optional>
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
  std::optional<Catalogued> catalogued;  ///< gives MESSAGE_ID; unset for uncatalogued records
};

/// One journal field: name (A-Z, 0-9, _) and value.
using JournalField = std::pair<std::string, std::string>;

/// The syslog priority of a level (journald's PRIORITY): error 3, warn 4, info 6, debug and
/// trace 7 (syslog has nothing below debug).
int journal_priority(Level level);

/// Turns an extra field's key into a journal field name: "cause" -> "LIFTD_CAUSE". Characters
/// outside A-Z 0-9 _ become _, and the name is cut to journald's 64-character limit.
std::string journal_field_name(std::string_view key);

/// The fields of one record, in order: MESSAGE, PRIORITY, MESSAGE_ID (the id of its catalog key,
/// when it has one: catalog.hpp; never looked up by event name or field text), SYSLOG_IDENTIFIER,
/// LIFTD_COMPONENT, LIFTD_EVENT (when set), the extra fields, CODE_FILE/CODE_LINE/CODE_FUNC (when
/// known).
std::vector<JournalField> journal_fields(const Record& record, std::string_view identifier);

/// Sends the fields as one journal entry with sd_journal_sendv(3); returns 0 or the errno of
/// the failure (ENOENT when no journald listens on this machine).
int send_to_journal(const std::vector<JournalField>& fields);

/// One readable line for a terminal: "2026-11-22 03:00:43.123 WARN  dcp: text [event=... k=v]".
std::string format_text_line(const Record& record, std::chrono::system_clock::time_point when);

/// One line for a stderr that journald (or syslog) reads: the priority as an sd-daemon(3)
/// prefix, no time stamp (the reader adds its own): "<4>dcp: text [event=... k=v]". Newlines
/// in the text become spaces, so one record stays one line.
std::string format_stream_line(const Record& record);

}  // namespace liftd::log
