// libFuzzer target: arbitrary character streams with arbitrary timing through the USS receiver
// (A 5.2), every complete telegram through the payload decoder. Input: one configuration byte
// (bit 0: fixed length with LGE from the second byte, bit 1: no start-pause check, bits 2..3:
// baud 9600/19200/38400/187500), then pairs (control, byte): control bits 0..2 = line error
// (0 none, 1 parity, 2 framing, 3 overrun, 4 break, 5 none + check_time afterwards, 6 restart
// first, 7 none), bits 3..7 = time since the previous character in quarter character times (31:
// 400 ms). Invariants: counters add up, results and counters agree, a complete telegram is
// well-formed (STX, LGE = payload + 2, BCC), the deadline exists exactly while receiving.
#include <array>
#include <cstdlib>

#include "uss/pkw.hpp"
#include "uss/receiver.hpp"
#include "uss/telegram.hpp"
#include "uss/timing.hpp"

namespace {

using namespace liftd::uss;

void check(bool ok) {
  if (!ok) abort();
}

std::uint64_t reasons(const RxCounters& c) {
  return c.framing + c.overrun + c.parity + c.no_stx + c.residual_time + c.bcc + c.lge;
}

void check_result(const Receiver& rx, const RxResult& r, const RxCounters& before) {
  const RxCounters& now = rx.counters();
  check(now.rejected == reasons(now));
  check((now.error_word & 0xFF80) == 0);
  check(rx.deadline().has_value() == rx.receiving());
  switch (r.kind) {
    case RxResult::Kind::Pending:
      check(now.good == before.good && now.rejected == before.rejected);
      break;
    case RxResult::Kind::Rejected:
      check(now.good == before.good && now.rejected == before.rejected + 1);
      check(r.error != RxError::ReplyTimeout);
      check((now.error_word & error_bit(r.error)) != 0);
      break;
    case RxResult::Kind::Complete: {
      check(now.good == before.good + 1 && now.rejected == before.rejected);
      const auto bytes = rx.bytes();
      const Telegram t = rx.telegram();
      check(bytes.size() >= 4 && bytes.size() <= kMaxTelegramBytes);
      check(bytes[0] == kStx);
      check(bytes[1] >= kMinLge && bytes[1] <= kMaxLge);
      check(t.payload.size() == std::size_t{bytes[1]} - 2);
      check(bytes.size() == std::size_t{bytes[1]} + 2);
      check(block_check(bytes.first(bytes.size() - 1)) == bytes.back());
      check(t.adr == bytes[2]);
      if (rx.expected_lge() != 0) check(bytes[1] == rx.expected_lge());
      check(decode_telegram(bytes).has_value());
      std::array<std::uint8_t, kMaxTelegramBytes> again{};
      check(encode_telegram(t.adr, t.payload, again) == bytes.size());
      for (std::size_t i = 0; i < bytes.size(); ++i) check(again[i] == bytes[i]);
      // The payload through the PKW/PZD decoder and back.
      for (PkwLength len :
           {PkwLength::None, PkwLength::Three, PkwLength::Four, PkwLength::Variable}) {
        for (std::uint8_t pzd_words : {0, 2, 16}) {
          Pkw pkw;
          std::array<std::uint16_t, kMaxPzdWords> pzd{};
          if (!decode_payload(t.payload, len, pzd_words, pkw, pzd)) continue;
          (void)classify_reply(pkw, pkw);
          (void)reply_name(pkw.id);
          std::array<std::uint8_t, kMaxPayloadBytes> out{};
          const std::size_t n =
              encode_payload(pkw, len, std::span<const std::uint16_t>(pzd.data(), pzd_words), out);
          // A variable area of PKE + IND only is re-encoded with one PWE word more.
          if (len == PkwLength::Variable && pkw.pwe_count == 0) continue;
          check(n == t.payload.size());
          for (std::size_t i = 0; i < n; ++i) check(out[i] == t.payload[i]);
        }
      }
      break;
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 2) return 0;
  constexpr std::array<std::uint32_t, 4> kBauds{9600, 19200, 38400, 187500};
  const std::uint8_t config = data[0];
  Receiver rx(kBauds[(config >> 2) & 3]);
  if ((config & 1) != 0) rx.set_expected_lge(data[1]);
  rx.set_start_pause_check((config & 2) == 0);
  const std::chrono::nanoseconds quarter = character_time(rx.baud()) / 4;
  liftd::MonoTime now{std::chrono::seconds(1)};
  for (std::size_t i = 2; i + 1 < size; i += 2) {
    const std::uint8_t ctl = data[i];
    const unsigned steps = ctl >> 3;
    now += steps == 31 ? std::chrono::milliseconds(400) : quarter * steps;
    LineError error = LineError::None;
    switch (ctl & 7) {
      case 1:
        error = LineError::Parity;
        break;
      case 2:
        error = LineError::Framing;
        break;
      case 3:
        error = LineError::Overrun;
        break;
      case 4:
        error = LineError::Break;
        break;
      case 6:
        rx.restart();
        check(!rx.receiving());
        break;
      default:
        break;
    }
    RxCounters before = rx.counters();
    const RxResult r = rx.feed(RxChar{data[i + 1], error}, now);
    check_result(rx, r, before);
    if ((ctl & 7) == 5) {
      before = rx.counters();
      const auto deadline = rx.deadline();
      const RxResult t = rx.check_time(now);
      check(t.kind != RxResult::Kind::Complete);
      check((t.kind == RxResult::Kind::Rejected) == (deadline && now >= *deadline));
      check_result(rx, t, before);
    }
  }
  const RxCounters before = rx.counters();
  const RxResult last = rx.check_time(now + std::chrono::seconds(10));
  check(last.kind != RxResult::Kind::Complete);
  check_result(rx, last, before);
  check(!rx.receiving());
  return 0;
}
