#include "dcp/display.hpp"

#include <algorithm>

#include "dcp/channel.hpp"
#include "dcp/charset.hpp"

namespace liftd::dcp {
namespace {
constexpr std::uint8_t kBlank = 0x20;  // DCP appendix A: space
}  // namespace

std::string_view to_string(DisplayError error) noexcept {
  switch (error) {
    case DisplayError::None:
      return "no error";
    case DisplayError::BadControl:
      return "control byte that is no line or cursor position";
    case DisplayError::PastLineEnd:
      return "characters beyond column 20 dropped";
  }
  return "unknown display error";
}

void DisplayModel::clear() noexcept {
  for (auto& r : rows_) r.fill(kBlank);
  cursor_row_ = 0;
  cursor_column_ = 0;
  ++version_;
}

DisplayError DisplayModel::apply(std::span<const std::uint8_t> payload) noexcept {
  DisplayError first = DisplayError::None;
  auto note = [&first](DisplayError e) {
    if (first == DisplayError::None) first = e;
  };
  bool changed = false;
  for (const std::uint8_t byte : payload) {
    if (byte == channel_char::kIdle) continue;
    if (byte >= channel_char::kLine1 && byte <= channel_char::kLine4) {
      cursor_row_ = static_cast<std::size_t>(byte - channel_char::kLine1);
      cursor_column_ = 0;
    } else if (byte >= channel_char::kCursor0 && byte <= channel_char::kCursor19) {
      cursor_column_ = static_cast<std::size_t>(byte - channel_char::kCursor0);
    } else if (!is_data_char(byte)) {
      note(DisplayError::BadControl);
    } else if (cursor_column_ >= kDisplayColumns) {
      note(DisplayError::PastLineEnd);
    } else {
      auto& cell = rows_[cursor_row_][cursor_column_++];
      if (cell != byte) {
        cell = byte;
        changed = true;
      }
    }
  }
  if (changed) ++version_;
  return first;
}

std::string DisplayModel::row_utf8(std::size_t index) const {
  return to_utf8(row(index));
}

std::size_t encode_display_text(std::size_t row, std::size_t column,
                                std::span<const std::uint8_t> chars,
                                std::span<std::uint8_t> out) noexcept {
  if (row >= kDisplayRows || column >= kDisplayColumns) return 0;
  if (column + chars.size() > kDisplayColumns || chars.size() + 2 > out.size()) return 0;
  if (!std::all_of(chars.begin(), chars.end(), [](std::uint8_t c) { return is_data_char(c); })) {
    return 0;
  }
  out[0] = static_cast<std::uint8_t>(channel_char::kLine1 + row);
  out[1] = static_cast<std::uint8_t>(channel_char::kCursor0 + column);
  std::copy(chars.begin(), chars.end(), out.begin() + 2);
  return chars.size() + 2;
}

}  // namespace liftd::dcp
