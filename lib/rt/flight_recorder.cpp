#include "rt/flight_recorder.hpp"

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <ostream>

namespace liftd::rt {
namespace {

std::uint64_t pack_word(std::span<const std::uint8_t> bytes, std::size_t word) noexcept {
  std::uint64_t w = 0;
  for (std::size_t i = 0; i < 8; ++i) {
    const std::size_t at = word * 8 + i;
    if (at < bytes.size()) w |= static_cast<std::uint64_t>(bytes[at]) << (8 * i);
  }
  return w;
}

}  // namespace

FlightRecorder::FlightRecorder(std::size_t capacity, std::size_t record_bytes)
    : capacity_(std::max<std::size_t>(capacity, 1)),
      words_per_record_(std::max<std::size_t>((record_bytes + 7) / 8, 1)),
      slots_(std::make_unique<Slot[]>(capacity_)),
      words_(std::make_unique<std::atomic<std::uint64_t>[]>(capacity_ * words_per_record_)) {}

void FlightRecorder::record(MonoTime time, Direction direction, std::uint8_t flags,
                            std::span<const std::uint8_t> bytes) noexcept {
  const std::uint64_t index = next_.load(std::memory_order_relaxed);
  const std::size_t at = static_cast<std::size_t>(index % capacity_);
  Slot& slot = slots_[at];
  std::atomic<std::uint64_t>* words = &words_[at * words_per_record_];
  // Seqlock without fences (TSan cannot check fences): the data stores are release stores,
  // so a reader that sees any new data also sees the odd stamp stored before it.
  slot.stamp.store(2 * index + 1, std::memory_order_relaxed);
  const std::size_t kept = std::min(bytes.size(), record_bytes());
  const std::uint64_t length = std::min<std::size_t>(bytes.size(), 0xFFFF);
  slot.time_ns.store(time.count(), std::memory_order_release);
  slot.meta.store(
      static_cast<std::uint64_t>(direction) | static_cast<std::uint64_t>(flags) << 8 | length << 16,
      std::memory_order_release);
  // Only the words the frame fills: copy() reads no further than the recorded length.
  for (std::size_t w = 0; w < (kept + 7) / 8; ++w) {
    words[w].store(pack_word(bytes.first(kept), w), std::memory_order_release);
  }
  slot.stamp.store(2 * (index + 1), std::memory_order_release);
  next_.store(index + 1, std::memory_order_release);
}

std::vector<FrameRecord> FlightRecorder::copy() const {
  const std::uint64_t end = next_.load(std::memory_order_acquire);
  const std::uint64_t begin = end > capacity_ ? end - capacity_ : 0;
  std::vector<FrameRecord> out;
  out.reserve(static_cast<std::size_t>(end - begin));
  for (std::uint64_t index = begin; index < end; ++index) {
    const std::size_t at = static_cast<std::size_t>(index % capacity_);
    const Slot& slot = slots_[at];
    const std::atomic<std::uint64_t>* words = &words_[at * words_per_record_];
    const std::uint64_t before = slot.stamp.load(std::memory_order_acquire);
    FrameRecord r;
    // Acquire loads keep the second stamp load after them (see record()).
    r.time = MonoTime(slot.time_ns.load(std::memory_order_acquire));
    const std::uint64_t meta = slot.meta.load(std::memory_order_acquire);
    const std::size_t length = static_cast<std::size_t>((meta >> 16) & 0xFFFF);
    const std::size_t kept = std::min(length, record_bytes());
    r.bytes.assign(record_bytes(), 0);
    for (std::size_t w = 0; w < (kept + 7) / 8; ++w) {
      const std::uint64_t word = words[w].load(std::memory_order_acquire);
      for (std::size_t i = 0; i < 8 && w * 8 + i < kept; ++i) {
        r.bytes[w * 8 + i] = static_cast<std::uint8_t>(word >> (8 * i));
      }
    }
    const std::uint64_t after = slot.stamp.load(std::memory_order_relaxed);
    // Skip a slot the writer has moved on to (or is writing) since we read `end`.
    if (before != after || before != 2 * (index + 1)) continue;
    r.direction = static_cast<Direction>(meta & 0xFF);
    r.flags = static_cast<std::uint8_t>((meta >> 8) & 0xFF);
    r.length = static_cast<std::uint16_t>(length);
    out.push_back(std::move(r));
  }
  return out;
}

std::string flags_to_string(std::uint8_t flags) {
  static constexpr std::array<const char*, 8> kNames = {
      "sent", "reply", "missing", "bad", "partial", "port-lost", "send-failed", "skipped"};
  std::string text;
  for (std::size_t bit = 0; bit < kNames.size(); ++bit) {
    if ((flags & (1U << bit)) == 0) continue;
    if (!text.empty()) text += '|';
    text += kNames[bit];
  }
  return text.empty() ? "-" : text;
}

void write_text(std::ostream& out, std::span<const FrameRecord> records,
                const FrameDecoder& decoder) {
  out << "# liftd flight recorder: monotonic seconds, direction, bytes (hex), flags\n";
  for (const FrameRecord& r : records) {
    char head[48];
    const auto ns = r.time.count();
    std::snprintf(head, sizeof head, "%lld.%06lld", static_cast<long long>(ns / 1'000'000'000),
                  static_cast<long long>((ns % 1'000'000'000) / 1000));
    out << head << ' '
        << (r.direction == Direction::Tx   ? "tx"
            : r.direction == Direction::Rx ? "rx"
                                           : "--");
    std::string hex;
    for (std::uint8_t b : r.data()) {
      char two[4];
      std::snprintf(two, sizeof two, " %02X", b);
      hex += two;
    }
    if (r.length > r.bytes.size()) hex += " ...";
    // Pad the hex column to a 6-byte DCP frame so the flags line up.
    while (hex.size() < 18) hex += ' ';
    out << hex << "  " << flags_to_string(r.flags);
    if (decoder) {
      const std::string decoded = decoder(r);
      if (!decoded.empty()) out << " | " << decoded;
    }
    out << '\n';
  }
}

int write_text_file(const std::string& path, std::span<const FrameRecord> records,
                    const FrameDecoder& decoder) {
  std::ofstream file(path, std::ios::out | std::ios::trunc);
  if (!file) return errno != 0 ? errno : EIO;
  write_text(file, records, decoder);
  file.flush();
  return file ? 0 : EIO;
}

}  // namespace liftd::rt
