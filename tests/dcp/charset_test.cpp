// The channel character set (DCP 5.2, appendix A) both ways.
#include "dcp/charset.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace liftd::dcp {
namespace {

TEST(DcpCharset, MapsTheAppendixAGlyphsBothWays) {
  // Legend: channel byte <-> Unicode code point, as printed in appendix A (German text).
  struct Case {
    std::uint8_t byte;
    char32_t code_point;
  };
  const std::vector<Case> cases = {
      {0x20, U' '},      {0x21, U'!'},      {0x30, U'0'},      {0x41, U'A'},      {0x7A, U'z'},
      {0x7D, U'}'},      {0x7C, U'|'},      {0x5C, U'\u00A5'},  // yen, not backslash
      {0x7E, U'\u2192'}, {0x7F, U'\u2190'},                     // arrows
      {0x8E, U'\u00C4'}, {0x99, U'\u00D6'}, {0x9A, U'\u00DC'},  // Ä Ö Ü
      {0x84, U'\u00E4'}, {0x94, U'\u00F6'}, {0x81, U'\u00FC'},  // ä ö ü
      {0xE1, U'\u00DF'}, {0xDF, U'\u00B0'},                     // ß, degree sign
      {0xB0, U'\u2261'}, {0xE0, U'\u03B1'}, {0xE2, U'\u03B2'}, {0xE3, U'\u03B5'}, {0xE4, U'\u03BC'},
      {0xE5, U'\u03C3'}, {0xE6, U'\u03C1'}, {0xE8, U'\u221A'}, {0xF0, U'\u03A1'}, {0xF1, U'\u00B1'},
      {0xF2, U'\u0398'}, {0xF3, U'\u221E'}, {0xF4, U'\u03A9'}, {0xF6, U'\u03A3'}, {0xF7, U'\u03C0'},
      {0xFD, U'\u00F7'},
  };
  for (const auto& c : cases) {
    EXPECT_EQ(char_to_unicode(c.byte), c.code_point) << std::hex << int{c.byte};
    EXPECT_EQ(unicode_to_char(c.code_point), c.byte) << std::hex << int{c.byte};
  }
}

TEST(DcpCharset, ControlAndUndefinedBytesHaveNoGlyph) {
  for (int b = 0; b < 0x20; ++b) EXPECT_FALSE(char_to_unicode(static_cast<std::uint8_t>(b)));
  for (int b : {0x80, 0x82, 0xA0, 0xE7, 0xFF})
    EXPECT_FALSE(char_to_unicode(static_cast<std::uint8_t>(b))) << b;
  EXPECT_FALSE(unicode_to_char(U'\\'));         // 0x5C is the yen sign
  EXPECT_FALSE(unicode_to_char(U'\n'));         // control characters are not data
  EXPECT_FALSE(unicode_to_char(U'\u00E9'));     // é is not in appendix A
  EXPECT_EQ(unicode_to_char(U'\u00B5'), 0xE4);  // micro sign typed for mu
}

TEST(DcpCharset, EveryDefinedByteRoundTripsThroughUtf8) {
  for (int b = 0x20; b <= 0xFF; ++b) {
    const auto byte = static_cast<std::uint8_t>(b);
    if (!char_to_unicode(byte)) continue;
    const std::string utf8 = to_utf8(std::span<const std::uint8_t>(&byte, 1));
    std::uint8_t back[4] = {};
    const auto r = from_utf8(utf8, back);
    ASSERT_TRUE(r.ok()) << b;
    ASSERT_EQ(r.written, 1U);
    EXPECT_EQ(back[0], byte);
  }
}

TEST(DcpCharset, ConvertsGermanTextToChannelBytes) {
  std::uint8_t out[32] = {};
  const auto r = from_utf8(
      "T\xC3\xBCr \xC3\x96l 5\xC2\xB0"
      "C",
      out);  // "Tür Öl 5°C"
  ASSERT_TRUE(r.ok());
  const std::vector<std::uint8_t> expected{'T', 0x81, 'r', ' ', 0x99, 'l', ' ', '5', 0xDF, 'C'};
  EXPECT_EQ(std::vector<std::uint8_t>(out, out + r.written), expected);
  EXPECT_EQ(to_utf8(expected),
            "T\xC3\xBCr \xC3\x96l 5\xC2\xB0"
            "C");
}

TEST(DcpCharset, RejectsWhatItCannotMap) {
  // Legend: UTF-8 input -> error and the input offset where it happened.
  struct Case {
    const char* what;
    std::string in;
    CharsetError error;
    std::size_t offset;
  };
  const std::vector<Case> cases = {
      {"e acute", "ab\xC3\xA9", CharsetError::Unmappable, 2},
      {"backslash", "a\\b", CharsetError::Unmappable, 1},
      {"tab", "a\tb", CharsetError::Unmappable, 1},
      {"truncated sequence", "ab\xC3", CharsetError::InvalidUtf8, 2},
      {"overlong slash", "\xC0\xAF", CharsetError::InvalidUtf8, 0},
      {"lone continuation byte", "\x80", CharsetError::InvalidUtf8, 0},
      {"surrogate", "\xED\xA0\x80", CharsetError::InvalidUtf8, 0},
      {"emoji", "\xF0\x9F\x98\x80", CharsetError::Unmappable, 0},
      {"longer than the buffer", "0123456789", CharsetError::TooLong, 4},
  };
  for (const auto& c : cases) {
    std::uint8_t out[4] = {};
    const auto r = from_utf8(c.in, out);
    EXPECT_EQ(r.error, c.error) << c.what;
    EXPECT_EQ(r.input_offset, c.offset) << c.what;
    EXPECT_FALSE(to_string(r.error).empty());
  }
}

TEST(DcpCharset, UndefinedBytesBecomeTheReplacementCharacter) {
  const std::vector<std::uint8_t> in{'A', 0x80, 0x01, 'B'};
  EXPECT_EQ(to_utf8(in),
            "A\xEF\xBF\xBD\xEF\xBF\xBD"
            "B");
}

}  // namespace
}  // namespace liftd::dcp
