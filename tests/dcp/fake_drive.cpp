#include "fake_drive.hpp"

#include <variant>

namespace liftd::dcp::test {

std::optional<FrameBytes> FakeDrive::exchange(const FrameBytes& master, MonoTime now) {
  if (deaf_frames > 0) {
    --deaf_frames;
    return std::nullopt;
  }
  FrameBytes reply{};
  const auto m = decode_master(master);
  if (!m) {
    // DCP 6.2 a: ignore the frame (and its B7), answer with S7 and idle channel bytes.
    ++bad_frames;
    SlaveFrame s{static_cast<std::uint8_t>(status | status_bit::kMessageChecksumError), 0, 0, 0, 0};
    s.set_data_word(data_word);
    reply = encode(s);
  } else {
    frames.push_back(master);
    feed(m->comm1, now);
    feed(m->comm2, now);
    if ((m->command & command_bit::kReplyChecksumError) != 0 && last_sent_) {
      ++b7_seen;
      reply = *last_sent_;  // DCP 6.2 b: repeat the last reply
    } else {
      SlaveFrame s{status, 0, 0, 0, 0};
      s.set_data_word(data_word);
      if (!out_.empty()) {
        s.comm1 = out_.front();
        out_.pop_front();
      }
      if (!out_.empty()) {
        s.comm2 = out_.front();
        out_.pop_front();
      }
      reply = encode(s);
    }
  }
  last_sent_ = reply;
  if (lose_replies > 0) {
    --lose_replies;
    return std::nullopt;
  }
  if (corrupt_replies > 0) {
    --corrupt_replies;
    reply[5] ^= 0x01;  // one flipped bit breaks the XOR checksum
  }
  return reply;
}

void FakeDrive::send_frame(ChannelMode mode, const std::vector<std::uint8_t>& payload) {
  out_.push_back(channel_char::kStx);
  out_.push_back(static_cast<std::uint8_t>(mode));
  out_.insert(out_.end(), payload.begin(), payload.end());
  out_.push_back(channel_char::kEtx);
}

void FakeDrive::send_raw(const std::vector<std::uint8_t>& bytes) {
  out_.insert(out_.end(), bytes.begin(), bytes.end());
}

void FakeDrive::feed(std::uint8_t byte, MonoTime now) {
  if (byte != channel_char::kIdle) stream.push_back(byte);
  const ParseStatus status_now = parser_.feed(byte, now);
  if (status_now == ParseStatus::Reset && parser_.reset_reason() == ChannelReset::StxEtx) {
    ++resets_seen;
  }
  if (status_now != ParseStatus::Complete) return;
  const ChannelFrame& frame = parser_.frame();
  if (frame.mode == ChannelMode::Expanded) {
    const auto decoded = decode_master_message(frame.payload());
    if (!decoded.ok()) return;
    messages.push_back(decoded.value);
    message_times.push_back(now);
    answer(decoded.value, now);
  } else if (frame.mode == ChannelMode::Remote) {
    const auto decoded = decode_keypad(frame.payload());
    if (decoded.ok()) keypad.push_back(decoded.value);
  }
}

void FakeDrive::answer(const MasterMessage& message, MonoTime now) {
  if (mute.count(message_id(message)) != 0) return;
  DriveMessage reply;
  if (std::holds_alternative<InitRequest>(message)) {
    reply = init;
  } else if (const auto* i1 = std::get_if<DataInfoRequest>(&message)) {
    extended_ = i1->extended_protocol && supports_extended;
    reply = DataInfoReply{extended_};
  } else if (const auto* i2 = std::get_if<SwitchRequest>(&message)) {
    SwitchFunction f = i2->function;
    if (f == SwitchFunction::Reset) {
      if (accepts_reset) {
        reset_reply_at = now;
      } else {
        f = SwitchFunction::None;
      }
    }
    reply = SwitchReply{f};
  } else if (std::holds_alternative<DateTimeRequest>(message)) {
    reply = DateTimeReply{};
  } else if (const auto* i6 = std::get_if<PowerRequest>(&message)) {
    reply = PowerReply{i6->supply, i6->saving};
  } else if (const auto* i7 = std::get_if<StartParamsRequest>(&message)) {
    // the spec's two examples at V4: 300 cm short (Sg 300, Sv 143), 1000 cm long (520, 250)
    if (i7->distance_cm >= 520) {
      reply = StartParamsReply{TravelKind::Long, 520, 250};
    } else {
      reply = StartParamsReply{TravelKind::Short, i7->distance_cm, i7->distance_cm * 143 / 300};
    }
  } else if (std::holds_alternative<LoadRequest>(message)) {
    reply = LoadReply{};
  } else if (std::holds_alternative<PositionRequest>(message)) {
    reply = PositionReply{extended_, last_travel_mm};
  }
  const auto payload = encode(reply);
  if (!payload.ok()) return;
  send_frame(ChannelMode::Expanded,
             std::vector<std::uint8_t>(payload.value.bytes().begin(), payload.value.bytes().end()));
}

}  // namespace liftd::dcp::test
