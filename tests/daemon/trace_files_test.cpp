// Flight-recorder files: never through a planted link, at most N kept, requests rate-limited,
// only in a directory that is ours alone.
#include "daemon/trace_files.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace liftd::daemon {
namespace {

using namespace std::chrono_literals;
using ::testing::HasSubstr;
namespace fs = std::filesystem;

class TraceFilesTest : public ::testing::Test {
 protected:
  TraceFilesTest() {
    char tmpl[] = "/tmp/liftd-trace-test-XXXXXX";
    dir_ = ::mkdtemp(tmpl);  // mode 0700, ours
  }
  ~TraceFilesTest() override { fs::remove_all(dir_); }
  static std::string read(const std::string& path) {
    std::ifstream in(path);
    std::ostringstream out;
    out << in.rdbuf();
    return out.str();
  }
  std::vector<std::string> names() const {
    std::vector<std::string> out;
    for (const auto& e : fs::directory_iterator(dir_)) out.push_back(e.path().filename());
    std::sort(out.begin(), out.end());
    return out;
  }
  std::string dir_;
};

TEST_F(TraceFilesTest, CreatesANewFileWithTheText) {
  TraceFiles files(dir_, 10);
  const TraceWrite w = files.write("20261123T214500Z", "frames\n");
  ASSERT_TRUE(w.ok()) << w.error;
  EXPECT_EQ(w.path, dir_ + "/liftd-trace-20261123T214500Z.txt");
  EXPECT_EQ(read(w.path), "frames\n");
  struct stat st {};
  ASSERT_EQ(::stat(w.path.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0640U);
  // The same second again: a new name, the first file untouched.
  const TraceWrite again = files.write("20261123T214500Z", "second\n");
  ASSERT_TRUE(again.ok()) << again.error;
  EXPECT_EQ(again.path, dir_ + "/liftd-trace-20261123T214500Z-2.txt");
  EXPECT_EQ(read(w.path), "frames\n");
}

TEST_F(TraceFilesTest, NeverWritesThroughAPlantedSymlink) {
  const std::string victim = dir_ + "-victim";
  std::ofstream(victim) << "precious";
  const std::string planted = dir_ + "/liftd-trace-20261123T214500Z.txt";
  ASSERT_EQ(::symlink(victim.c_str(), planted.c_str()), 0);
  TraceFiles files(dir_, 10);
  const TraceWrite w = files.write("20261123T214500Z", "frames\n");
  ASSERT_TRUE(w.ok()) << w.error;
  EXPECT_EQ(w.path, dir_ + "/liftd-trace-20261123T214500Z-2.txt");
  EXPECT_EQ(read(victim), "precious");
  EXPECT_TRUE(fs::is_symlink(planted));  // a link is not a trace file: not removed either
  ::unlink(victim.c_str());
}

TEST_F(TraceFilesTest, KeepsAtMostTheConfiguredNumberNewestFirst) {
  TraceFiles files(dir_, 3);
  std::ofstream(dir_ + "/notes.txt") << "not a trace";
  for (int i = 1; i <= 5; ++i) {
    const TraceWrite w = files.write("2026112" + std::to_string(i) + "T000000Z", "x");
    ASSERT_TRUE(w.ok()) << w.error;
  }
  EXPECT_EQ(names(), (std::vector<std::string>{"liftd-trace-20261123T000000Z.txt",
                                               "liftd-trace-20261124T000000Z.txt",
                                               "liftd-trace-20261125T000000Z.txt", "notes.txt"}));
}

TEST_F(TraceFilesTest, RefusesADirectoryOthersMayWriteOrALinkToOne) {
  ASSERT_EQ(::chmod(dir_.c_str(), 0777), 0);
  TraceFiles shared(dir_, 10);
  const TraceWrite w = shared.write("20261123T214500Z", "x");
  EXPECT_FALSE(w.ok());
  EXPECT_THAT(w.error, HasSubstr("must belong to liftd's user and be writable by nobody else"));
  EXPECT_TRUE(names().empty());
  ASSERT_EQ(::chmod(dir_.c_str(), 0700), 0);

  const std::string link = dir_ + "-link";
  ASSERT_EQ(::symlink(dir_.c_str(), link.c_str()), 0);
  TraceFiles via_link(link, 10);
  const TraceWrite l = via_link.write("20261123T214500Z", "x");
  EXPECT_FALSE(l.ok());
  EXPECT_THAT(l.error, HasSubstr("cannot open the directory"));
  ::unlink(link.c_str());
}

TEST_F(TraceFilesTest, RequestsAreRateLimited) {
  TraceFiles files(dir_, 10);
  const auto t0 = std::chrono::steady_clock::time_point{} + 1000s;
  EXPECT_EQ(files.admit_request(t0), std::nullopt);
  EXPECT_EQ(files.admit_request(t0 + 4s), "a trace was saved less than 10 s ago; try again in 6 s");
  EXPECT_EQ(files.admit_request(t0 + 10s), std::nullopt);
  EXPECT_NE(files.admit_request(t0 + 19s), std::nullopt);
}

}  // namespace
}  // namespace liftd::daemon
