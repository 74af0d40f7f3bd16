#include "dcp/trace.hpp"

#include <string>

namespace liftd::dcp {
namespace {

// Appends text to a fixed buffer, silently cutting at its end.
class LineWriter {
 public:
  explicit LineWriter(std::span<char> out) noexcept : out_(out) {}

  void text(std::string_view s) noexcept {
    for (const char c : s) character(c);
  }
  void character(char c) noexcept {
    if (size_ < out_.size()) out_[size_++] = c;
  }
  void decimal(std::uint32_t value) noexcept {
    std::array<char, 10> digits{};
    std::size_t n = 0;
    do {
      digits[n++] = static_cast<char>('0' + value % 10);
      value /= 10;
    } while (value != 0);
    while (n > 0) character(digits[--n]);
  }
  void hex_byte(std::uint8_t value) noexcept {
    constexpr std::string_view kHex = "0123456789ABCDEF";
    character(kHex[value >> 4]);
    character(kHex[value & 0x0F]);
  }
  std::size_t size() const noexcept { return size_; }

 private:
  std::span<char> out_;
  std::size_t size_ = 0;
};

// DCP 3.1: command bits B0..B7.
constexpr std::array<std::string_view, 8> kCommandBits = {
    "B0:enable", "B1:travel", "B2:stop",    "B3:speed",
    "B4:down",   "B5:change", "B6:desired", "B7:reply-error"};
// DCP 4.1: status bits S0..S7.
constexpr std::array<std::string_view, 8> kStatusBits = {
    "S0:ready", "S1:travel",   "S2:warning",    "S3:fault",
    "S4:slow",  "S5:accepted", "S6:brake-open", "S7:msg-error"};

void bit_names(LineWriter& w, std::uint8_t byte,
               const std::array<std::string_view, 8>& names) noexcept {
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (((static_cast<unsigned>(byte) >> i) & 1U) != 0) {
      w.character(' ');
      w.text(names[i]);
    }
  }
}

// DCP 5: 0x00 is the idle character, 0x02/0x03 frame the channel, 0x20..0x7E print as
// themselves; everything else (controls, the code page's upper half) as hex.
void channel_byte(LineWriter& w, std::uint8_t b) noexcept {
  if (b == 0x00) {
    w.text("--");
  } else if (b == 0x02) {
    w.text("STX");
  } else if (b == 0x03) {
    w.text("ETX");
  } else if (b >= 0x20 && b <= 0x7E) {
    w.character('\'');
    w.character(static_cast<char>(b));
    w.character('\'');
  } else {
    w.text("0x");
    w.hex_byte(b);
  }
}

void word_hex(LineWriter& w, std::uint16_t word) noexcept {
  w.text("0x");
  w.hex_byte(static_cast<std::uint8_t>(word >> 8));
  w.hex_byte(static_cast<std::uint8_t>(word & 0xFF));
}

void extended(LineWriter& w, const ExtendedStatus& e) noexcept {
  w.text("ext{");
  bool first = true;
  const auto item = [&](bool on, std::string_view name) {
    if (!on) return;
    if (!first) w.character(',');
    first = false;
    w.text(name);
  };
  // DCP 4.2.1.1: the meaning of bits 0..12.
  item(e.below_unlocking_speed, "v<0.8");
  item(e.below_border_speed, "v<border");
  item(e.below_overspeed, "v<overspeed");
  if (e.weight_bits != 0) {
    item(true, "weight=");
    w.decimal(e.weight_bits);
  }
  item(e.emergency_reduced_voltage, "emerg-low-voltage");
  item(e.emergency_direction_down, "emerg-down");
  item(e.motor_temperature_limit, "motor-hot");
  item(e.drive_temperature_limit, "drive-hot");
  w.character('}');
}

void master_data(LineWriter& w, std::uint8_t command, MessageType type,
                 std::uint16_t word) noexcept {
  if ((command & command_bit::kSpeedData) != 0) {  // DCP 3.5.3.7: B3 = data bytes are a speed
    if (const auto speed = speed_from_word(word)) {
      w.text("speed ");
      w.text(to_string(*speed));
    } else {
      w.text("speed? ");
      word_hex(w, word);
    }
  } else if (type == MessageType::Idle && word == 0) {
    w.character('-');
  } else {  // DCP 3.5.3.4: remaining distance in mm
    w.text("dist ");
    w.decimal(word);
    w.text(" mm");
  }
}

void drive_data(LineWriter& w, std::uint16_t word, DataInfoType type) noexcept {
  const auto data = decode_drive_data(word, type);
  if (!data) {
    w.text("data? ");
    word_hex(w, word);
  } else if (data->kind == DriveData::Kind::ExtendedStatus) {
    extended(w, data->extended);
  } else if (data->saturated) {  // DCP 4.2.1.2: 0x7FFF / 0xFFFF while stationary or starting
    w.text("decel -");
  } else {
    w.text("decel ");
    w.decimal(data->deceleration_distance_mm);
    w.text(" mm");
  }
}

}  // namespace

std::size_t format_frame(std::span<const std::uint8_t> bytes, FrameSide side,
                         const TraceOptions& options, std::span<char> out) noexcept {
  LineWriter w(out);
  if (bytes.empty()) {
    w.text("no bytes");
    return w.size();
  }
  if (bytes.size() < kFrameSize) {
    w.text("short ");
    w.decimal(static_cast<std::uint32_t>(bytes.size()));
    w.text("/6:");  // DCP 2: a frame is 6 bytes
    for (const std::uint8_t b : bytes) {
      w.character(' ');
      w.hex_byte(b);
    }
    return w.size();
  }
  const auto frame = bytes.first<kFrameSize>();
  // DCP 3.4 / 4.4: the last byte is the XOR of the five before it.
  if (checksum(frame.first<5>()) != frame[5]) w.text("BAD-CHECKSUM ");
  const std::uint16_t word = static_cast<std::uint16_t>((frame[1] << 8) | frame[2]);
  if (side == FrameSide::Master) {
    const MessageType type = classify_command(frame[0], options.protocol);
    w.text(to_string(type));
    bit_names(w, frame[0], kCommandBits);
    w.text(" | ");
    master_data(w, frame[0], type, word);
  } else {
    w.text("drive");
    bit_names(w, frame[0], kStatusBits);
    w.text(" | ");
    drive_data(w, word, options.data_info);
  }
  w.text(" | ch ");
  channel_byte(w, frame[3]);
  w.character(' ');
  channel_byte(w, frame[4]);
  if (bytes.size() > kFrameSize) {
    w.text(" +");
    w.decimal(static_cast<std::uint32_t>(bytes.size() - kFrameSize));
    w.text(" extra");
  }
  return w.size();
}

std::string_view format_frame(std::span<const std::uint8_t> bytes, FrameSide side,
                              const TraceOptions& options, TraceBuffer& buffer) noexcept {
  const std::size_t n = format_frame(bytes, side, options, std::span<char>(buffer));
  return {buffer.data(), n};
}

rt::FrameDecoder trace_decoder(const TraceOptions& options) {
  return [options](const rt::FrameRecord& record) -> std::string {
    if (record.direction == rt::Direction::Event) return {};
    TraceBuffer buffer;
    const FrameSide side =
        record.direction == rt::Direction::Tx ? FrameSide::Master : FrameSide::Drive;
    return std::string(format_frame(record.data(), side, options, buffer));
  };
}

}  // namespace liftd::dcp
