// The record's failures (issue #42): a file it cannot create, a damaged file, a newer schema, a
// full record. Each leaves the record off with a reason that says what and where, one journal
// line, and calls that do no I/O from then on. The tests run as root on the build machine, where
// permissions stop nothing: the unwritable places here are ones root cannot write either (a
// path through a regular file, procfs); the read-only file as another user is in
// record_process_test.
#include <fcntl.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <string>

#include <gtest/gtest.h>

#include "log/log.hpp"
#include "record/lift_record.hpp"
#include "record_fixture.hpp"

namespace liftd::record {
namespace {

using nlohmann::json;
using testing::arrived_travel;
using testing::kDay0;
using testing::kMono0;
using testing::options_at;
using testing::Peek;
using testing::read_bytes;
using testing::TempDir;
using testing::write_bytes;

/// 2026-11-28T01:02:03Z: the moment the damaged files are found.
constexpr std::int64_t kFound = kDay0 + 3'723'000;

/// Everything written to stderr while it lives (where the text log backend writes).
class CapturedStderr {
 public:
  explicit CapturedStderr(const std::string& file) : file_(file) {
    std::fflush(stderr);
    saved_ = ::dup(2);
    const int fd = ::open(file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
    ::dup2(fd, 2);
    ::close(fd);
    log::init({log::Level::info, log::Backend::text, "liftd-test"});
  }
  ~CapturedStderr() { restore(); }
  CapturedStderr(const CapturedStderr&) = delete;
  CapturedStderr& operator=(const CapturedStderr&) = delete;
  /// Stops capturing and gives what was written.
  std::string text() {
    restore();
    return read_bytes(file_);
  }

 private:
  void restore() {
    if (saved_ < 0) return;
    log::flush();
    std::fflush(stderr);
    ::dup2(saved_, 2);
    ::close(saved_);
    saved_ = -1;
  }
  std::string file_;
  int saved_ = -1;
};

std::size_t occurrences(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

/// Calls every write of the record; an off record must take them all without touching the disk.
void use(LiftRecord& record) {
  record.travel(arrived_travel(0, 1, 0, 3000), kMono0 + 10, kDay0 + 10);
  record.fault_raised("drive_fault", kMono0 + 20);
  record.link_lost(kMono0 + 30);
  record.inputs({.doors_locked = true}, kMono0 + 40);
  record.tick(kMono0 + 1'000'000, kDay0 + 1'000'000);
  EXPECT_TRUE(record.reset({"faults.*"}, "test", kDay0 + 1'000'001)
                  .error.ends_with(record.status_json()["reason"].get<std::string>()));
}

void expect_off_and_inert(LiftRecord& record, const std::string& reason) {
  EXPECT_FALSE(record.on());
  EXPECT_EQ(record.status_json()["state"], "off");
  EXPECT_EQ(record.status_json()["reason"], reason);
  EXPECT_EQ(record.status_json()["travels"], 0);
  use(record);
  EXPECT_EQ(record.status_json()["reason"], reason);
  EXPECT_EQ(record.history_json({}), json::parse(R"({"travels":[],"count":0,"truncated":false,
                                                    "record":"off"})"));
  EXPECT_EQ(record.trend_json({}), json::parse(R"({"days":[],"pairs":[],"record":"off"})"));
  // The counters go on in memory, for the API, until the next start.
  const json counters = record.counters_json();
  EXPECT_EQ(counters["record"], "off");
  EXPECT_EQ(counters["counters"]["travels"], 1);
  EXPECT_EQ(counters["counters"]["link_losses"], 1);
}

TEST(RecordFailure, no_path_is_off_with_that_reason) {
  LiftRecord record(Options{}, kMono0, kDay0);
  EXPECT_EQ(record.status_json(), json::parse(R"({"state":"off","path":"",
      "reason":"record.path is not set","travels":0})"));
  expect_off_and_inert(record, "record.path is not set");
}

TEST(RecordFailure, a_missing_directory_is_named_with_what_to_do) {
  TempDir dir;
  const std::string path = dir.file("missing/record.db");
  LiftRecord record(options_at(path), kMono0, kDay0);
  expect_off_and_inert(record,
                       "cannot open or create " + path +
                           " (opening the file: unable to open database file (No such file or "
                           "directory)): check that its directory exists and that liftd may "
                           "write there (the unit's StateDirectory=)");
  EXPECT_FALSE(std::filesystem::exists(dir.file("missing")));
}

TEST(RecordFailure, a_directory_that_is_a_regular_file_cannot_hold_a_record) {
  TempDir dir;
  write_bytes(dir.file("afile"), "not a directory\n");
  const std::string path = dir.file("afile/record.db");
  LiftRecord record(options_at(path), kMono0, kDay0);
  expect_off_and_inert(record,
                       "cannot open or create " + path +
                           " (opening the file: unable to open database file (Not a "
                           "directory)): check that its directory exists and that liftd may "
                           "write there (the unit's StateDirectory=)");
  EXPECT_EQ(read_bytes(dir.file("afile")), "not a directory\n");
}

TEST(RecordFailure, a_directory_even_root_cannot_write) {
  // procfs takes no new files, whoever asks.
  const std::string path = "/proc/self/record.db";
  LiftRecord record(options_at(path), kMono0, kDay0);
  EXPECT_FALSE(record.on());
  const std::string reason = record.status_json()["reason"].get<std::string>();
  EXPECT_TRUE(reason.starts_with("cannot open or create /proc/self/record.db (opening the file: "))
      << reason;
  expect_off_and_inert(record, reason);
}

/// Expects the damaged file moved aside with its bytes as found and the record off, saying so.
void expect_moved_aside(const TempDir& dir, const std::string& bytes, const std::string& detail) {
  const std::string path = dir.file("record.db");
  const std::string aside = path + ".corrupt-20261128T010203Z";
  CapturedStderr journal(dir.file("stderr.txt"));
  {
    LiftRecord record(options_at(path), kMono0, kFound);
    expect_off_and_inert(record, path + " is damaged (" + detail + "): moved aside to " + aside +
                                     "; the next start of liftd creates a new record");
  }
  const std::string lines = journal.text();
  EXPECT_EQ(occurrences(lines, "the lift's record is off"), 1U) << lines;
  // In the text, the moved_to field and the reason field.
  EXPECT_EQ(occurrences(lines, aside), 3U) << lines;
  EXPECT_FALSE(std::filesystem::exists(path));
  EXPECT_FALSE(std::filesystem::exists(path + "-wal"));
  EXPECT_EQ(read_bytes(aside), bytes);
  // The next start creates a new record beside the damaged one.
  LiftRecord next(options_at(path), kMono0, kFound + 1000);
  EXPECT_TRUE(next.on()) << next.status_json().dump();
  EXPECT_EQ(next.status_json()["travels"], 0);
  EXPECT_EQ(read_bytes(aside), bytes);
}

TEST(RecordFailure, a_file_of_text_is_moved_aside) {
  TempDir dir;
  std::string text;
  for (int i = 0; i < 300; ++i)
    text += "line " + std::to_string(i) + " of a file that is no database\n";
  write_bytes(dir.file("record.db"), text);
  expect_moved_aside(dir, text, "reading the schema version: file is not a database");
}

TEST(RecordFailure, a_record_with_damaged_pages_is_moved_aside) {
  TempDir dir;
  {
    LiftRecord record(options_at(dir.file("record.db")), kMono0, kDay0);
    for (int i = 0; i < 200; ++i) {
      Travel t = arrived_travel(i % 4, (i + 1) % 4, i * 10'000, 3000);
      t.curve_json = std::string(2000, 'x');
      record.travel(std::move(t), kMono0, kDay0);
    }
  }
  ASSERT_FALSE(std::filesystem::exists(dir.file("record.db-wal")));  // checkpointed on close
  // Garbage over every page after the first (which keeps the header and the schema).
  std::string bytes = read_bytes(dir.file("record.db"));
  ASSERT_GT(bytes.size(), 16U * 4096U);
  for (std::size_t i = 4096; i < bytes.size(); ++i) {
    bytes[i] = static_cast<char>((i * 2654435761U) >> 13);
  }
  write_bytes(dir.file("record.db"), bytes);
  const std::string path = dir.file("record.db");
  const std::string aside = path + ".corrupt-20261128T010203Z";
  CapturedStderr journal(dir.file("stderr.txt"));
  std::string reason;
  {
    LiftRecord record(options_at(path), kMono0, kFound);
    EXPECT_FALSE(record.on());
    reason = record.status_json()["reason"].get<std::string>();
  }
  journal.text();
  EXPECT_TRUE(reason.starts_with(path + " is damaged (")) << reason;
  EXPECT_TRUE(reason.ends_with("): moved aside to " + aside +
                               "; the next start of liftd creates a new record"))
      << reason;
  EXPECT_EQ(read_bytes(aside), bytes);
  EXPECT_FALSE(std::filesystem::exists(path));
}

TEST(RecordFailure, a_damaged_file_is_never_moved_over_another) {
  TempDir dir;
  const std::string path = dir.file("record.db");
  const std::string aside = path + ".corrupt-20261128T010203Z";
  write_bytes(path, std::string(8192, 'z'));
  write_bytes(aside, "found earlier");
  LiftRecord record(options_at(path), kMono0, kFound);
  expect_off_and_inert(record, path +
                                   " is damaged (reading the schema version: file is not a "
                                   "database) and could not be moved "
                                   "aside to " +
                                   aside +
                                   " (File exists): move it away by hand, then restart liftd");
  EXPECT_EQ(read_bytes(aside), "found earlier");
  EXPECT_EQ(read_bytes(path), std::string(8192, 'z'));
}

TEST(RecordFailure, a_record_of_a_newer_schema_is_left_untouched) {
  TempDir dir;
  const std::string path = dir.file("record.db");
  {
    LiftRecord record(options_at(path), kMono0, kDay0);
    record.travel(arrived_travel(0, 1, 0, 3000), kMono0, kDay0);
  }
  {
    Peek peek(path);
    ASSERT_TRUE(peek.exec("PRAGMA user_version = 99"));
  }
  const std::string bytes = read_bytes(path);
  LiftRecord record(options_at(path), kMono0, kFound);
  expect_off_and_inert(record, path +
                                   " was written by a newer liftd (reading the schema version: "
                                   "schema version 99, this liftd knows 1 and older): left "
                                   "untouched; run that liftd, or move the file away to start a "
                                   "new record");
  EXPECT_EQ(read_bytes(path), bytes);
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.path()),
                          std::filesystem::directory_iterator()),
            1);
}

TEST(RecordFailure, a_database_that_is_no_record_is_left_untouched) {
  TempDir dir;
  const std::string path = dir.file("other.db");
  {
    sqlite3* db = nullptr;
    sqlite3_open(path.c_str(), &db);
    sqlite3_exec(db, "CREATE TABLE inventory(item TEXT)", nullptr, nullptr, nullptr);
    sqlite3_close(db);
  }
  const std::string bytes = read_bytes(path);
  LiftRecord record(options_at(path), kMono0, kDay0);
  expect_off_and_inert(record, path +
                                   " is not a record this liftd can use (reading the schema: the "
                                   "file is an SQLite database with 1 tables but no liftd schema "
                                   "version: not a liftd record): left untouched; move it away or "
                                   "set record.path to another file");
  EXPECT_EQ(read_bytes(path), bytes);
}

TEST(RecordFailure, a_full_record_turns_off_once_and_keeps_what_it_had) {
  // SQLITE_FULL from a bound on the file's pages (max_page_count): the same error a full disk
  // gives, in process and at the same travel on every run. A full disk itself (write(2) failing)
  // is in record_process_test.
  TempDir dir;
  const std::string path = dir.file("record.db");
  Options options = options_at(path);
  options.max_bytes = 40 * 1024;
  CapturedStderr journal(dir.file("stderr.txt"));
  std::string reason;
  int written = 0;
  {
    LiftRecord record(options, kMono0, kDay0);
    ASSERT_TRUE(record.on());
    for (int i = 0; i < 100 && record.on(); ++i) {
      Travel t = arrived_travel(0, 1, i * 10'000, 3000);
      t.curve_json = std::string(8000, 'c');
      record.travel(std::move(t), kMono0, kDay0);
      if (record.on()) ++written;
    }
    ASSERT_FALSE(record.on());
    reason = record.status_json()["reason"].get<std::string>();
    for (int i = 0; i < 10; ++i) use(record);
  }
  const std::string lines = journal.text();
  EXPECT_EQ(reason, "the storage holding " + path +
                        " is full (writing a travel: database or disk is full, or the record "
                        "reached its max_bytes): free space there; the record stays off until "
                        "liftd starts again");
  EXPECT_EQ(occurrences(lines, "the lift's record is off"), 1U) << lines;
  EXPECT_GT(written, 0);
  // What was committed stays: the failed travel's transaction left nothing behind.
  Peek peek(path);
  EXPECT_EQ(peek.text("PRAGMA integrity_check"), "ok");
  EXPECT_EQ(peek.number("SELECT count(*) FROM travels"), written);
  EXPECT_EQ(peek.number("SELECT value FROM counters WHERE name = 'travels'"), written);
}

}  // namespace
}  // namespace liftd::record
