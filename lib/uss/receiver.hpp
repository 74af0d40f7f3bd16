// The receive side of a USS station (A 5.2), master and slave alike: start detection
// (start pause + STX), LGE check, residual-time supervision, BCC, character errors, and the
// diagnostic counters and error word of A 5.2.3. Sans-I/O: the caller passes each character
// with the time it was received and calls check_time() when deadline() passes.
// noexcept and allocation-free after construction.
//
// Decisions (each with the spec sentence it rests on):
//  - Start of a telegram: "Erst ein STX mit vorangegangener Startpause kennzeichnet einen
//    gültigen Telegrammbeginn" (A 5.1.2). An STX starts a telegram only if the previous
//    character was received at least start_pause() (2 character times) earlier. Timestamps mark
//    whole characters, so a stamp gap of 2 tz means at least 1 tz of silence: one character of
//    tolerance for timestamp jitter; inside a telegram the character delay must stay below the
//    start pause (A 6.3). The first character after construction or restart() counts as preceded
//    by a pause (the caller restarts when it knows the line was quiet, e.g. after sending).
//    set_start_pause_check(false) accepts any STX while hunting.
//  - "Telegrammstart nicht erkannt (erstes Zeichen kein STX)" (A 5.2.3 bit 3): while hunting,
//    the first character of a burst (a character after a start pause, or the first one after a
//    good telegram) that does not start a telegram is counted once as NoStx; the rest of that
//    burst is ignored silently.
//  - LGE: "Entspricht die Angabe der Länge nicht dem eingestellten Wert bei fester
//    Telegrammlänge oder hat sie keinen gültigen Wert bei variabler Telegrammlänge, wird das
//    Telegramm verworfen" (A 5.2). Fixed: LGE must equal set_expected_lge(); variable: 2..254
//    (A 4.2). Rejected at once when LGE arrives.
//  - Residual time (A 5.2.1.2, A 6.3): from the STX's time stamp the telegram must be complete
//    within 1.5 * (n + 3) * tz, n = payload characters. Variable length: loaded with n = 252 at
//    STX, reloaded with n = LGE - 2 when LGE arrives; fixed length: n = expected LGE - 2 at
//    once. A character stamped exactly at STX + max is still accepted; from one nanosecond later
//    the telegram is rejected (deadline() returns that first late instant).
//  - Parity, framing, overrun, break (A 5.2.2: "Nur fehlerfrei empfangene ... Telegramme werden
//    weiterverarbeitet"; A 5.2: ADR may only be evaluated if no character had a framing or parity
//    error): the telegram can no longer become valid, so it is rejected on that character (break
//    counts as framing error: a break is a character frame without stop bit).
//  - BCC: "Stimmen diese nicht überein, wird das Telegramm nicht ausgewertet" (A 5.2): checked
//    on the last character.
//  - After every rejection the receiver hunts for the next STX that follows a start pause; the
//    rest of the rejected telegram is ignored and not counted again. A character that arrives
//    too late is first charged to the late telegram, then examined as a possible new start.
//  - Address: "Entspricht das Adreßbyte (ADR) nicht der Teilnehmernummer (beim Slave) oder der
//    erwarteten Slave-Teilnehmernummer (beim Master), so wird das Telegramm verworfen" (A 5.2).
//    The receiver does not know the address: the caller compares telegram().adr (parse_adr) and
//    drops the telegram; A 5.2.3 has no counter for it, so it stays counted as good.
//  - Counters: every rejected telegram increments `rejected` and exactly one reason counter,
//    so rejected == framing + overrun + parity + no_stx + residual_time + bcc + lge always.
//    reply_timeout (count_reply_timeout) is no rejected telegram. The error word keeps every
//    bit ever set until clear_error_word().
#pragma once

#include <array>
#include <chrono>
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>

#include "common/mono_time.hpp"
#include "uss/line.hpp"
#include "uss/telegram.hpp"

