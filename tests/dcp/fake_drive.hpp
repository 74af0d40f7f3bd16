// A small scripted DCP drive for the master link tests (not the simulator): it answers master
// frames per DCP 6.2 (S7 on a corrupt frame, repeat on B7), parses our channel stream, answers
// I-messages, and lets a test inject faults one cycle at a time.
#pragma once

#include <deque>
#include <optional>
#include <set>
#include <vector>

#include "dcp/channel.hpp"
#include "dcp/frame.hpp"
#include "dcp/messages.hpp"

namespace liftd::dcp::test {

class FakeDrive {
 public:
  /// What the drive answers to I0.
  InitReply init{{'Z', 'A'}, 102, {1, 2, 15}, Protocol::Dcp4, {'D', 'E'}};
  /// Whether it supports the extended I9 reply.
  bool supports_extended = true;
  /// I-messages it never answers (e.g. I6 on a drive without emergency power support).
  std::set<MessageId> mute;
  /// Status byte and data word of every reply.
  std::uint8_t status = status_bit::kReady;
  std::uint16_t data_word = 0x7FFF;
  /// Whether an I2 'R' is accepted ('R') or refused ('0').
  bool accepts_reset = true;
  /// Travel distance reported in the extended I9 reply.
  SignedMm last_travel_mm = 1234;

  // ---- fault injection, per cycle ----
  /// The next N replies are corrupted on the wire (bad checksum at the master), after the drive
  /// built and remembered them.
  int corrupt_replies = 0;
  /// The next N replies are lost on the wire after the drive built them.
  int lose_replies = 0;
  /// The drive is off the bus for the next N frames: it neither sees nor answers them.
  int deaf_frames = 0;

  /// One cycle: the master's 6 bytes as they arrive (the test may have corrupted them); the
  /// reply as it arrives at the master, or nullopt if none.
  std::optional<FrameBytes> exchange(const FrameBytes& master, MonoTime now);

  /// Queues a raw drive -> master channel frame (STX mode payload ETX) after the current one.
  void send_frame(ChannelMode mode, const std::vector<std::uint8_t>& payload);
  /// Queues raw channel bytes (may be a broken frame).
  void send_raw(const std::vector<std::uint8_t>& bytes);

  // ---- what the drive saw ----
  std::vector<FrameBytes> frames;       ///< every master frame with a good checksum
  std::vector<std::uint8_t> stream;     ///< non-idle channel bytes consumed, in order
  std::vector<MasterMessage> messages;  ///< decoded I-messages, in order
  std::vector<MonoTime> message_times;  ///< when each message's ETX arrived
  std::vector<std::uint8_t> keypad;     ///< decoded keypad bytes, in order
  int resets_seen = 0;                  ///< STX ETX received
  int b7_seen = 0;
  int bad_frames = 0;                      ///< master frames with a bad checksum
  std::optional<MonoTime> reset_reply_at;  ///< when it replied 'R'

 private:
  void answer(const MasterMessage& message, MonoTime now);
  void feed(std::uint8_t byte, MonoTime now);

  ChannelParser parser_;
  std::deque<std::uint8_t> out_;  ///< channel bytes waiting to be sent, two per reply
  std::optional<FrameBytes> last_sent_;
  bool extended_ = false;
};

}  // namespace liftd::dcp::test
