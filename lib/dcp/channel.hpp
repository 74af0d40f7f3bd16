// The DCP communication channel byte stream (DCP 5.3 to 5.11): communication bytes 4 and 5 of
// every frame form a byte stream in each direction, framed as STX mode payload ETX.
// Sans-I/O: bytes and time in, frames and decisions out. No allocation, no clock, no logging.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>

#include "common/mono_time.hpp"
#include "dcp/charset.hpp"

namespace liftd::dcp {

/// Control characters of the channel (DCP 5.6.1).
namespace channel_char {
inline constexpr std::uint8_t kIdle = 0x00;          ///< DCP 5.9: nothing to send
inline constexpr std::uint8_t kStx = 0x02;           ///< start of text
inline constexpr std::uint8_t kEtx = 0x03;           ///< end of text
inline constexpr std::uint8_t kLine1 = 0x04;         ///< DCP 5.6.2: output in line 1 (0x04..0x07)
inline constexpr std::uint8_t kLine4 = 0x07;         ///< output in line 4
inline constexpr std::uint8_t kCursor0 = 0x08;       ///< DCP 5.6.2: cursor position 0 (0x08..0x1B)
inline constexpr std::uint8_t kCursor19 = 0x1B;      ///< cursor position 19
inline constexpr std::uint8_t kModeExpanded = 0x1C;  ///< DCP 5.6.1: expanded data (I-messages)
inline constexpr std::uint8_t kModeReserved = 0x1D;  ///< DCP 5.6.1: reserved
inline constexpr std::uint8_t kModeDriveError = 0x1E;  ///< DCP 5.11: drive error message
inline constexpr std::uint8_t kModeRemote = 0x1F;      ///< DCP 5.7/5.8: remote display / keypad
}  // namespace channel_char

/// The mode byte after STX (DCP 5.6.1).
enum class ChannelMode : std::uint8_t {
  Expanded = channel_char::kModeExpanded,      ///< 0x1C: I-messages (DCP 5.12)
  DriveError = channel_char::kModeDriveError,  ///< 0x1E: drive error text for the event log
  Remote = channel_char::kModeRemote,  ///< 0x1F: display (drive -> us) or keypad (us -> drive)
};

std::string_view to_string(ChannelMode mode) noexcept;

/// DCP 5.4: one second without an exchange, or one second from STX without ETX, resets the
/// channel to its initial state.
inline constexpr MonoTime kChannelTimeout = std::chrono::milliseconds(1000);

/// DCP 5.3: two channel bytes per 15 ms cycle in each direction.
inline constexpr std::size_t kChannelBytesPerCycle = 2;

/// Longest payload (bytes between the mode byte and ETX) the parser and the transmitter accept.
/// Why 131: DCP 5.4 resets the channel one second after STX. At two bytes per 15 ms cycle
/// (DCP 5.3, 7.2) at most 67 cycles = 134 bytes fit in that second, so STX + mode + payload +
/// ETX <= 134 and any longer frame is bound to time out. The largest frames the spec shows are
/// a full 4x20 display with line and cursor per line (2 + 88 + 1 bytes, DCP 5.7 footnote).
inline constexpr std::size_t kMaxChannelPayload = 131;

/// A complete channel frame: mode and payload, STX/ETX stripped. Fixed storage.
struct ChannelFrame {
  ChannelMode mode = ChannelMode::Expanded;
  std::array<std::uint8_t, kMaxChannelPayload> data{};
  std::size_t length = 0;
  /// The payload bytes.
  std::span<const std::uint8_t> payload() const noexcept { return {data.data(), length}; }
};

/// What one fed byte (or a time check) did to the parser.
enum class ParseStatus : std::uint8_t {
  NeedMore,  ///< nothing complete yet (also: idle bytes between frames)
  Complete,  ///< frame() holds a complete frame, valid until the next feed/poll/reset
  Reset,     ///< the channel went back to its initial state; see reset_reason()
  Bad,       ///< a malformed byte or frame was dropped; see error()
};

/// Why the parser dropped something (ParseStatus::Bad).
enum class ChannelError : std::uint8_t {
  None,
  DataOutsideFrame,  ///< a data or control byte between frames (only 0x00 and STX are allowed)
  MissingMode,       ///< STX followed by a data character instead of a mode byte
  UnknownMode,       ///< STX followed by a control byte that is no mode (not 0x1C/0x1E/0x1F)
  ReservedMode,      ///< STX followed by the reserved mode 0x1D
  Overflow,          ///< payload longer than kMaxChannelPayload
  StxInFrame,        ///< DCP 5.7: a new STX before ETX; the old frame is dropped, the new one runs
};

std::string_view to_string(ChannelError error) noexcept;

/// Why the parser went back to its initial state (ParseStatus::Reset).
enum class ChannelReset : std::uint8_t {
  None,
  StxEtx,        ///< DCP 5.10: the peer sent STX ETX
  IdleTimeout,   ///< DCP 5.4: one second without any byte fed (no exchange)
  FrameTimeout,  ///< DCP 5.4: one second from STX without ETX
};

std::string_view to_string(ChannelReset reason) noexcept;

/// Incremental receive-side parser of one direction of the channel. Feed it the channel bytes of
/// every frame that is to be consumed (two per cycle), with the cycle's time.
///
/// Rules: 0x00 between frames is idle. STX starts a frame; the next non-idle byte must be a mode.
/// In Expanded and DriveError frames 0x00 is idle fill and skipped (their content is data
/// characters only); in Remote frames 0x00 is kept because it is the keypad value "no button".
/// Control bytes 0x04..0x1F inside a frame are kept for the payload decoder to judge.
class ChannelParser {
 public:
  /// Feeds one byte received at `now`. Checks the timeouts first (a timed-out frame is reset
  /// before the byte is looked at; that reset is reported via reset_reason() if the byte itself
  /// completes nothing).
  ParseStatus feed(std::uint8_t byte, MonoTime now) noexcept;
  /// Checks the two DCP 5.4 timeouts without a byte; returns Reset if one expired.
  ParseStatus poll(MonoTime now) noexcept;
  /// Back to the initial state (between frames), as after STX ETX. Restarts the idle timer.
  void reset(MonoTime now) noexcept;

