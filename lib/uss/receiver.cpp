#include "uss/receiver.hpp"

#include "uss/timing.hpp"

namespace liftd::uss {
namespace {

// A 4.2: LGE = n + 2, so the telegram is LGE + 2 bytes (STX and LGE are not counted).
constexpr std::size_t kUncountedBytes = 2;
// The deadline is the first late instant: max residual time + 1 ns (A 6.3 is a maximum).
constexpr std::chrono::nanoseconds kOneTick{1};

RxError line_error(LineError e) noexcept {
  switch (e) {
    case LineError::Parity:
      return RxError::Parity;
    case LineError::Overrun:
      return RxError::Overrun;
    case LineError::Framing:
    case LineError::Break:  // a break is a character without a valid stop bit
    case LineError::None:
      break;
  }
  return RxError::Framing;
}

}  // namespace

std::string_view to_string(RxError error) noexcept {
  switch (error) {
    case RxError::Framing:
      return "framing error";
    case RxError::Overrun:
      return "overrun";
    case RxError::Parity:
      return "parity error";
    case RxError::NoStx:
      return "telegram start not recognised";
    case RxError::Bcc:
      return "wrong BCC";
    case RxError::ResidualTime:
      return "residual telegram time exceeded";
    case RxError::Lge:
      return "wrong telegram length";
    case RxError::ReplyTimeout:
      return "reply delay exceeded";
  }
  return "?";
}

Receiver::Receiver(std::uint32_t baud) noexcept : baud_(baud), start_pause_(start_pause(baud)) {}

void Receiver::restart() noexcept {
  state_ = State::Hunting;
  burst_counted_ = false;
  have_last_ = false;
  count_ = 0;
}

void Receiver::begin(MonoTime at) noexcept {
  state_ = State::Lge;
  started_at_ = at;
  buf_[0] = kStx;
  count_ = 1;
  bcc_ = kStx;  // A 4.4: BCC = 0 EXOR STX
  telegram_lge_ = expected_lge_;
  // A 5.2.1.2: variable length starts with the value for 252 payload bytes; fixed length with
  // the correct value at once.
  const std::size_t n = expected_lge_ == 0
                            ? kMaxPayloadBytes
                            : (expected_lge_ < kMinLge ? 0 : std::size_t{expected_lge_} - 2);
  deadline_ = at + max_residual_time(baud_, n) + kOneTick;
}

RxResult Receiver::reject(RxError error) noexcept {
  switch (error) {
    case RxError::Framing:
      ++counters_.framing;
      break;
    case RxError::Overrun:
      ++counters_.overrun;
      break;
    case RxError::Parity:
      ++counters_.parity;
      break;
    case RxError::NoStx:
      ++counters_.no_stx;
      break;
    case RxError::Bcc:
      ++counters_.bcc;
      break;
    case RxError::ResidualTime:
      ++counters_.residual_time;
      break;
    case RxError::Lge:
      ++counters_.lge;
      break;
    case RxError::ReplyTimeout:  // never a rejected telegram; see count_reply_timeout()
      break;
  }
  if (error != RxError::ReplyTimeout) ++counters_.rejected;
  counters_.error_word = static_cast<std::uint16_t>(counters_.error_word | error_bit(error));
  state_ = State::Hunting;
  burst_counted_ = true;  // the rest of this telegram is ignored until a start pause
  count_ = 0;
  return RxResult{RxResult::Kind::Rejected, error};
}

RxResult Receiver::hunt(const RxChar& c, MonoTime at, bool pause_before) noexcept {
  if (pause_before) burst_counted_ = false;
  const bool start_allowed = pause_before || !pause_check_;
  if (c.error == LineError::None && c.byte == kStx && start_allowed) {
    begin(at);
    return RxResult{};
  }
  if (burst_counted_) return RxResult{};  // rest of a burst already charged
  // The first character of a burst is no valid telegram start (A 5.2.3 bit 3), or is itself
  // corrupt (bits 0..2).
  return reject(c.error != LineError::None ? line_error(c.error) : RxError::NoStx);
}

RxResult Receiver::feed(const RxChar& c, MonoTime at) noexcept {
  const bool pause_before = !have_last_ || at - last_at_ >= start_pause_;
  have_last_ = true;
  last_at_ = at;

  if (state_ == State::Hunting) return hunt(c, at, pause_before);

  if (at >= deadline_) {
    // A 5.2.1.2: the telegram in progress is late. The character is charged to it; if it
    // follows a start pause and is an STX it begins the next telegram.
    const RxResult late = reject(RxError::ResidualTime);
    if (pause_before && c.error == LineError::None && c.byte == kStx) begin(at);
    return late;
  }
  if (c.error != LineError::None) return reject(line_error(c.error));

  buf_[count_++] = c.byte;
  if (state_ == State::Lge) {
    const std::uint8_t lge = c.byte;
    // A 4.2: 2..254 always; A 4.2.2: fixed length must match (a fixed value outside 2..254
    // thus rejects every telegram).
    const bool ok =
        lge >= kMinLge && lge <= kMaxLge && (telegram_lge_ == 0 || lge == telegram_lge_);
    if (!ok) return reject(RxError::Lge);
    telegram_lge_ = lge;
    bcc_ = static_cast<std::uint8_t>(bcc_ ^ lge);
    // A 5.2.1.2: with LGE known the supervision is reloaded with the correct value.
    deadline_ = started_at_ + max_residual_time_for_lge(baud_, lge) + kOneTick;
    if (at >= deadline_) return reject(RxError::ResidualTime);
    state_ = State::Body;
    return RxResult{};
  }

  if (count_ < std::size_t{telegram_lge_} + kUncountedBytes) {
    bcc_ = static_cast<std::uint8_t>(bcc_ ^ c.byte);
    return RxResult{};
  }
  // The last character is the BCC (A 4.4).
  if (c.byte != bcc_) return reject(RxError::Bcc);
  ++counters_.good;
  for (std::size_t i = 0; i < count_; ++i) done_[i] = buf_[i];
  done_bytes_ = count_;
  count_ = 0;
  state_ = State::Hunting;
  burst_counted_ = false;  // anything right after a good telegram starts a new burst
  return RxResult{RxResult::Kind::Complete, RxError::Framing};
}

RxResult Receiver::check_time(MonoTime now) noexcept {
  if (state_ != State::Hunting && now >= deadline_) return reject(RxError::ResidualTime);
  return RxResult{};
}

std::optional<MonoTime> Receiver::deadline() const noexcept {
  if (state_ == State::Hunting) return std::nullopt;
  return deadline_;
}

Telegram Receiver::telegram() const noexcept {
  if (done_bytes_ < kFrameOverheadBytes) return Telegram{};
  return Telegram{done_[2], std::span<const std::uint8_t>(done_.data() + 3, done_bytes_ - 4)};
}

std::span<const std::uint8_t> Receiver::bytes() const noexcept {
  return {done_.data(), done_bytes_};
}

void Receiver::count_reply_timeout() noexcept {
  ++counters_.reply_timeout;
  counters_.error_word =
      static_cast<std::uint16_t>(counters_.error_word | error_bit(RxError::ReplyTimeout));
}

}  // namespace liftd::uss
