// Flight-recorder files: never through a planted link, at most N kept, requests rate-limited,
// only in a directory that is ours alone.
#include "host/trace_files.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
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

// The one path every drive kind's `trace` save and SIGUSR1 take: the recorder's records as text
// in a new file, with the drive's decoded column where it has one, under the same rate limit.
TEST_F(TraceFilesTest, FlightRecorderFilesWriteTheRecorderForAnyDriveKind) {
  rt::FlightRecorder recorder(16, rt::kCanRecordBytes);
  const std::array<std::uint8_t, 4> answer = {0x05, 0x51, 0x68, 0x00};  // SCH001 3c, id first
  const std::array<std::uint8_t, 4> status = {0x05, 0x81, 0x61, 0x02};  // SCH001 3b
  recorder.record(MonoTime(1s), rt::Direction::Rx, rt::record_flag::kReply, status);
  recorder.record(MonoTime(1s + 1ms), rt::Direction::Tx, rt::record_flag::kSent, answer);
  FlightRecorderFiles files(recorder, dir_, 10, "sch001");
  const api::Result written = files.write("SIGUSR1");
  ASSERT_TRUE(written.is_ok());
  const std::string path = written.value().at("file");
  EXPECT_EQ(path.rfind(dir_ + "/liftd-trace-", 0), 0U) << path;
  EXPECT_EQ(written.value().at("records"), 2);
  const std::string text = read(path);
  EXPECT_THAT(text, HasSubstr("rx 05 81 61 02"));
  EXPECT_THAT(text, HasSubstr("tx 05 51 68 00"));
  EXPECT_EQ(text.find(" | "), std::string::npos) << "no decoder, no decoded column";

  // With a decoder (as the DCP lift has), its column; requests rate-limited as TraceFiles does.
  FlightRecorderFiles decoded(recorder, dir_, 10, "dcp", [] {
    return rt::FrameDecoder([](const rt::FrameRecord& r) {
      return std::string(r.direction == rt::Direction::Tx ? "ours" : "theirs");
    });
  });
  const auto now = std::chrono::steady_clock::now();
  const api::Result saved = decoded.save_requested(now);
  ASSERT_TRUE(saved.is_ok());
  EXPECT_THAT(read(saved.value().at("file")), HasSubstr("| theirs"));
  const api::Result again = decoded.save_requested(now + 1s);
  ASSERT_FALSE(again.is_ok());
  EXPECT_EQ(again.error().code, api::ErrorCode::Busy);
}

TEST_F(TraceFilesTest, FlightRecorderFilesSayWhyTheyCouldNotWrite) {
  rt::FlightRecorder recorder(4, rt::kUssRecordBytes);
  FlightRecorderFiles files(recorder, dir_ + "/missing", 10, "uss");
  const api::Result r = files.write("request");
  ASSERT_FALSE(r.is_ok());
  EXPECT_EQ(r.error().code, api::ErrorCode::Internal);
  EXPECT_THAT(r.error().message, HasSubstr("could not write the flight recorder"));
}

// ---- the API's trace: which frames pair into one exchange ----

rt::FrameRecord frame(rt::Direction direction, std::uint8_t first_byte, std::uint8_t flags = 0) {
  rt::FrameRecord r;
  r.time = MonoTime{std::chrono::milliseconds(first_byte)};
  r.direction = direction;
  r.flags = flags;
  r.length = direction == rt::Direction::Event ? 0 : 2;
  r.bytes = {first_byte, 0xEE, 0x00};  // padded beyond the length, as the recorder stores it
  return r;
}
rt::FrameRecord tx(std::uint8_t b) {
  return frame(rt::Direction::Tx, b);
}
rt::FrameRecord rx(std::uint8_t b, std::uint8_t flags = 0) {
  return frame(rt::Direction::Rx, b, flags);
}
rt::FrameRecord event() {
  return frame(rt::Direction::Event, 0);
}

/// Each exchange as "tx/rx" by first bytes, "-" for no rx.
std::vector<std::string> exchanges(const std::vector<api::TraceEntry>& entries) {
  std::vector<std::string> out;
  for (const api::TraceEntry& e : entries) {
    EXPECT_EQ(e.tx.size(), 2U) << "only the frame's own bytes";
    out.push_back(std::to_string(e.tx[0]) + "/" + (e.rx ? std::to_string((*e.rx)[0]) : "-"));
  }
  return out;
}

TEST(TraceExchanges, AReplyPairsWithTheFrameBeforeItOnceAndEventsPairWithNothing) {
  // DCP 7.2 and USS: the slave's reply follows the master's frame; a second frame of theirs
  // before our next one answers nothing of ours.
  const std::vector<rt::FrameRecord> records{rx(9), tx(1),   rx(2), event(), rx(3),
                                             tx(4), event(), tx(5), rx(6)};
  EXPECT_THAT(exchanges(trace_exchanges(records, 10, {.we_answer = false})),
              ::testing::ElementsAre("1/2", "4/-", "5/6"));
}

TEST(TraceExchanges, OurAnswerPairsWithTheirLastFrameBeforeIt) {
  // SCH001 (card document 3c): liftd answers the card's status that came before.
  const std::vector<rt::FrameRecord> records{rx(1), rx(2), event(), tx(3), tx(4), rx(5), tx(6)};
  EXPECT_THAT(exchanges(trace_exchanges(records, 10, {.we_answer = true})),
              ::testing::ElementsAre("3/2", "4/-", "6/5"));
}

TEST(TraceExchanges, FramesTheFiltersRefuseTakeNoPart) {
  static constexpr TracePairing kOddOnes{
      .we_answer = false,
      .ours = [](const rt::FrameRecord& r) { return r.bytes[0] % 2 == 1; },
      .theirs = [](const rt::FrameRecord& r) { return (r.flags & 0x02) != 0; },
  };
  const std::vector<rt::FrameRecord> records{tx(1),       rx(2), rx(4, 0x02), tx(6),
                                             rx(8, 0x02), tx(3), rx(10, 0x06)};
  EXPECT_THAT(exchanges(trace_exchanges(records, 10, kOddOnes)),
              ::testing::ElementsAre("1/4", "3/10"))
      << "rx 8 follows a frame of ours the filter refused: it answers 1, which has its reply";
}

TEST(TraceExchanges, KeepsTheNewestOldestFirst) {
  const std::vector<rt::FrameRecord> records{tx(1), rx(2), tx(3), rx(4), tx(5), rx(6)};
  EXPECT_THAT(exchanges(trace_exchanges(records, 2, {})), ::testing::ElementsAre("3/4", "5/6"));
  EXPECT_TRUE(trace_exchanges(records, 0, {}).empty());
  EXPECT_TRUE(trace_exchanges({}, 5, {}).empty());
}

}  // namespace
}  // namespace liftd::daemon