  /// The last complete frame (after ParseStatus::Complete).
  const ChannelFrame& frame() const noexcept { return frame_; }
  /// The last error (after ParseStatus::Bad).
  ChannelError error() const noexcept { return error_; }
  /// The last reset reason (after ParseStatus::Reset).
  ChannelReset reset_reason() const noexcept { return reset_reason_; }
  /// For StxInFrame and FrameTimeout: the mode of the dropped frame, if it had one (a display
  /// stream interrupted this way must clear the display, DCP 5.7).
  std::optional<ChannelMode> dropped_mode() const noexcept { return dropped_mode_; }
  /// True between STX and ETX.
  bool in_frame() const noexcept { return state_ != State::Idle; }

 private:
  enum class State : std::uint8_t {
    Idle,      ///< between frames
    WantMode,  ///< STX seen, waiting for the mode byte
    Payload,   ///< collecting payload until ETX
    Skipping,  ///< a bad frame: dropping bytes until ETX or STX
  };
  ParseStatus check_timeouts(MonoTime now) noexcept;
  ParseStatus start_frame(MonoTime now) noexcept;
  ParseStatus bad(ChannelError error) noexcept;

  State state_ = State::Idle;
  ChannelFrame frame_{};
  ChannelMode pending_mode_ = ChannelMode::Expanded;
  std::size_t pending_length_ = 0;
  std::array<std::uint8_t, kMaxChannelPayload> pending_{};
  bool have_time_ = false;
  bool idle_reported_ = false;
  MonoTime last_byte_at_{};
  MonoTime stx_at_{};
  ChannelError error_ = ChannelError::None;
  ChannelReset reset_reason_ = ChannelReset::None;
  std::optional<ChannelMode> dropped_mode_;
};

/// Two channel bytes for one frame.
using ChannelPair = std::array<std::uint8_t, kChannelBytesPerCycle>;

/// Send side of one direction: serialises one frame at a time, two bytes per cycle, padding with
/// 0x00 (idle) after ETX. It can repeat the last pair when the peer reported our frame corrupt
/// (DCP 6.1 b / 6.2: S7 or B7 seen: the communication bytes are repeated, not advanced).
class ChannelTransmitter {
 public:
  /// Queues STX mode payload ETX. False (nothing queued) if a frame is still being sent or the
  /// payload is longer than kMaxChannelPayload.
  bool start(ChannelMode mode, std::span<const std::uint8_t> payload) noexcept;
  /// Queues STX ETX (DCP 5.10 reset). False if busy.
  bool start_reset() noexcept;
  /// The next two bytes, advancing the stream (0x00 0x00 when idle).
  ChannelPair next_pair() noexcept;
  /// The last pair returned again, without advancing (0x00 0x00 before the first).
  ChannelPair repeat_pair() const noexcept { return last_pair_; }
  /// True while bytes of a frame remain to be sent.
  bool busy() const noexcept { return position_ < length_; }
  /// True once the frame's last byte (ETX) has left in a pair (the pair may still be repeated).
  bool idle() const noexcept { return !busy(); }
  /// Drops whatever is being sent; the next pair is idle.
  void clear() noexcept;

 private:
  /// STX + mode + payload + ETX
  std::array<std::uint8_t, kMaxChannelPayload + 3> bytes_{};
  std::size_t length_ = 0;
  std::size_t position_ = 0;
  ChannelPair last_pair_{};
};

}  // namespace liftd::dcp
