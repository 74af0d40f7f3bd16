// A fake-clock bus for the master engine: sends the master's telegrams as a UART would (one
// character time per byte) and feeds replies character by character, each stamped when it is
// complete. Slaves are written from the spec (C 4, A 5.3), not from the master.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdint>
#include <span>
#include <vector>

#include "common/mono_time.hpp"
#include "uss/master/master.hpp"
#include "uss/pkw.hpp"
#include "uss/telegram.hpp"
#include "uss/timing.hpp"

namespace liftd::uss::testing {

using Bytes = std::vector<std::uint8_t>;

/// One telegram the master sent.
struct Sent {
  Bytes bytes;
  MonoTime start{};  ///< when sending began (the master's next_telegram time)
  MonoTime end{};    ///< when its last character left the line
};

/// A request taken apart the way a slave does (A 4, C 2).
struct Request {
  AddressByte adr;
  Pkw pkw;
  std::vector<std::uint16_t> pzd;
  bool ok = false;
};

inline Request parse_request(const Bytes& bytes, PkwLength len, std::uint8_t pzd_words) {
  Request r;
  const auto t = decode_telegram(bytes);
  if (!t) return r;
  r.adr = parse_adr(t->adr);
  r.pzd.resize(pzd_words);
  r.ok = decode_payload(t->payload, len, pzd_words, r.pkw, r.pzd);
  return r;
}

/// STX LGE ADR payload BCC of a reply.
inline Bytes make_telegram(std::uint8_t adr, std::span<const std::uint8_t> payload) {
  Bytes out(kMaxTelegramBytes);
  out.resize(encode_telegram(adr, payload, out));
  return out;
}

inline Bytes make_reply(std::uint8_t address, const Pkw& pkw, PkwLength len,
                        std::vector<std::uint16_t> pzd) {
  std::array<std::uint8_t, kMaxPayloadBytes> payload{};
  const std::size_t n = encode_payload(pkw, len, pzd, payload);
  EXPECT_TRUE(n > 0 || (len == PkwLength::None && pzd.empty()));
  return make_telegram(make_adr(address, TelegramType::Normal),
                       std::span<const std::uint8_t>(payload.data(), n));
}

/// A reply PKW with a word value (C 4.2.3: PWE1 with 3 words or variable, PWE2 with 4).
inline Pkw reply_pkw(std::uint8_t id, std::uint16_t pnu, PkwLength len, std::uint16_t value,
                     bool toggle = false, std::uint16_t ind = 0) {
  Pkw p;
  p.id = id;
  p.pnu = pnu;
  p.ind = ind;
  p.toggle = toggle;
  set_value(p, len, PkwWidth::Word, value);
  return p;
}

/// The master on a simulated line with a fake clock.
class Bus {
 public:
  explicit Bus(MasterConfig config)
      : master(std::move(config)), baud(master.config().baud), tz(character_time(baud)) {
    master.reset_link(t);  // as the runner does when the port opens
  }

  /// Waits for send_at() (never earlier than now), sends the next telegram.
  Sent send() {
    const MonoTime at = std::max(t, master.send_at());
    const auto span = master.next_telegram(at);
    Sent s{Bytes(span.begin(), span.end()), at, at + transmission_time(baud, span.size())};
    master.on_sent(s.end);
    t = s.end;
    return s;
  }

  /// Feeds bytes as a UART delivers them: the STX begins `delay` after the current time and
  /// character i is stamped when complete, transmission_time(i + 1) after that. Returns the last
  /// stamp.
  MonoTime reply(const Bytes& bytes,
                 std::chrono::nanoseconds delay = std::chrono::microseconds(1000)) {
    const MonoTime begin = t + delay;
    MonoTime at = begin;
    for (std::size_t i = 0; i < bytes.size(); ++i) {
      at = begin + transmission_time(baud, i + 1);
      master.on_char(RxChar{bytes[i], LineError::None}, at);
    }
    t = at;
    return at;
  }

  /// Feeds all bytes with one stamp (a pty or a late read delivers them at once).
  void reply_at_once(const Bytes& bytes, MonoTime at) {
    for (const std::uint8_t b : bytes) master.on_char(RxChar{b, LineError::None}, at);
    t = at;
  }

  /// Lets the reply delay run out.
  void timeout() {
    t = master.deadline();
    master.on_time(t);
  }

  Master master;
  std::uint32_t baud;
  std::chrono::nanoseconds tz;
  MonoTime t = std::chrono::seconds(100);
};

}  // namespace liftd::uss::testing
