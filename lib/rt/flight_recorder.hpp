// Flight recorder: the last few seconds of link traffic, written by the cycle thread into a
// preallocated ring, copied out consistently by another thread and dumped as readable text.
#pragma once

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <iosfwd>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "common/mono_time.hpp"

namespace liftd::rt {

/// Which way a recorded frame went.
enum class Direction : std::uint8_t {
  Tx,     ///< we sent it
  Rx,     ///< we received it (possibly partial)
  Event,  ///< no bytes: a link event (port lost, cycle skipped)
};

/// What happened to a recorded frame; bit flags.
namespace record_flag {
inline constexpr std::uint8_t kSent = 0x01;        ///< frame handed to the port
inline constexpr std::uint8_t kReply = 0x02;       ///< complete reply in time
inline constexpr std::uint8_t kMissing = 0x04;     ///< no complete reply by the deadline
inline constexpr std::uint8_t kBad = 0x08;         ///< complete but rejected by the engine
inline constexpr std::uint8_t kPartial = 0x10;     ///< some bytes came, not all
inline constexpr std::uint8_t kPortLost = 0x20;    ///< the device went away
inline constexpr std::uint8_t kSendFailed = 0x40;  ///< the port refused the frame
inline constexpr std::uint8_t kSkipped = 0x80;     ///< cycle skipped: woke too late to send
}  // namespace record_flag

/// Bytes a record keeps, per link kind. A longer frame is cut; its record still says its length.
/// DCP: a frame is 6 bytes (DCP 3.1); the reply window may hold stray bytes beyond one frame.
inline constexpr std::size_t kDcpRecordBytes = 16;
/// CAN: the 11-bit identifier in 2 bytes, then up to 8 data bytes (classic struct can_frame).
inline constexpr std::size_t kCanRecordBytes = 10;
/// USS: the longest telegram, STX LGE ADR, 252 payload bytes and BCC (LGE at most 254, so
/// LGE + 2 = 256 bytes on the wire).
inline constexpr std::size_t kUssRecordBytes = 256;

/// One recorded frame (a plain copy, outside the ring).
struct FrameRecord {
  MonoTime time{};                      ///< when it was sent / received
  Direction direction = Direction::Tx;  ///< which way
  std::uint8_t flags = 0;               ///< record_flag bits
  std::uint16_t length = 0;             ///< real frame length in bytes
  /// The recorder's record width, zero padded: the first min(length, width) are the frame's.
  std::vector<std::uint8_t> bytes;

  /// The stored bytes.
  std::span<const std::uint8_t> data() const noexcept {
    return {bytes.data(), length < bytes.size() ? length : bytes.size()};
  }
};

/// Turns a frame into a decoded text column (e.g. a DCP frame decoder); empty for none.
using FrameDecoder = std::function<std::string(const FrameRecord&)>;

/// Ring of records. record() is for exactly one writer thread: wait-free, allocation free.
/// copy() may run on any other thread at the same time and returns only whole records.
class FlightRecorder {
 public:
  /// A ring holding the newest `capacity` records of `record_bytes` each (kDcpRecordBytes,
  /// kCanRecordBytes, kUssRecordBytes: the link's longest frame), allocated here, once.
  FlightRecorder(std::size_t capacity, std::size_t record_bytes);

  /// The ring size in records.
  std::size_t capacity() const noexcept { return capacity_; }
  /// Bytes kept per record (the width asked for, rounded up to whole 8-byte words).
  std::size_t record_bytes() const noexcept { return words_per_record_ * 8; }

  /// Writer: appends a record (bytes beyond record_bytes() are cut).
  void record(MonoTime time, Direction direction, std::uint8_t flags,
              std::span<const std::uint8_t> bytes) noexcept;

  /// Any thread: the records still in the ring, oldest first. A record being overwritten
  /// during the copy is left out rather than returned torn.
  std::vector<FrameRecord> copy() const;

  /// Records written since construction.
  std::uint64_t total_records() const noexcept { return next_.load(std::memory_order_acquire); }

 private:
  // Each slot is a small seqlock: stamp is odd while written, 2 * (index + 1) when complete.
  // The slot's bytes live in `words_`, words_per_record_ words from slot * words_per_record_.
  struct Slot {
    std::atomic<std::uint64_t> stamp{0};
    std::atomic<std::int64_t> time_ns{0};
    std::atomic<std::uint64_t> meta{0};  // direction | flags << 8 | length << 16
  };

  std::size_t capacity_;
  std::size_t words_per_record_;
  std::unique_ptr<Slot[]> slots_;
  std::unique_ptr<std::atomic<std::uint64_t>[]> words_;
  std::atomic<std::uint64_t> next_{0};
};

/// Flag names separated by '|', e.g. "reply|bad".
std::string flags_to_string(std::uint8_t flags);

/// Writes one line per record: monotonic seconds, direction, hex bytes, flags and, with a
/// decoder, a decoded column after " | ".
void write_text(std::ostream& out, std::span<const FrameRecord> records,
                const FrameDecoder& decoder = {});

/// write_text() into a new file at `path`. Returns 0 or an errno.
int write_text_file(const std::string& path, std::span<const FrameRecord> records,
                    const FrameDecoder& decoder = {});

}  // namespace liftd::rt