namespace liftd::uss {

/// Receive errors; the value is the bit number in the A 5.2.3 error word.
enum class RxError : std::uint8_t {
  Framing = 0,       ///< bit 0: character frame error (and break)
  Overrun = 1,       ///< bit 1: buffer overrun
  Parity = 2,        ///< bit 2: parity error
  NoStx = 3,         ///< bit 3: telegram start not recognised (first character no STX)
  Bcc = 4,           ///< bit 4: wrong block check character
  ResidualTime = 5,  ///< bit 5: residual telegram time exceeded
  Lge = 6,           ///< bit 6: wrong telegram length
  ReplyTimeout = 7,  ///< bit 7: master: reply delay exceeded (slave: bus monitoring time)
};

std::string_view to_string(RxError error) noexcept;

/// The error word bit of an error (A 5.2.3).
constexpr std::uint16_t error_bit(RxError error) noexcept {
  return static_cast<std::uint16_t>(1U << static_cast<unsigned>(error));
}

/// A 5.2.3 diagnostics (items 4 and 7..16).
struct RxCounters {
  std::uint64_t good = 0;           ///< 7: error-free telegrams
  std::uint64_t rejected = 0;       ///< 8: rejected telegrams
  std::uint64_t framing = 0;        ///< 9: framing errors (breaks included)
  std::uint64_t overrun = 0;        ///< 10: overruns
  std::uint64_t parity = 0;         ///< 11: parity errors
  std::uint64_t no_stx = 0;         ///< 12: telegram start not recognised
  std::uint64_t residual_time = 0;  ///< 13: residual telegram time exceeded
  std::uint64_t bcc = 0;            ///< 14: BCC errors
  std::uint64_t lge = 0;            ///< 15: wrong telegram length
  std::uint64_t reply_timeout = 0;  ///< 16: supervision time exceeded (master: reply delay)
  std::uint16_t error_word = 0;     ///< 4: bit per RxError (bits 8..15 reserved, always 0)
  bool operator==(const RxCounters&) const = default;
};

/// What one feed()/check_time() did.
struct RxResult {
  enum class Kind : std::uint8_t {
    Pending,   ///< nothing finished (inside a telegram, or hunting)
    Complete,  ///< a telegram passed every check: telegram() holds it
    Rejected,  ///< a telegram was rejected for `error`
  };
  Kind kind = Kind::Pending;
  RxError error = RxError::Framing;  ///< meaningful for Rejected only
  bool operator==(const RxResult&) const = default;
};

class Receiver {
 public:
  /// baud sets the character time for the start pause and the residual time (A 6).
  explicit Receiver(std::uint32_t baud) noexcept;

  /// Fixed telegram length (A 4.2.2): the LGE every telegram must carry; 0 = variable length:
  /// any valid LGE (2..254). Takes effect at the next STX.
  void set_expected_lge(std::uint8_t lge) noexcept { expected_lge_ = lge; }
  std::uint8_t expected_lge() const noexcept { return expected_lge_; }
  /// Whether an STX needs a preceding start pause (default true, A 5.1.2).
  void set_start_pause_check(bool on) noexcept { pause_check_ = on; }
  /// Drops a telegram in progress (uncounted) and hunts for the next STX; the next character
  /// counts as preceded by a start pause.
  void restart() noexcept;

  /// One received character, stamped with the time it was received.
  RxResult feed(const RxChar& c, MonoTime at) noexcept;
  /// Residual-time supervision: rejects the telegram in progress once now >= deadline().
  RxResult check_time(MonoTime now) noexcept;
  /// While a telegram is in progress: the first instant at which it is late
  /// (STX stamp + max residual time + 1 ns); nullopt while hunting.
  std::optional<MonoTime> deadline() const noexcept;
  /// True between an accepted STX and the end of that telegram.
  bool receiving() const noexcept { return state_ != State::Hunting; }

  /// The last complete telegram (a view into the receiver); valid after Complete until the next
  /// Complete (telegrams in progress do not disturb it).
  Telegram telegram() const noexcept;
  /// The last complete telegram's bytes, STX through BCC (for mirror checks, A 5.3).
  std::span<const std::uint8_t> bytes() const noexcept;

  /// Master: the reply delay ran out (A 5.2.1.1): counter 16 and error word bit 7.
  void count_reply_timeout() noexcept;
  const RxCounters& counters() const noexcept { return counters_; }
  void clear_error_word() noexcept { counters_.error_word = 0; }
  void reset_counters() noexcept { counters_ = RxCounters{}; }

  std::uint32_t baud() const noexcept { return baud_; }

 private:
  enum class State : std::uint8_t { Hunting, Lge, Body };
  RxResult reject(RxError error) noexcept;
  RxResult hunt(const RxChar& c, MonoTime at, bool pause_before) noexcept;
  void begin(MonoTime at) noexcept;

  std::uint32_t baud_;
  std::chrono::nanoseconds start_pause_;
  std::uint8_t expected_lge_ = 0;
  bool pause_check_ = true;

  State state_ = State::Hunting;
  bool burst_counted_ = false;  // the current burst was charged (NoStx or a rejection) already
  bool have_last_ = false;      // false after construction/restart(): treat as line quiet
  MonoTime last_at_{};
  MonoTime started_at_{};
  MonoTime deadline_{};  // first late instant
  std::uint8_t telegram_lge_ = 0;
  std::size_t count_ = 0;       // bytes in buf_
  std::size_t done_bytes_ = 0;  // bytes in done_
  std::uint8_t bcc_ = 0;
  std::array<std::uint8_t, kMaxTelegramBytes> buf_{};   // telegram in progress
  std::array<std::uint8_t, kMaxTelegramBytes> done_{};  // last complete telegram
  RxCounters counters_{};
};

}  // namespace liftd::uss
