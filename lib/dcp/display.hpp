// Remote display of the drive on the lift controller (DCP 5.7, 5.6.2): a 4 x 20 character screen
// fed by Remote-mode (0x1F) payloads from the drive. Pure code: no I/O, no allocation except the
// UTF-8 helper marked as such.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>

namespace liftd::dcp {

/// DCP 5.6.2: lines 0x04..0x07 (four) and cursor positions 0x08..0x1B (twenty).
inline constexpr std::size_t kDisplayRows = 4;
/// DCP 5.6.2: cursor positions 0..19.
inline constexpr std::size_t kDisplayColumns = 20;

/// What went wrong while applying a display payload. The rest of the payload is still applied.
enum class DisplayError : std::uint8_t {
  None,
  BadControl,   ///< a control byte that is neither line, cursor nor idle (e.g. 0x01, 0x1C)
  PastLineEnd,  ///< characters written beyond column 20 were dropped
};

std::string_view to_string(DisplayError error) noexcept;

/// The drive's screen as we show it: 4 rows of 20 appendix-A bytes, blank (0x20) when cleared.
class DisplayModel {
 public:
  DisplayModel() noexcept { clear(); }

  /// Applies one Remote-mode payload from the drive: a line byte selects the row (and column
  /// 0), a cursor byte selects the column, data characters are written and advance the column,
  /// 0x00 is ignored. Characters before any line byte go to row 1. Returns the first problem
  /// met (the payload is applied as far as it makes sense either way).
  DisplayError apply(std::span<const std::uint8_t> payload) noexcept;
  /// Blanks the screen and homes the cursor (DCP 5.7 new STX, DCP 5.10 STX ETX, DCP 5.4 timeout).
  void clear() noexcept;

  /// One row's 20 bytes (row 0..3).
  std::span<const std::uint8_t, kDisplayColumns> row(std::size_t index) const noexcept {
    return std::span<const std::uint8_t, kDisplayColumns>(rows_[index % kDisplayRows]);
  }
  /// Increases with every change of content, so readers can tell a new screen cheaply.
  std::uint32_t version() const noexcept { return version_; }
  /// One row as UTF-8 with trailing blanks kept. Allocates: not for the real-time cycle.
  std::string row_utf8(std::size_t index) const;

 private:
  std::array<std::array<std::uint8_t, kDisplayColumns>, kDisplayRows> rows_{};
  std::size_t cursor_row_ = 0;
  std::size_t cursor_column_ = 0;
  std::uint32_t version_ = 0;
};

/// Drive side (simulator): writes `line byte, cursor byte, chars` for text at (row, column) into
/// `out`. Returns the bytes written, 0 if row/column are out of range, the text has a control
/// character, does not fit the line, or `out` is too small.
std::size_t encode_display_text(std::size_t row, std::size_t column,
                                std::span<const std::uint8_t> chars,
                                std::span<std::uint8_t> out) noexcept;

}  // namespace liftd::dcp
