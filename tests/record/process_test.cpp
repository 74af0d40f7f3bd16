// The record against what only another process can show (issue #42): a writer killed at any
// moment leaves a whole record, a file another user may not write, and a write(2) that fails as
// on a full disk. Each case forks; the child reports through its exit status or a pipe.
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "record/lift_record.hpp"
#include "record_fixture.hpp"

namespace liftd::record {
namespace {

using testing::arrived_travel;
using testing::kDay0;
using testing::kMono0;
using testing::options_at;
using testing::Peek;
using testing::TempDir;

/// Runs `body` in a child process and gives what it wrote to the pipe (its first argument) and
/// its wait status.
template <typename Body>
std::pair<std::string, int> in_child(Body body) {
  int fds[2];
  if (::pipe(fds) != 0) return {"pipe failed", -1};
  const pid_t child = ::fork();
  if (child == 0) {
    ::close(fds[0]);
    body(fds[1]);
    ::_exit(0);
  }
  ::close(fds[1]);
  std::string said;
  char buffer[512];
  for (ssize_t n; (n = ::read(fds[0], buffer, sizeof buffer)) > 0;) {
    said.append(buffer, static_cast<std::size_t>(n));
  }
  ::close(fds[0]);
  int status = 0;
  ::waitpid(child, &status, 0);
  return {said, status};
}

void say(int fd, const std::string& text) {
  for (std::size_t done = 0; done < text.size();) {
    const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n <= 0) return;
    done += static_cast<std::size_t>(n);
  }
}

/// Travels kept and the `travels` counter, as a connection of the test's own reads them.
std::pair<std::int64_t, std::int64_t> rows_and_counter(Peek& peek) {
  if (peek.number("SELECT count(*) FROM sqlite_schema WHERE name = 'travels'") == 0) return {0, 0};
  return {peek.number("SELECT count(*) FROM travels"),
          peek.number("SELECT value FROM counters WHERE name = 'travels'")};
}

TEST(RecordProcess, a_writer_killed_at_any_moment_leaves_a_whole_record) {
  // 100 writers in turn on one file, each killed with SIGKILL after a random 0..30 ms (seeded,
  // so a failure repeats): mid-open, mid-transaction, mid-checkpoint. After each, SQLite's own
  // integrity check passes, and the travels counter, written in the travel's transaction, equals
  // the rows kept (the issue allows one apart; one transaction makes it none).
  TempDir dir;
  const std::string path = dir.file("record.db");
  std::mt19937 random(4242);
  std::uniform_int_distribution<int> delay_us(0, 30'000);
  std::int64_t rows_before = 0;
  for (int round = 0; round < 100; ++round) {
    SCOPED_TRACE("round " + std::to_string(round));
    const pid_t child = ::fork();
    if (child == 0) {
      LiftRecord record(options_at(path), kMono0, kDay0);
      if (!record.on()) ::_exit(3);
      for (std::int64_t i = 0;; ++i) {
        Travel t = arrived_travel(static_cast<int>(i % 5), static_cast<int>((i + 1) % 5),
                                  i * 10'000, 3000, i % 7 - 3);
        t.curve_json = std::string(2000, 'c');
        record.travel(std::move(t), kMono0 + i, kDay0 + i);
        record.inputs({.doors_locked = i % 2 == 0}, kMono0 + i);
        record.tick(kMono0 + i * 100'000, kDay0 + i);  // a counters write between travels
        if (!record.on()) ::_exit(4);
      }
    }
    ::usleep(static_cast<useconds_t>(delay_us(random)));
    ::kill(child, SIGKILL);
    int status = 0;
    ::waitpid(child, &status, 0);
    ASSERT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL)
        << "the writer ended by itself, exit status " << WEXITSTATUS(status)
        << " (3: the record was off at start, 4: a write failed)";
    Peek peek(path);
    ASSERT_EQ(peek.text("PRAGMA integrity_check"), "ok");
    const auto [rows, counter] = rows_and_counter(peek);
    EXPECT_EQ(counter, rows);
    EXPECT_GE(rows, rows_before);
    rows_before = rows;
  }
  EXPECT_GT(rows_before, 100);  // the writers did write
}

TEST(RecordProcess, a_file_its_user_may_not_write_is_named_with_what_to_do) {
  // Permissions stop only a user other than root (root writes a 0444 file in a 0555 directory),
  // so the child takes the user "nobody" when the test runs as root, as liftd runs as its own
  // user.
  TempDir dir;
  std::filesystem::permissions(dir.path(), std::filesystem::perms::all ^
                                               std::filesystem::perms::group_write ^
                                               std::filesystem::perms::others_write);
  std::filesystem::create_directory(dir.file("ro"));
  const std::string path = dir.file("ro/record.db");
  {
    LiftRecord record(options_at(path), kMono0, kDay0);
    record.travel(arrived_travel(0, 1, 0, 3000), kMono0, kDay0);
  }
  ::chmod(path.c_str(), 0444);
  ::chmod(dir.file("ro").c_str(), 0555);
  const auto open_as_nobody = [&path](int fd) {
    if (::geteuid() == 0 && (::setgid(65534) != 0 || ::setuid(65534) != 0)) {
      say(fd, "could not become nobody");
      return;
    }
    LiftRecord record(options_at(path), kMono0, kDay0);
    say(fd, record.on() ? "on" : record.status_json()["reason"].get<std::string>());
  };
  auto [reason, status] = in_child(open_as_nobody);
  EXPECT_EQ(status, 0);
  EXPECT_EQ(reason, path +
                        " cannot be written (opening the file: the file can only be opened for "
                        "reading): make the file and its directory writable for liftd");

  // A file it may write in a directory it may not: the log beside the file cannot be made.
  ::chmod(path.c_str(), 0666);
  std::tie(reason, status) = in_child(open_as_nobody);
  EXPECT_EQ(status, 0);
  EXPECT_EQ(reason, path +
                        " cannot be written (reading the schema version: attempt to write a "
                        "readonly database): make the file and its directory writable for liftd");
  ::chmod(dir.file("ro").c_str(), 0755);  // so that a user other than root can clean up
}

TEST(RecordProcess, a_write_that_fails_as_on_a_full_disk_turns_the_record_off) {
  // A limit on the file size (RLIMIT_FSIZE, with SIGXFSZ ignored) makes write(2) fail past it
  // the way a full disk does (EFBIG instead of ENOSPC): SQLite reports the failed write and the
  // record turns off, keeping every transaction committed before.
  TempDir dir;
  const std::string path = dir.file("record.db");
  auto [said, status] = in_child([&path](int fd) {
    ::signal(SIGXFSZ, SIG_IGN);
    LiftRecord record(options_at(path), kMono0, kDay0);
    int written = 0;
    for (; written < 20; ++written) {
      record.travel(arrived_travel(0, 1, written * 10'000, 3000), kMono0, kDay0);
    }
    struct stat db {};
    struct stat wal {};
    ::stat(path.c_str(), &db);
    ::stat((path + "-wal").c_str(), &wal);
    const auto limit = static_cast<rlim_t>(std::max(db.st_size, wal.st_size) + 64 * 1024);
    const rlimit file_size{limit, limit};
    ::setrlimit(RLIMIT_FSIZE, &file_size);
    for (int i = 0; i < 1000 && record.on(); ++i) {
      Travel t = arrived_travel(1, 0, (20 + i) * 10'000, 3000);
      t.curve_json = std::string(8000, 'c');
      record.travel(std::move(t), kMono0, kDay0);
      if (record.on()) ++written;
    }
    say(fd, std::to_string(written) + "\n" +
                (record.on() ? "on" : record.status_json()["reason"].get<std::string>()));
  });
  EXPECT_EQ(status, 0);
  const auto newline = said.find('\n');
  ASSERT_NE(newline, std::string::npos) << said;
  const std::int64_t written = std::stoll(said.substr(0, newline));
  const std::string reason = said.substr(newline + 1);
  EXPECT_GT(written, 20);
  EXPECT_TRUE(reason.starts_with("the storage holding " + path + " ")) << reason;
  EXPECT_TRUE(reason.ends_with("the record stays off until liftd starts again")) << reason;
  // A write cut short at the limit is SQLITE_FULL, one refused outright SQLITE_IOERR_WRITE: which
  // one comes depends on where the limit falls in a page, and both mean the same here.
  EXPECT_TRUE(reason.find(" is full (writing a travel: database or disk is full)") !=
                  std::string::npos ||
              reason.find(" failed a read or write (writing a travel: disk I/O error, a write "
                          "failed)") != std::string::npos)
      << reason;
  EXPECT_FALSE(std::filesystem::exists(path + ".corrupt-20261128T000000Z"));
  // A later start (the limit gone) finds every committed travel and goes on.
  Peek peek(path);
  EXPECT_EQ(peek.text("PRAGMA integrity_check"), "ok");
  EXPECT_EQ(rows_and_counter(peek), std::make_pair(written, written));
  LiftRecord again(options_at(path), kMono0, kDay0);
  EXPECT_TRUE(again.on()) << again.status_json().dump();
  EXPECT_EQ(again.status_json()["travels"], written);
}

}  // namespace
}  // namespace liftd::record
