// The DCP decoder of the flight recorder: exact decoded lines for master and drive frames.
#include <gtest/gtest.h>

#include <sstream>
#include <string>
#include <vector>

#include "dcp/trace.hpp"
#include "rt/flight_recorder.hpp"

namespace liftd::dcp {
namespace {

// A frame with the checksum filled in (DCP 3.4 / 4.4).
std::vector<std::uint8_t> framed(std::uint8_t b0, std::uint8_t d1, std::uint8_t d2, std::uint8_t c1,
                                 std::uint8_t c2) {
  return {b0, d1, d2, c1, c2, static_cast<std::uint8_t>(b0 ^ d1 ^ d2 ^ c1 ^ c2)};
}

struct Case {
  const char* legend;
  FrameSide side;
  TraceOptions options;
  std::vector<std::uint8_t> bytes;
  const char* expected;
};

constexpr TraceOptions kDcp4{};
constexpr TraceOptions kDcp3{Protocol::Dcp3, DataInfoType::Alternating};

TEST(DcpTrace, DecodesFramesAsTheTableSays) {
  // Legend: master frames (command byte first, DCP 3) and drive frames (status byte first,
  // DCP 4), each with the line the flight recorder shows after " | ".
  const std::vector<Case> cases = {
      {"idle master frame, nothing on the channel", FrameSide::Master, kDcp4,
       framed(0x00, 0x00, 0x00, 0x00, 0x00), "idle | - | ch -- --"},
      {"DCP4 travel down, 2999 mm to go, channel opens an I-message", FrameSide::Master, kDcp4,
       framed(0x17, 0x0B, 0xB7, 0x02, 0x1C),
       "travel B0:enable B1:travel B2:stop B4:down | dist 2999 mm | ch STX 0x1C"},
      {"speed message V4 (G7), channel text 'I0'", FrameSide::Master, kDcp4,
       framed(0x09, 0x00, 0x80, 'I', '0'), "speed B0:enable B3:speed | speed V4 | ch 'I' '0'"},
      {"speed message with two speed bits is no speed", FrameSide::Master, kDcp4,
       framed(0x09, 0x00, 0x03, 0x00, 0x00), "speed B0:enable B3:speed | speed? 0x0003 | ch -- --"},
      {"B7: the drive's last reply was corrupt", FrameSide::Master, kDcp4,
       framed(0x87, 0x00, 0x00, 0x03, 0x00),
       "travel B0:enable B1:travel B2:stop B7:reply-error | dist 0 mm | ch ETX --"},
      {"DCP3 speed after fast start is 1111", FrameSide::Master, kDcp3,
       framed(0x0F, 0x00, 0x40, 0x00, 0x00),
       "speed-after-fast-start B0:enable B1:travel B2:stop B3:speed | speed V3 | ch -- --"},
      {"1111 is no message in DCP4", FrameSide::Master, kDcp4, framed(0x0F, 0x00, 0x40, 0x00, 0x00),
       "invalid B0:enable B1:travel B2:stop B3:speed | speed V3 | ch -- --"},
      {"DCP4 remaining distance 0101, 15-bit clamp", FrameSide::Master, kDcp4,
       framed(0x05, 0x7F, 0xFF, 0x00, 0x00),
       "distance/deceleration B0:enable B2:stop | dist 32767 mm | ch -- --"},
      {"drive travelling, brake open, 1430 mm deceleration distance", FrameSide::Drive, kDcp4,
       framed(0x43, 0x05, 0x96, '0', '4'),
       "drive S0:ready S1:travel S6:brake-open | decel 1430 mm | ch '0' '4'"},
      {"drive at rest: deceleration distance saturated", FrameSide::Drive, kDcp4,
       framed(0x11, 0x7F, 0xFF, 0x00, 0x00), "drive S0:ready S4:slow | decel - | ch -- --"},
      {"extended status, the three speed bits", FrameSide::Drive, kDcp4,
       framed(0x11, 0x80, 0x07, 0x00, 0x00),
       "drive S0:ready S4:slow | ext{v<0.8,v<border,v<overspeed} | ch -- --"},
      {"extended status, emergency power and motor temperature", FrameSide::Drive, kDcp4,
       framed(0x09, 0x8A, 0x00, 0x00, 0x00),
       "drive S0:ready S3:fault | ext{emerg-low-voltage,motor-hot} | ch -- --"},
      {"extended status, weight bits 4..8 = 5", FrameSide::Drive, kDcp4,
       framed(0x01, 0x80, 0x50, 0x00, 0x00), "drive S0:ready | ext{weight=5} | ch -- --"},
      {"S7 and every other status bit", FrameSide::Drive, kDcp4,
       framed(0xFF, 0x00, 0x00, 0x8E, 0x7F),
       "drive S0:ready S1:travel S2:warning S3:fault S4:slow S5:accepted S6:brake-open "
       "S7:msg-error | decel 0 mm | ch 0x8E 0x7F"},
      {"type '2' expects extended status: a distance word does not fit", FrameSide::Drive,
       TraceOptions{Protocol::Dcp4, DataInfoType::Extended}, framed(0x01, 0x05, 0x96, 0, 0),
       "drive S0:ready | data? 0x0596 | ch -- --"},
      {"type '3': 16-bit deceleration distance", FrameSide::Drive,
       TraceOptions{Protocol::Dcp4, DataInfoType::Decel16}, framed(0x03, 0x90, 0x00, 0, 0),
       "drive S0:ready S1:travel | decel 36864 mm | ch -- --"},
      {"corrupt reply (last byte wrong)",
       FrameSide::Drive,
       kDcp4,
       {0x43, 0x05, 0x96, '0', '4', 0x00},
       "BAD-CHECKSUM drive S0:ready S1:travel S6:brake-open | decel 1430 mm | ch '0' '4'"},
      {"truncated reply: 3 of 6 bytes",
       FrameSide::Drive,
       kDcp4,
       {0x21, 0x7F, 0xFF},
       "short 3/6: 21 7F FF"},
      {"nothing arrived", FrameSide::Drive, kDcp4, {}, "no bytes"},
      {"two garbage bytes after a good reply",
       FrameSide::Drive,
       kDcp4,
       {0x01, 0x7F, 0xFF, 0x00, 0x00, 0x81, 0xAA, 0xBB},
       "drive S0:ready | decel - | ch -- -- +2 extra"},
  };
  for (const Case& c : cases) {
    TraceBuffer buffer;
    EXPECT_EQ(format_frame(c.bytes, c.side, c.options, buffer), c.expected) << c.legend;
  }
}

TEST(DcpTrace, CutsAtTheEndOfASmallBuffer) {
  const auto bytes = framed(0x43, 0x05, 0x96, '0', '4');
  std::array<char, 8> small{};
  const std::size_t n = format_frame(bytes, FrameSide::Drive, kDcp4, std::span<char>(small));
  EXPECT_EQ(std::string(small.data(), n), "drive S0");
  EXPECT_EQ(format_frame(bytes, FrameSide::Drive, kDcp4, std::span<char>()), 0U);
}

TEST(DcpTrace, LongestLineFitsTheBuffer) {
  // Every status bit, every extended bit, weight 31, two hex channel bytes, a bad checksum and
  // ten extra bytes: the longest line there is must not be cut.
  std::vector<std::uint8_t> bytes = {0xFF, 0x9F, 0xF7, 0xFF, 0xFF, 0x00};
  bytes.resize(16, 0xEE);
  TraceBuffer buffer;
  const auto line = format_frame(bytes, FrameSide::Drive, kDcp4, buffer);
  EXPECT_LT(line.size(), buffer.size());
  EXPECT_EQ(line.substr(line.size() - 9), "+10 extra") << line;
}

TEST(DcpTrace, DecoderAddsAColumnToTheRecorderDump) {
  rt::FlightRecorder recorder(8, rt::kDcpRecordBytes);
  const auto tx = framed(0x09, 0x00, 0x80, 0x00, 0x00);
  const auto rx = framed(0x21, 0x7F, 0xFF, 0x00, 0x00);
  recorder.record(MonoTime{std::chrono::milliseconds(1500)}, rt::Direction::Tx,
                  rt::record_flag::kSent, tx);
  recorder.record(MonoTime{std::chrono::milliseconds(1502)}, rt::Direction::Rx,
                  rt::record_flag::kReply, rx);
  recorder.record(MonoTime{std::chrono::milliseconds(1515)}, rt::Direction::Event,
                  rt::record_flag::kPortLost, {});
  std::ostringstream out;
  const auto records = recorder.copy();
  rt::write_text(out, records, trace_decoder());
  const std::string text = out.str();
  EXPECT_NE(text.find(" | speed B0:enable B3:speed | speed V4 | ch -- --\n"), std::string::npos)
      << text;
  EXPECT_NE(text.find(" | drive S0:ready S5:accepted | decel - | ch -- --\n"), std::string::npos)
      << text;
  // The event line has no decoded column.
  const auto last = text.rfind("1.515000");
  ASSERT_NE(last, std::string::npos) << text;
  EXPECT_EQ(text.find(" | ", last), std::string::npos) << text;
}

}  // namespace
}  // namespace liftd::dcp
