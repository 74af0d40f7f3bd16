// What the record's tests share: a temporary directory, travels made to order, and a look into
// the record's file with SQLite itself (not through the record under test).
#pragma once

#include <sqlite3.h>
#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <optional>
#include <string>
#include <system_error>

#include <gtest/gtest.h>

#include "record/lift_record.hpp"

namespace liftd::record::testing {

/// 2026-11-28T00:00:00Z: the day the tests' travels happen.
inline constexpr std::int64_t kDay0 = 1'795'824'000'000;

/// The monotonic clock at the record's start in most tests.
inline constexpr std::int64_t kMono0 = 1'000;

inline Options options_at(const std::string& path) {
  Options o;
  o.path = path;
  return o;
}

/// A fresh directory under $TMPDIR (or /tmp), removed with everything in it at the end.
class TempDir {
 public:
  TempDir() {
    const char* base = std::getenv("TMPDIR");
    std::string pattern = std::string(base && *base ? base : "/tmp") + "/liftd-record-XXXXXX";
    if (::mkdtemp(pattern.data()) == nullptr) ADD_FAILURE() << "mkdtemp " << pattern;
    path_ = pattern;
  }
  ~TempDir() {
    std::error_code ignored;
    std::filesystem::permissions(path_, std::filesystem::perms::owner_all,
                                 std::filesystem::perm_options::add, ignored);
    std::filesystem::remove_all(path_, ignored);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  std::string file(const std::string& name) const { return path_ + "/" + name; }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

inline std::string read_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

inline void write_bytes(const std::string& path, const std::string& bytes, std::streamoff at = 0) {
  std::fstream out(path, std::ios::binary | std::ios::in | std::ios::out);
  if (!out) out.open(path, std::ios::binary | std::ios::out);
  out.seekp(at);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

/// An ordinary arrived travel from `from` to `to`, starting `start_ms` after kDay0.
inline Travel arrived_travel(int from, int to, std::int64_t start_ms, std::int64_t duration_ms,
                             std::optional<std::int64_t> stop_error_mm = 0) {
  Travel t;
  t.start_unix_ms = kDay0 + start_ms;
  t.end_unix_ms = t.start_unix_ms + duration_ms;
  t.start_mono_ms = 5'000 + start_ms;
  t.end_mono_ms = t.start_mono_ms + duration_ms;
  t.from_floor = from;
  t.to_floor = to;
  t.end_floor = to;
  t.kind = "travel";
  t.arrived = true;
  t.cause = "arrived";
  t.duration_ms = duration_ms;
  t.top_speed_mm_s = 1000;
  t.stop_error_mm = stop_error_mm;
  return t;
}

inline Travel aborted_travel(int from, int to, std::int64_t start_ms, std::string cause) {
  Travel t = arrived_travel(from, to, start_ms, 1500, std::nullopt);
  t.arrived = false;
  t.cause = std::move(cause);
  t.end_floor.reset();
  t.top_speed_mm_s = 400;
  return t;
}

/// A connection of the test's own to a record's file, for what the record does not tell.
class Peek {
 public:
  explicit Peek(const std::string& path) {
    if (sqlite3_open_v2(path.c_str(), &db_, SQLITE_OPEN_READWRITE, nullptr) != SQLITE_OK) {
      ADD_FAILURE() << "cannot open " << path << ": " << sqlite3_errmsg(db_);
    }
  }
  ~Peek() { sqlite3_close_v2(db_); }
  Peek(const Peek&) = delete;
  Peek& operator=(const Peek&) = delete;

  /// The first column of the first row as text ("" for no row or NULL; "error: ..." on error).
  std::string text(const std::string& sql) {
    sqlite3_stmt* s = nullptr;
    if (sqlite3_prepare_v2(db_, sql.c_str(), -1, &s, nullptr) != SQLITE_OK) {
      return std::string("error: ") + sqlite3_errmsg(db_);
    }
    std::string out;
    const int rc = sqlite3_step(s);
    if (rc == SQLITE_ROW && sqlite3_column_text(s, 0)) {
      out = reinterpret_cast<const char*>(sqlite3_column_text(s, 0));
    } else if (rc != SQLITE_ROW && rc != SQLITE_DONE) {
      out = std::string("error: ") + sqlite3_errmsg(db_);
    }
    sqlite3_finalize(s);
    return out;
  }
  std::int64_t number(const std::string& sql) {
    return std::strtoll(text(sql).c_str(), nullptr, 10);
  }
  bool exec(const std::string& sql) {
    return sqlite3_exec(db_, sql.c_str(), nullptr, nullptr, nullptr) == SQLITE_OK;
  }

 private:
  sqlite3* db_ = nullptr;
};

}  // namespace liftd::record::testing
