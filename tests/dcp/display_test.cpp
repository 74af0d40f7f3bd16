// The remote display (DCP 5.7, 5.6.2) as a 4 x 20 screen.
#include "dcp/display.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "dcp/dcp_test_util.hpp"

namespace liftd::dcp {
namespace {

std::string row(const DisplayModel& d, std::size_t r) {
  return {d.row(r).begin(), d.row(r).end()};
}
std::vector<std::uint8_t> payload(std::initializer_list<std::uint8_t> head, std::string_view text) {
  std::vector<std::uint8_t> v(head);
  v.insert(v.end(), text.begin(), text.end());
  return v;
}

TEST(DcpDisplay, StartsBlank) {
  DisplayModel d;
  for (std::size_t r = 0; r < kDisplayRows; ++r) EXPECT_EQ(row(d, r), std::string(20, ' '));
}

TEST(DcpDisplay, WritesAWholeLineAsInExample1) {
  // STX 1F line cursor char1..charn ETX: line 2 (0x05), cursor 0 (0x08).
  DisplayModel d;
  EXPECT_EQ(d.apply(payload({0x05, 0x08}, "Speed 1.60 m/s")), DisplayError::None);
  EXPECT_EQ(row(d, 1), "Speed 1.60 m/s      ");
  EXPECT_EQ(row(d, 0), std::string(20, ' '));
}

TEST(DcpDisplay, WritesSingleCharactersAtPositionsAsInExample2) {
  DisplayModel d;
  const std::vector<std::uint8_t> p{0x04, 0x0A, 'A', 0x07, 0x1B, 'Z', 0x06, 0x08, 0x84};
  EXPECT_EQ(d.apply(p), DisplayError::None);
  EXPECT_EQ(row(d, 0), "  A                 ");
  EXPECT_EQ(row(d, 3), "                   Z");  // 19 spaces, Z in the last column
  EXPECT_EQ(d.row(2)[0], 0x84);
  EXPECT_EQ(d.row_utf8(2), "\xC3\xA4" + std::string(19, ' '));
}

TEST(DcpDisplay, LineByteHomesTheCursor) {
  DisplayModel d;
  d.apply(payload({0x04, 0x0C}, "xx"));
  d.apply(payload({0x04}, "ab"));
  EXPECT_EQ(row(d, 0), "ab  xx              ");
}

TEST(DcpDisplay, DropsCharactersPastColumn20) {
  DisplayModel d;
  EXPECT_EQ(d.apply(payload({0x04, 0x1A}, "XYZ")), DisplayError::PastLineEnd);
  EXPECT_EQ(row(d, 0), "                  XY");  // 18 spaces
  EXPECT_EQ(row(d, 1), std::string(20, ' '));    // no wrap into the next line
}

TEST(DcpDisplay, ReportsStrayControlBytesAndAppliesTheRest) {
  DisplayModel d;
  const std::vector<std::uint8_t> p{0x04, 0x08, 'A', 0x01, 'B', 0x1C, 0x00, 'C'};
  EXPECT_EQ(d.apply(p), DisplayError::BadControl);
  EXPECT_EQ(row(d, 0).substr(0, 3), "ABC");
}

TEST(DcpDisplay, VersionChangesOnlyWithContent) {
  DisplayModel d;
  const auto v0 = d.version();
  d.apply(payload({0x04, 0x08}, "Hi"));
  const auto v1 = d.version();
  EXPECT_NE(v1, v0);
  d.apply(payload({0x04, 0x08}, "Hi"));  // same text again: no change
  EXPECT_EQ(d.version(), v1);
  d.clear();
  EXPECT_NE(d.version(), v1);
  EXPECT_EQ(row(d, 0), std::string(20, ' '));
}

TEST(DcpDisplay, DriveSideEncodingRoundTrips) {
  std::uint8_t out[32] = {};
  const auto text = test::bytes("Menu 3");
  const std::size_t n = encode_display_text(2, 5, text, out);
  ASSERT_EQ(n, 8U);
  EXPECT_EQ(out[0], 0x06);
  EXPECT_EQ(out[1], 0x0D);
  DisplayModel d;
  EXPECT_EQ(d.apply(std::span<const std::uint8_t>(out, n)), DisplayError::None);
  EXPECT_EQ(row(d, 2), "     Menu 3         ");
  // Legend: invalid placements encode nothing.
  EXPECT_EQ(encode_display_text(4, 0, text, out), 0U);   // no fifth line
  EXPECT_EQ(encode_display_text(0, 20, text, out), 0U);  // no column 21
  EXPECT_EQ(encode_display_text(0, 15, text, out), 0U);  // would pass the line end
  const std::vector<std::uint8_t> ctrl{'a', 0x05};
  EXPECT_EQ(encode_display_text(0, 0, ctrl, out), 0U);  // control character
  EXPECT_EQ(encode_display_text(0, 0, text, std::span<std::uint8_t>(out, 4)), 0U);  // no room
}

}  // namespace
}  // namespace liftd::dcp
