// The SQLite calls the record's store makes everywhere (store.cpp writes, store_queries.cpp
// reads): binding a parameter, reading a column, running a statement that returns no rows,
// resetting one whatever happens. Internal to lib/record.
#pragma once

#include <sqlite3.h>

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

namespace liftd::record::sql {

// Binding helpers (not named bind: with a std::string argument, ADL would find std::bind): SQLite
// copies text with SQLITE_TRANSIENT only when the text does not outlive the step; every text bound
// here lives until the statement is reset, so it is bound static.
inline int bind_param(sqlite3_stmt* s, int index, std::int64_t value) {
  return sqlite3_bind_int64(s, index, value);
}
inline int bind_param(sqlite3_stmt* s, int index, std::optional<std::int64_t> value) {
  return value ? sqlite3_bind_int64(s, index, *value) : sqlite3_bind_null(s, index);
}
inline int bind_param(sqlite3_stmt* s, int index, std::optional<int> value) {
  return value ? sqlite3_bind_int64(s, index, *value) : sqlite3_bind_null(s, index);
}
inline int bind_param(sqlite3_stmt* s, int index, std::string_view text) {
  return sqlite3_bind_text64(s, index, text.data(), text.size(), SQLITE_STATIC, SQLITE_UTF8);
}
inline int bind_blob(sqlite3_stmt* s, int index, const void* data, std::size_t size) {
  return sqlite3_bind_blob64(s, index, data, size, SQLITE_STATIC);
}

inline std::optional<std::int64_t> column_optional(sqlite3_stmt* s, int column) {
  if (sqlite3_column_type(s, column) == SQLITE_NULL) return std::nullopt;
  return sqlite3_column_int64(s, column);
}
inline nlohmann::json column_json(sqlite3_stmt* s, int column) {
  if (sqlite3_column_type(s, column) == SQLITE_NULL) return nullptr;
  return sqlite3_column_int64(s, column);
}
inline std::string column_text(sqlite3_stmt* s, int column) {
  const unsigned char* text = sqlite3_column_text(s, column);
  const int size = sqlite3_column_bytes(s, column);
  return text ? std::string(reinterpret_cast<const char*>(text), static_cast<std::size_t>(size))
              : std::string();
}

/// Resets a statement when the scope ends, whatever happened, so it holds no read lock.
class ResetOnExit {
 public:
  explicit ResetOnExit(sqlite3_stmt* s) : s_(s) {}
  ~ResetOnExit() {
    sqlite3_reset(s_);
    sqlite3_clear_bindings(s_);
  }
  ResetOnExit(const ResetOnExit&) = delete;
  ResetOnExit& operator=(const ResetOnExit&) = delete;

 private:
  sqlite3_stmt* s_;
};

/// Runs a statement that returns no rows.
inline int run(sqlite3_stmt* s) {
  const int rc = sqlite3_step(s);
  sqlite3_reset(s);
  sqlite3_clear_bindings(s);
  return rc == SQLITE_DONE || rc == SQLITE_ROW ? SQLITE_OK : rc;
}

}  // namespace liftd::record::sql
