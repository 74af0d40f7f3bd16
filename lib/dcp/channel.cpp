#include "dcp/channel.hpp"

#include <algorithm>

namespace liftd::dcp {

using namespace channel_char;

std::string_view to_string(ChannelMode mode) noexcept {
  switch (mode) {
    case ChannelMode::Expanded:
      return "expanded data";
    case ChannelMode::DriveError:
      return "drive error message";
    case ChannelMode::Remote:
      return "remote display/keypad";
  }
  return "unknown mode";
}

std::string_view to_string(ChannelError error) noexcept {
  switch (error) {
    case ChannelError::None:
      return "no error";
    case ChannelError::DataOutsideFrame:
      return "byte outside a frame (only idle 0x00 or STX allowed)";
    case ChannelError::MissingMode:
      return "STX not followed by a mode byte";
    case ChannelError::UnknownMode:
      return "STX followed by an unknown control byte";
    case ChannelError::ReservedMode:
      return "STX followed by the reserved mode 0x1D";
    case ChannelError::Overflow:
      return "frame longer than the channel allows";
    case ChannelError::StxInFrame:
      return "new STX before ETX: frame dropped";
  }
  return "unknown channel error";
}

std::string_view to_string(ChannelReset reason) noexcept {
  switch (reason) {
    case ChannelReset::None:
      return "no reset";
    case ChannelReset::StxEtx:
      return "STX ETX received";
    case ChannelReset::IdleTimeout:
      return "no exchange for 1 s";
    case ChannelReset::FrameTimeout:
      return "no ETX within 1 s of STX";
  }
  return "unknown reset";
}

// ---- ChannelParser ---------------------------------------------------------------------------

ParseStatus ChannelParser::check_timeouts(MonoTime now) noexcept {
  if (!have_time_) {
    have_time_ = true;
    last_byte_at_ = now;
    return ParseStatus::NeedMore;
  }
  if (state_ != State::Idle && now - stx_at_ >= kChannelTimeout) {
    dropped_mode_ = state_ == State::Payload ? std::optional(pending_mode_) : std::nullopt;
    state_ = State::Idle;
    reset_reason_ = ChannelReset::FrameTimeout;
    last_byte_at_ = now;  // the reset starts a fresh idle period
    return ParseStatus::Reset;
  }
  if (!idle_reported_ && now - last_byte_at_ >= kChannelTimeout) {
    idle_reported_ = true;  // report a silence once, not every poll
    dropped_mode_ = state_ == State::Payload ? std::optional(pending_mode_) : std::nullopt;
    state_ = State::Idle;
    reset_reason_ = ChannelReset::IdleTimeout;
    return ParseStatus::Reset;
  }
  return ParseStatus::NeedMore;
}

ParseStatus ChannelParser::poll(MonoTime now) noexcept {
  return check_timeouts(now);
}

void ChannelParser::reset(MonoTime now) noexcept {
  state_ = State::Idle;
  pending_length_ = 0;
  have_time_ = true;
  last_byte_at_ = now;
  idle_reported_ = false;
  dropped_mode_.reset();
}

ParseStatus ChannelParser::bad(ChannelError error) noexcept {
  error_ = error;
  return ParseStatus::Bad;
}

ParseStatus ChannelParser::start_frame(MonoTime now) noexcept {
  const State was = state_;
  const ChannelMode was_mode = pending_mode_;
  state_ = State::WantMode;
  pending_length_ = 0;
  stx_at_ = now;
  if (was == State::WantMode || was == State::Payload) {
    // DCP 5.7: an STX before ETX drops the running frame (and clears a display).
    dropped_mode_ = was == State::Payload ? std::optional(was_mode) : std::nullopt;
    return bad(ChannelError::StxInFrame);
  }
  return ParseStatus::NeedMore;
}

ParseStatus ChannelParser::feed(std::uint8_t byte, MonoTime now) noexcept {
  const ParseStatus timeout = check_timeouts(now);
  last_byte_at_ = now;
  idle_reported_ = false;
  ParseStatus status = ParseStatus::NeedMore;
  switch (state_) {
    case State::Idle:
      if (byte == kIdle) break;
      if (byte == kStx) {
        status = start_frame(now);
        break;
      }
      status = bad(ChannelError::DataOutsideFrame);
      break;
    case State::WantMode:
      if (byte == kIdle) break;
      if (byte == kStx) {
        status = start_frame(now);
      } else if (byte == kEtx) {
        state_ = State::Idle;  // DCP 5.10: STX ETX resets the channel
        reset_reason_ = ChannelReset::StxEtx;
        dropped_mode_.reset();
        status = ParseStatus::Reset;
      } else if (byte == kModeExpanded || byte == kModeDriveError || byte == kModeRemote) {
        pending_mode_ = static_cast<ChannelMode>(byte);
        pending_length_ = 0;
        state_ = State::Payload;
      } else {
        state_ = State::Skipping;
        status = bad(byte == kModeReserved   ? ChannelError::ReservedMode
                     : byte < kFirstDataChar ? ChannelError::UnknownMode
                                             : ChannelError::MissingMode);
      }
      break;
    case State::Payload:
      if (byte == kEtx) {
        frame_.mode = pending_mode_;
        std::copy_n(pending_.begin(), pending_length_, frame_.data.begin());
        frame_.length = pending_length_;
        state_ = State::Idle;
        status = ParseStatus::Complete;
      } else if (byte == kStx) {
        status = start_frame(now);
      } else if (byte == kIdle && pending_mode_ != ChannelMode::Remote) {
        // idle fill inside a text-only frame carries nothing
      } else if (pending_length_ >= kMaxChannelPayload) {
        state_ = State::Skipping;
        status = bad(ChannelError::Overflow);
      } else {
        pending_[pending_length_++] = byte;
      }
      break;
    case State::Skipping:
      if (byte == kEtx) {
        state_ = State::Idle;
      } else if (byte == kStx) {
        state_ = State::Idle;  // the bad frame was reported already; this STX starts afresh
        status = start_frame(now);
      }
      break;
  }
  // A timeout reset that happened before this byte wins over "need more" and over an error the
  // byte caused right after it (that byte belongs to no frame anyway).
  if (timeout == ParseStatus::Reset && status != ParseStatus::Complete) return ParseStatus::Reset;
  return status;
}

// ---- ChannelTransmitter -----------------------------------------------------------------------

bool ChannelTransmitter::start(ChannelMode mode, std::span<const std::uint8_t> payload) noexcept {
  if (busy() || payload.size() > kMaxChannelPayload) return false;
  bytes_[0] = kStx;
  bytes_[1] = static_cast<std::uint8_t>(mode);
  std::copy(payload.begin(), payload.end(), bytes_.begin() + 2);
  bytes_[2 + payload.size()] = kEtx;
  length_ = payload.size() + 3;
  position_ = 0;
  return true;
}

bool ChannelTransmitter::start_reset() noexcept {
  if (busy()) return false;
  bytes_[0] = kStx;
  bytes_[1] = kEtx;
  length_ = 2;
  position_ = 0;
  return true;
}

ChannelPair ChannelTransmitter::next_pair() noexcept {
  ChannelPair pair{kIdle, kIdle};
  for (auto& byte : pair) {
    if (position_ < length_) byte = bytes_[position_++];
  }
  if (position_ >= length_) {
    position_ = 0;
    length_ = 0;
  }
  last_pair_ = pair;
  return pair;
}

void ChannelTransmitter::clear() noexcept {
  position_ = 0;
  length_ = 0;
  last_pair_ = {kIdle, kIdle};
}

}  // namespace liftd::dcp
