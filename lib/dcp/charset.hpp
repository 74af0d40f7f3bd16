// The character set of the DCP communication channel (DCP 5.2, appendix A / chapter 14), to and
// from UTF-8. Pure code: no I/O, no allocation except in the std::string helpers marked as such.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>

namespace liftd::dcp {

/// DCP 5.2: data characters are 0x20..0xFF; 0x00..0x1F are control characters.
inline constexpr std::uint8_t kFirstDataChar = 0x20;

/// True for 0x20..0xFF (DCP 5.2).
constexpr bool is_data_char(std::uint8_t byte) noexcept {
  return byte >= kFirstDataChar;
}

/// What a channel byte that has no glyph in appendix A decodes to: U+FFFD REPLACEMENT CHARACTER.
/// Bytes 0x20..0x7D and 0x7E/0x7F are ASCII-like; of 0x80..0xFF only the ones appendix A lists
/// (umlauts, sharp s, degree, Greek letters, arrows, maths signs) have a glyph.
inline constexpr char32_t kReplacementChar = 0xFFFD;

/// The Unicode code point of a data character per appendix A; nullopt for control characters
/// (0x00..0x1F) and for data characters appendix A does not define.
std::optional<char32_t> char_to_unicode(std::uint8_t byte) noexcept;

/// The channel byte for a Unicode code point per appendix A; nullopt where appendix A has no
/// such character. Never returns a control character.
std::optional<std::uint8_t> unicode_to_char(char32_t code_point) noexcept;

/// Channel bytes to UTF-8 for humans (logs, API). Control characters and bytes without a glyph
/// become U+FFFD. Allocates: never call it inside the real-time cycle.
std::string to_utf8(std::span<const std::uint8_t> bytes);

/// Why UTF-8 text could not be converted to channel bytes.
enum class CharsetError : std::uint8_t {
  None,
  InvalidUtf8,  ///< the input is not well-formed UTF-8
  Unmappable,   ///< a code point appendix A does not contain (e.g. a control character, 'é')
  TooLong,      ///< the output buffer is full
};

/// "invalid UTF-8", ...
std::string_view to_string(CharsetError error) noexcept;

/// Result of from_utf8: bytes written, and on failure the error and the byte offset in the
/// UTF-8 input where it happened.
struct CharsetResult {
  std::size_t written = 0;
  CharsetError error = CharsetError::None;
  std::size_t input_offset = 0;
  bool ok() const noexcept { return error == CharsetError::None; }
};

/// UTF-8 text to channel bytes, strictly: the first unmappable code point or malformed sequence
/// stops the conversion with an error (no silent replacement). No allocation.
CharsetResult from_utf8(std::string_view utf8, std::span<std::uint8_t> out) noexcept;

}  // namespace liftd::dcp
