#include "dcp/charset.hpp"

#include <array>

namespace liftd::dcp {
namespace {

struct Glyph {
  std::uint8_t byte;
  char32_t code_point;
};

// DCP appendix A (chapter 14), the characters above 0x7D and the ones in 0x20..0x7D that are not
// plain ASCII. The German text has the clean glyphs; the English one lost some in conversion.
// 0x7C's glyph is blank in both texts (a '|' lost as a table delimiter in conversion): ASCII.
constexpr std::array<Glyph, 27> kSpecialGlyphs = {{
    {0x5C, 0x00A5},  // YEN SIGN instead of the backslash
    {0x7E, 0x2192},  // RIGHTWARDS ARROW
    {0x7F, 0x2190},  // LEFTWARDS ARROW
    {0x81, 0x00FC},  // u umlaut
    {0x84, 0x00E4},  // a umlaut
    {0x8E, 0x00C4},  // A umlaut
    {0x94, 0x00F6},  // o umlaut
    {0x99, 0x00D6},  // O umlaut
    {0x9A, 0x00DC},  // U umlaut
    {0xB0, 0x2261},  // IDENTICAL TO
    {0xDF, 0x00B0},  // DEGREE SIGN
    {0xE0, 0x03B1},  // alpha
    {0xE1, 0x00DF},  // sharp s
    {0xE2, 0x03B2},  // beta
    {0xE3, 0x03B5},  // epsilon
    {0xE4, 0x03BC},  // mu
    {0xE5, 0x03C3},  // sigma
    {0xE6, 0x03C1},  // rho
    {0xE8, 0x221A},  // SQUARE ROOT
    {0xF0, 0x03A1},  // capital rho (as printed in the German appendix)
    {0xF1, 0x00B1},  // PLUS-MINUS SIGN
    {0xF2, 0x0398},  // capital theta
    {0xF3, 0x221E},  // INFINITY
    {0xF4, 0x03A9},  // capital omega
    {0xF6, 0x03A3},  // capital sigma
    {0xF7, 0x03C0},  // pi
    {0xFD, 0x00F7},  // DIVISION SIGN
}};

constexpr char32_t kMicroSign = 0x00B5;  // typed instead of the Greek mu; maps to 0xE4 as well

constexpr std::uint8_t kLastAscii = 0x7D;  // appendix A: 0x20..0x7D are ASCII (except 0x5C)

std::size_t put_utf8(char32_t cp, char* out) noexcept {
  if (cp < 0x80) {
    out[0] = static_cast<char>(cp);
    return 1;
  }
  if (cp < 0x800) {
    out[0] = static_cast<char>(0xC0 | (cp >> 6));
    out[1] = static_cast<char>(0x80 | (cp & 0x3F));
    return 2;
  }
  out[0] = static_cast<char>(0xE0 | (cp >> 12));
  out[1] = static_cast<char>(0x80 | ((cp >> 6) & 0x3F));
  out[2] = static_cast<char>(0x80 | (cp & 0x3F));
  return 3;  // every glyph of appendix A and U+FFFD lie in the BMP
}

// Decodes one UTF-8 sequence at text[i]; returns its length (0 if malformed) and the code point.
std::size_t next_utf8(std::string_view text, std::size_t i, char32_t& cp) noexcept {
  const auto b0 = static_cast<std::uint8_t>(text[i]);
  std::size_t len = 0;
  char32_t min = 0;
  if (b0 < 0x80) {
    cp = b0;
    return 1;
  } else if ((b0 & 0xE0) == 0xC0) {
    len = 2;
    cp = b0 & 0x1Fu;
    min = 0x80;
  } else if ((b0 & 0xF0) == 0xE0) {
    len = 3;
    cp = b0 & 0x0Fu;
    min = 0x800;
  } else if ((b0 & 0xF8) == 0xF0) {
    len = 4;
    cp = b0 & 0x07u;
    min = 0x10000;
  } else {
    return 0;
  }
  if (i + len > text.size()) return 0;
  for (std::size_t k = 1; k < len; ++k) {
    const auto b = static_cast<std::uint8_t>(text[i + k]);
    if ((b & 0xC0) != 0x80) return 0;
    cp = (cp << 6) | (b & 0x3Fu);
  }
  if (cp < min || cp > 0x10FFFF || (cp >= 0xD800 && cp <= 0xDFFF)) return 0;
  return len;
}

}  // namespace

std::optional<char32_t> char_to_unicode(std::uint8_t byte) noexcept {
  if (!is_data_char(byte)) return std::nullopt;
  for (const auto& g : kSpecialGlyphs) {
    if (g.byte == byte) return g.code_point;
  }
  if (byte <= kLastAscii) return static_cast<char32_t>(byte);
  return std::nullopt;
}

std::optional<std::uint8_t> unicode_to_char(char32_t code_point) noexcept {
  if (code_point == kMicroSign) return std::uint8_t{0xE4};
  for (const auto& g : kSpecialGlyphs) {
    if (g.code_point == code_point) return g.byte;
  }
  if (code_point >= kFirstDataChar && code_point <= kLastAscii && code_point != U'\\') {
    return static_cast<std::uint8_t>(code_point);
  }
  return std::nullopt;
}

std::string to_utf8(std::span<const std::uint8_t> bytes) {
  std::string out;
  out.reserve(bytes.size());
  char buffer[4];
  for (std::uint8_t b : bytes) {
    const char32_t cp = char_to_unicode(b).value_or(kReplacementChar);
    out.append(buffer, put_utf8(cp, buffer));
  }
  return out;
}

std::string_view to_string(CharsetError error) noexcept {
  switch (error) {
    case CharsetError::None:
      return "no error";
    case CharsetError::InvalidUtf8:
      return "invalid UTF-8";
    case CharsetError::Unmappable:
      return "character not in the DCP character set (appendix A)";
    case CharsetError::TooLong:
      return "text too long";
  }
  return "unknown charset error";
}

CharsetResult from_utf8(std::string_view utf8, std::span<std::uint8_t> out) noexcept {
  CharsetResult result;
  std::size_t i = 0;
  while (i < utf8.size()) {
    char32_t cp = 0;
    const std::size_t len = next_utf8(utf8, i, cp);
    if (len == 0) {
      result.error = CharsetError::InvalidUtf8;
      result.input_offset = i;
      return result;
    }
    const auto byte = unicode_to_char(cp);
    if (!byte) {
      result.error = CharsetError::Unmappable;
      result.input_offset = i;
      return result;
    }
    if (result.written >= out.size()) {
      result.error = CharsetError::TooLong;
      result.input_offset = i;
      return result;
    }
    out[result.written++] = *byte;
    i += len;
  }
  return result;
}

}  // namespace liftd::dcp
