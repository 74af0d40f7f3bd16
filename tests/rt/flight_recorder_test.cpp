// FlightRecorder: ring wrap-around, exact text lines, and consistent copies under a writer.
#include "rt/flight_recorder.hpp"

#include <gtest/gtest.h>

#include <unistd.h>
#include <array>
#include <atomic>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <thread>

namespace liftd::rt {
namespace {

using std::chrono::milliseconds;
using std::chrono::seconds;

TEST(RtFlightRecorder, KeepsOnlyTheNewestRecordsOldestFirst) {
  FlightRecorder rec(4, kDcpRecordBytes);
  for (std::uint8_t i = 0; i < 10; ++i) {
    const std::array<std::uint8_t, 1> b{i};
    rec.record(milliseconds(i), Direction::Tx, record_flag::kSent, b);
  }
  const auto copy = rec.copy();
  ASSERT_EQ(copy.size(), 4U);
  for (std::size_t k = 0; k < 4; ++k) {
    EXPECT_EQ(copy[k].bytes[0], 6 + k);
    EXPECT_EQ(copy[k].time, milliseconds(6 + static_cast<int>(k)));
  }
  EXPECT_EQ(rec.total_records(), 10U);
}

TEST(RtFlightRecorder, WritesOneReadableLinePerFrame) {
  // Legend: a sent DCP-sized frame, a bad reply with a decoder column, a partial (missing)
  // reply of two bytes, and a byte-less port-lost event.
  FlightRecorder rec(8, kDcpRecordBytes);
  const std::array<std::uint8_t, 6> tx{0x09, 0x00, 0x80, 0x02, 0x1C, 0x97};
  const std::array<std::uint8_t, 6> rx{0x61, 0x80, 0x07, 0x49, 0x30, 0x00};
  const std::array<std::uint8_t, 2> part{0x61, 0x80};
  rec.record(seconds(12) + milliseconds(345), Direction::Tx, record_flag::kSent, tx);
  rec.record(seconds(12) + milliseconds(347), Direction::Rx,
             record_flag::kReply | record_flag::kBad, rx);
  rec.record(seconds(12) + milliseconds(360), Direction::Rx,
             record_flag::kMissing | record_flag::kPartial, part);
  rec.record(seconds(13), Direction::Event, record_flag::kPortLost, {});
  std::ostringstream out;
  write_text(out, rec.copy(), [](const FrameRecord& r) {
    return r.direction == Direction::Rx && r.length == 6 ? std::string("status 0x61")
                                                         : std::string();
  });
  EXPECT_EQ(out.str(),
            "# liftd flight recorder: monotonic seconds, direction, bytes (hex), flags\n"
            "12.345000 tx 09 00 80 02 1C 97  sent\n"
            "12.347000 rx 61 80 07 49 30 00  reply|bad | status 0x61\n"
            "12.360000 rx 61 80              missing|partial\n"
            "13.000000 --                    port-lost\n");
}

TEST(RtFlightRecorder, CutsLongFramesButKeepsTheirLength) {
  FlightRecorder rec(2, kDcpRecordBytes);
  std::array<std::uint8_t, 40> big{};
  for (std::size_t i = 0; i < big.size(); ++i) big[i] = static_cast<std::uint8_t>(i);
  rec.record(seconds(1), Direction::Tx, record_flag::kSent, big);
  const auto copy = rec.copy();
  ASSERT_EQ(copy.size(), 1U);
  EXPECT_EQ(copy[0].length, 40);
  EXPECT_EQ(copy[0].data().size(), kDcpRecordBytes);
  EXPECT_EQ(copy[0].bytes[15], 15);
}

TEST(RtFlightRecorder, RecordsAreSizedForTheirLinksLongestFrame) {
  // A whole USS telegram of 256 bytes (LGE 254) and a CAN record (identifier + 8 data bytes)
  // are kept whole in recorders sized for their link; a DCP-sized recorder cuts them.
  std::array<std::uint8_t, kUssRecordBytes> telegram{};
  for (std::size_t i = 0; i < telegram.size(); ++i) telegram[i] = static_cast<std::uint8_t>(i);
  FlightRecorder uss(4, kUssRecordBytes);
  uss.record(seconds(1), Direction::Tx, record_flag::kSent, telegram);
  uss.record(seconds(2), Direction::Rx, record_flag::kReply, std::span(telegram).first(5));
  const auto copy = uss.copy();
  ASSERT_EQ(copy.size(), 2U);
  ASSERT_EQ(copy[0].data().size(), 256U);
  EXPECT_EQ(copy[0].data()[255], 255);
  EXPECT_EQ(copy[1].data().size(), 5U) << "a short record after a long one carries only its own";
  EXPECT_EQ(copy[1].bytes[5], 0) << "nothing of the longer record before it shows through";
  FlightRecorder can(4, kCanRecordBytes);
  can.record(seconds(1), Direction::Rx, record_flag::kReply, std::span(telegram).first(10));
  EXPECT_EQ(can.copy()[0].data().size(), 10U);
  FlightRecorder dcp(4, kDcpRecordBytes);
  dcp.record(seconds(1), Direction::Tx, record_flag::kSent, telegram);
  EXPECT_EQ(dcp.copy()[0].data().size(), kDcpRecordBytes);
  EXPECT_EQ(dcp.copy()[0].length, 256);
}

TEST(RtFlightRecorder, WritesAFile) {
  FlightRecorder rec(2, kDcpRecordBytes);
  const std::array<std::uint8_t, 1> b{0xAB};
  rec.record(seconds(2), Direction::Tx, record_flag::kSent, b);
  const std::string path = "/tmp/liftd-rt-recorder-" + std::to_string(getpid()) + ".txt";
  ASSERT_EQ(write_text_file(path, rec.copy()), 0);
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_NE(text.str().find("2.000000 tx AB"), std::string::npos);
  std::remove(path.c_str());
  EXPECT_NE(write_text_file("/nonexistent-dir/x.txt", rec.copy()), 0);
}

TEST(RtFlightRecorder, CopiesAreNeverTornWhileTheWriterRuns) {
  // The writer stores frames whose 6 bytes all equal the low byte of the record number and
  // whose time is that number; a copy must only ever contain such consistent records, in order.
  FlightRecorder rec(64, kDcpRecordBytes);
  std::atomic<bool> done{false};
  std::thread writer([&] {
    for (std::uint32_t n = 0; n < 200000; ++n) {
      std::array<std::uint8_t, 6> b{};
      b.fill(static_cast<std::uint8_t>(n));
      rec.record(MonoTime(n), Direction::Rx, record_flag::kReply, b);
    }
    done.store(true);
  });
  std::uint64_t torn = 0;
  std::uint64_t disorder = 0;
  std::uint64_t copies = 0;
  while (!done.load() || copies == 0) {
    const auto copy = rec.copy();
    ++copies;
    for (std::size_t i = 0; i < copy.size(); ++i) {
      const auto n = static_cast<std::uint8_t>(copy[i].time.count());
      for (std::size_t k = 0; k < 6; ++k) {
        if (copy[i].bytes[k] != n) ++torn;
      }
      if (i > 0 && copy[i].time <= copy[i - 1].time) ++disorder;
    }
  }
  writer.join();
  EXPECT_EQ(torn, 0U);
  EXPECT_EQ(disorder, 0U);
}

TEST(RtFlightRecorder, FlagNames) {
  EXPECT_EQ(flags_to_string(0), "-");
  EXPECT_EQ(flags_to_string(record_flag::kSkipped | record_flag::kSent), "sent|skipped");
}

}  // namespace
}  // namespace liftd::rt
