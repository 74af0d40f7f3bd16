// The simulated USS slave against the spec: exact reply bytes for every kind of PKW request
// (C 4), mirror / broadcast / special / undefined telegrams (A 3, A 4.3, A 5.3, A 5.4), the
// drive-profile state machine (C 5.2.1), spontaneous reports (C 4.2.1.2), each injected fault,
// the violations it records, and the car model. Fake clock throughout; telegrams are fed one
// character per character time (A 6.1) after a start pause. Telegrams are built here by hand
// (STX LGE ADR words BCC), not with the codec under test elsewhere.
#include "uss/sim/uss_slave_sim.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <initializer_list>
#include <optional>
#include <string>
#include <vector>

#include "uss/timing.hpp"

namespace {

using namespace std::chrono_literals;
using liftd::MonoTime;
using liftd::uss::sim::UssDriveState;
using liftd::uss::sim::UssReply;
using liftd::uss::sim::UssReplyFault;
using liftd::uss::sim::UssSlaveConfig;
using liftd::uss::sim::UssSlaveSim;
using Bytes = std::vector<std::uint8_t>;
using Words = std::vector<std::uint16_t>;

constexpr std::uint32_t kBaud = 38400;

Bytes telegram(std::uint8_t adr, const Words& words) {
  Bytes b = {0x02, static_cast<std::uint8_t>(2 * words.size() + 2), adr};
  for (const auto w : words) {
    b.push_back(static_cast<std::uint8_t>(w >> 8));
    b.push_back(static_cast<std::uint8_t>(w & 0xFF));
  }
  std::uint8_t bcc = 0;
  for (const auto x : b) bcc ^= x;
  b.push_back(bcc);
  return b;
}

std::string hex(const Bytes& b) {
  std::string s;
  char buf[4];
  for (const auto x : b) {
    std::snprintf(buf, sizeof buf, "%02X ", x);
    s += buf;
  }
  return s;
}

struct Harness {
  MonoTime now{std::chrono::seconds(10)};
  UssSlaveSim sim;
  UssReply last{};
  MonoTime request_end{};

  explicit Harness(const UssSlaveConfig& c) : sim(c, kBaud, MonoTime{std::chrono::seconds(10)}) {}

  void send(const Bytes& bytes, std::chrono::nanoseconds pause = 5ms,
            std::optional<std::size_t> parity_at = std::nullopt) {
    now += pause;
    const auto tz = liftd::uss::character_time(kBaud);
    for (std::size_t i = 0; i < bytes.size(); ++i) {
      now += tz;
      liftd::uss::RxChar c{bytes[i], liftd::uss::LineError::None};
      if (parity_at && *parity_at == i) c.error = liftd::uss::LineError::Parity;
      sim.on_char(c, now);
    }
    request_end = now;
  }
  // Waits up to 40 ms in 50 us steps for a reply.
  std::optional<Bytes> wait_reply() {
    for (int i = 0; i < 800; ++i) {
      now += 50us;
      sim.on_time(now);
      if (sim.take_reply(now, last)) {
        now = last.send_at + liftd::uss::transmission_time(kBaud, last.size);
        return Bytes(last.bytes.begin(), last.bytes.begin() + static_cast<long>(last.size));
      }
    }
    return std::nullopt;
  }
  std::optional<Bytes> exchange(const Bytes& bytes) {
    send(bytes);
    return wait_reply();
  }
  // The reply's payload words; checks frame, LGE and BCC.
  Words words(std::uint8_t adr, const Words& request) {
    const auto r = exchange(telegram(adr, request));
    if (!r) {
      ADD_FAILURE() << "no reply";
      return {};
    }
    return payload_words(*r);
  }
  static Words payload_words(const Bytes& r) {
    EXPECT_GE(r.size(), 4U);
    EXPECT_EQ(r[0], 0x02);
    EXPECT_EQ(r[1], r.size() - 2);
    std::uint8_t bcc = 0;
    for (std::size_t i = 0; i + 1 < r.size(); ++i) bcc ^= r[i];
    EXPECT_EQ(bcc, r.back()) << hex(r);
    Words w;
    for (std::size_t i = 3; i + 2 < r.size(); i += 2) {
      w.push_back(static_cast<std::uint16_t>(r[i] << 8 | r[i + 1]));
    }
    return w;
  }
  std::vector<std::string_view> violations() {
    std::array<liftd::uss::sim::UssViolation, 64> v{};
    const std::size_t n = sim.take_violations(v);
    std::vector<std::string_view> out;
    for (std::size_t i = 0; i < n; ++i) out.push_back(v[i].rule);
    return out;
  }
};

UssSlaveConfig config(liftd::uss::PkwLength pkw, std::uint8_t pzd, std::uint8_t address = 5) {
  UssSlaveConfig c;
  c.address = address;
  c.pkw = pkw;
  c.pzd_words = pzd;
  c.telegram_timeout = 0s;
  return c;
}

constexpr std::uint16_t pke(unsigned ak, unsigned pnu, bool toggle = false) {
  return static_cast<std::uint16_t>(ak << 12 | (toggle ? 1U << 11 : 0U) | pnu);
}

// ---------------------------------------------------------------------------------- C 8 examples

TEST(UssSlaveSim, Example2ReadP52ThreePkwTwoPzdExactBytes) {
  // C 8.1 Beispiel 2: PKW_ANZ = 3, PZD_ANZ = 2, "Wert von Parameter-Nr. 52 lesen; Wert = 4000".
  Harness h(config(liftd::uss::PkwLength::Three, 2, 0));
  const auto r = h.exchange(
      Bytes{0x02, 0x0C, 0x00, 0x10, 0x34, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x2A});
  ASSERT_TRUE(r);
  // AK 1 PNU 52, IND 0, PWE 4000; ZSW: switch-on inhibit (bit 6), setpoint within tolerance at
  // standstill (bit 8), control requested (bit 9); HIW 0.
  const Bytes expected = {0x02, 0x0C, 0x00, 0x10, 0x34, 0x00, 0x00,
                          0x40, 0x00, 0x03, 0x40, 0x00, 0x00, 0x29};
  EXPECT_EQ(hex(*r), hex(expected));
  // A 5.2.1.1: the reply's STX after the configured reply delay from the request's BCC.
  EXPECT_EQ(h.last.send_at - h.request_end, 2ms);
}

// ----------------------------------------------------------------------- the PKW request table

struct PkwCase {
  const char* name;
  liftd::uss::PkwLength pkw;
  Words request;   // PKW words (no PZD)
  Words expected;  // reply PKW words
};

using liftd::uss::PkwLength;
const std::vector<PkwCase> kPkwCases = {
    // reads of every kind
    {"read word, 4 words: PWE2",
     PkwLength::Four,
     {pke(1, 18), 0, 0, 0},
     {pke(1, 18), 0, 0, 0x0100}},
    {"read word, 3 words: PWE1", PkwLength::Three, {pke(1, 18), 0, 0}, {pke(1, 18), 0, 0x0100}},
    {"read word, variable", PkwLength::Variable, {pke(1, 18), 0, 0}, {pke(1, 18), 0, 0x0100}},
    {"read dword", PkwLength::Four, {pke(1, 20), 0, 0, 0}, {pke(2, 20), 0, 0, 0}},
    {"read dword with 3 words: 101", PkwLength::Three, {pke(1, 20), 0, 0}, {pke(7, 20), 0, 101}},
    {"read read-only", PkwLength::Four, {pke(1, 1), 0, 0, 0}, {pke(1, 1), 0, 0, 0x0100}},
    {"array place 2", PkwLength::Four, {pke(6, 683), 2, 0, 0}, {pke(4, 683), 2, 0, 0}},
    {"dword array place 1", PkwLength::Four, {pke(6, 4), 1, 0, 0}, {pke(5, 4), 1, 0, 0}},
    {"array count", PkwLength::Four, {pke(9, 683), 0, 0, 0}, {pke(6, 683), 0, 0, 3}},
    {"whole array, variable",
     PkwLength::Variable,
     {pke(6, 683), 255, 0},
     {pke(4, 683), 255, 0, 0, 0}},
    {"whole dword array, variable",
     PkwLength::Variable,
     {pke(6, 4), 255, 0},
     {pke(5, 4), 255, 0, 0, 0, 0, 0, 0, 0, 0}},
    {"whole array, fixed: 101",
     PkwLength::Four,
     {pke(6, 683), 255, 0, 0},
     {pke(7, 683), 255, 0, 101}},
    // writes and EEPROM writes
    {"example 6: word 7000 to P18",
     PkwLength::Four,
     {pke(2, 18), 0, 0, 0x7000},
     {pke(1, 18), 0, 0, 0x7000}},
    {"write word, variable", PkwLength::Variable, {pke(2, 18), 0, 0x1234}, {pke(1, 18), 0, 0x1234}},
    {"write dword",
     PkwLength::Four,
     {pke(3, 20), 0, 0x0001, 0x0002},
     {pke(2, 20), 0, 0x0001, 0x0002}},
    {"example 5: dword 40000000 to P4 place 2",
     PkwLength::Four,
     {pke(8, 4), 2, 0x4000, 0},
     {pke(5, 4), 2, 0x4000, 0}},
    {"array word", PkwLength::Four, {pke(7, 683), 3, 0, 17}, {pke(4, 683), 3, 0, 17}},
    {"EEPROM word", PkwLength::Four, {pke(14, 18), 0, 0, 9}, {pke(1, 18), 0, 0, 9}},
    {"EEPROM dword", PkwLength::Four, {pke(13, 20), 0, 1, 2}, {pke(2, 20), 0, 1, 2}},
    {"EEPROM array word", PkwLength::Four, {pke(12, 683), 1, 0, 30}, {pke(4, 683), 1, 0, 30}},
    {"EEPROM array dword",
     PkwLength::Four,
     {pke(11, 4), 4, 0xABCD, 0x1234},
     {pke(5, 4), 4, 0xABCD, 0x1234}},
    {"whole array write, variable",
     PkwLength::Variable,
     {pke(7, 683), 255, 1, 2, 3},
     {pke(4, 683), 255, 1, 2, 3}},
    // errors (Tabelle 4.3)
    {"unknown PNU: 0", PkwLength::Four, {pke(1, 999), 0, 0, 0}, {pke(7, 999), 0, 0, 0}},
    {"read-only: 1", PkwLength::Four, {pke(2, 1), 0, 0, 5}, {pke(7, 1), 0, 0, 1}},
    {"EEPROM read-only: 1", PkwLength::Four, {pke(14, 60), 0, 0, 5}, {pke(7, 60), 0, 0, 1}},
    {"above limit: 2", PkwLength::Four, {pke(2, 7), 0, 0, 11}, {pke(7, 7), 0, 0, 2}},
    {"below limit: 2", PkwLength::Four, {pke(2, 7), 0, 0, 0}, {pke(7, 7), 0, 0, 2}},
    {"place 0: 3", PkwLength::Four, {pke(6, 683), 0, 0, 0}, {pke(7, 683), 0, 0, 3}},
    {"place 4 of 3: 3", PkwLength::Four, {pke(6, 683), 4, 0, 0}, {pke(7, 683), 4, 0, 3}},
    {"array request on a simple parameter: 4",
     PkwLength::Four,
     {pke(6, 18), 1, 0, 0},
     {pke(7, 18), 1, 0, 4}},
    {"array count of a simple parameter: 4",
     PkwLength::Four,
     {pke(9, 18), 0, 0, 0},
     {pke(7, 18), 0, 0, 4}},
    {"word write to a dword: 5", PkwLength::Four, {pke(2, 20), 0, 0, 1}, {pke(7, 20), 0, 0, 5}},
    {"dword write to a word: 5", PkwLength::Four, {pke(3, 18), 0, 0, 1}, {pke(7, 18), 0, 0, 5}},
    {"description change: 7", PkwLength::Four, {pke(5, 18), 7, 0, 1}, {pke(7, 18), 7, 0, 7}},
    {"reserved request 10: 102", PkwLength::Four, {pke(10, 18), 0, 0, 0}, {pke(7, 18), 0, 0, 102}},
    {"no request -> no reply", PkwLength::Four, {pke(0, 18), 0, 0, 0}, {0, 0, 0, 0}},
    // descriptions (C 6)
    {"description element 1 (identifier)",
     PkwLength::Four,
     {pke(4, 683), 1, 0, 0},
     {pke(3, 683), 1, 0, 0x4406}},
    {"description element 2 (array elements)",
     PkwLength::Three,
     {pke(4, 4), 2, 0},
     {pke(3, 4), 2, 4}},
    {"description element 7 (lower limit)",
     PkwLength::Four,
     {pke(4, 7), 7, 0, 0},
     {pke(3, 7), 7, 0, 1}},
    {"description element 8 of a dword",
     PkwLength::Four,
     {pke(4, 20), 8, 0, 0},
     {pke(3, 20), 8, 0xFFFF, 0xFFFF}},
    {"description element 3 with 3 words: 101",
     PkwLength::Three,
     {pke(4, 18), 3, 0},
     {pke(7, 18), 3, 101}},
    {"description name with 4 words: 101",
     PkwLength::Four,
     {pke(4, 18), 6, 0, 0},
     {pke(7, 18), 6, 0, 101}},
    {"description name, variable",
     PkwLength::Variable,
     {pke(4, 18), 6, 0},
     {pke(3, 18), 6, 0x5241, 0x4D50, 0x2054, 0x494D, 0x4520, 0x2020, 0x2020, 0x2020}},
    {"whole description, variable",
     PkwLength::Variable,
     {pke(4, 18), 255, 0},
     {pke(3, 18), 255,    0x0006, 0,      0x3F80, 0,      0, 0,      0, 0x5241, 0x4D50,
      0x2054,     0x494D, 0x4520, 0x2020, 0x2020, 0x2020, 0, 0xFFFF, 0, 0}},
    {"whole description, fixed: 101",
     PkwLength::Four,
     {pke(4, 18), 255, 0, 0},
     {pke(7, 18), 255, 0, 101}},
    // texts (C 4.2.2, C 8 example 7: y = value + 1)
    {"text of P7 value 2",
     PkwLength::Variable,
     {pke(15, 7), 3, 0},
     {pke(15, 7), 3, 0x3630, 0x3020, 0x4241, 0x5544, 0x2020, 0x2020, 0x2020, 0x2020}},
    {"text of P683 place 2",
     PkwLength::Variable,
     {pke(15, 683), 2, 0},
     {pke(15, 683), 2, 0x5343, 0x4220, 0x2020, 0x2020, 0x2020, 0x2020, 0x2020, 0x2020}},
    {"text write",
     PkwLength::Variable,
     {pke(15, 683), 0x0101, 0x4C49, 0x4654},
     {pke(15, 683), 0x0101, 0x4C49, 0x4654, 0x2020, 0x2020, 0x2020, 0x2020, 0x2020, 0x2020}},
    {"text, fixed length: 101", PkwLength::Four, {pke(15, 7), 3, 0, 0}, {pke(7, 7), 3, 0, 101}},
    {"text element 255: 3", PkwLength::Variable, {pke(15, 7), 255, 0}, {pke(7, 7), 255, 3}},
    {"text element beyond the field: 3",
     PkwLength::Variable,
     {pke(15, 683), 4, 0},
     {pke(7, 683), 4, 3}},
    {"value texts of an array without them: 3",
     PkwLength::Variable,
     {pke(15, 683), 0x0201, 0},
     {pke(7, 683), 0x0201, 3}},
    {"no texts: 3", PkwLength::Variable, {pke(15, 18), 1, 0}, {pke(7, 18), 1, 3}},
};

TEST(UssSlaveSim, PkwRequestTableGivesExactReplies) {
  for (const auto& c : kPkwCases) {
    SCOPED_TRACE(c.name);
    Harness h(config(c.pkw, 0));
    EXPECT_EQ(h.words(5, c.request), c.expected);
  }
}

TEST(UssSlaveSim, EepromWritesAreCountedAndValuesKept) {
  Harness h(config(PkwLength::Four, 0));
  h.words(5, {pke(14, 18), 0, 0, 9});
  h.words(5, {pke(14, 18), 0, 0, 9});  // a repeat is not done again
  h.words(5, {pke(12, 683), 1, 0, 30});
  EXPECT_EQ(h.sim.stats().eeprom_writes, 2U);
  EXPECT_EQ(h.sim.parameter(18), 9U);
  EXPECT_EQ(h.sim.parameter(683, 1), 30U);
  EXPECT_EQ(h.sim.stats().pkw_requests, 2U);
}

TEST(UssSlaveSim, ZeroBasedIndexOption) {
  auto c = config(PkwLength::Four, 0);
  c.zero_based_index = true;
  Harness h(c);
  EXPECT_EQ(h.words(5, {pke(7, 683), 0, 0, 7}), (Words{pke(4, 683), 0, 0, 7}));
  EXPECT_EQ(h.sim.parameter(683, 0), 7U);
  EXPECT_EQ(h.words(5, {pke(6, 683), 3, 0, 0}), (Words{pke(7, 683), 3, 0, 3}));
}

TEST(UssSlaveSim, NoPkwAuthorityRefusesChangesButReads) {
  Harness h(config(PkwLength::Four, 0));
  h.sim.set_pkw_authority(false);
  EXPECT_EQ(h.words(5, {pke(2, 18), 0, 0, 5}), (Words{pke(8, 18), 0, 0, 0}));
  EXPECT_EQ(h.words(5, {pke(13, 20), 0, 0, 5}), (Words{pke(8, 20), 0, 0, 0}));
  EXPECT_EQ(h.words(5, {pke(1, 18), 0, 0, 0}), (Words{pke(1, 18), 0, 0, 0x0100}));
  EXPECT_EQ(h.sim.parameter(18), 0x0100U);
}

TEST(UssSlaveSim, NoPkwAuthorityRefusesTextWrites) {
  Harness h(config(PkwLength::Variable, 0));
  h.sim.set_pkw_authority(false);
  EXPECT_EQ(h.words(5, {pke(15, 683), 0x0101, 0x4142}), (Words{pke(8, 683), 0x0101, 0}));
  EXPECT_EQ(h.words(5, {pke(15, 683), 0x0001, 0}).at(0), pke(15, 683));
}

TEST(UssSlaveSim, RepeatedReadAnswersTheCurrentValue) {
  // C 4.2.1.1: "antwortet der Slave bei der Wiederholung der Antworttelegramme immer mit dem
  // aktuellen Wert".
  Harness h(config(PkwLength::Four, 0));
  EXPECT_EQ(h.words(5, {pke(1, 18), 0, 0, 0}).at(3), 0x0100);
  ASSERT_TRUE(h.sim.change_parameter(18, 0, 0x0200));
  EXPECT_EQ(h.words(5, {pke(1, 18), 0, 0, 0}).at(3), 0x0200);
  EXPECT_EQ(h.sim.stats().pkw_requests, 1U);
}

// --------------------------------------------------------------- telegram types and reception

TEST(UssSlaveSim, AnswersOnlyItsOwnAddress) {
  Harness h(config(PkwLength::Four, 2));
  EXPECT_FALSE(h.exchange(telegram(4, {pke(1, 18), 0, 0, 0, 0, 0})));
  EXPECT_TRUE(h.exchange(telegram(5, {pke(1, 18), 0, 0, 0, 0, 0})));
}

TEST(UssSlaveSim, MirrorTelegramComesBackUnchanged) {
  Harness h(config(PkwLength::Four, 2));
  const Bytes m = telegram(0x40 | 5, {0x1234, 0x5678, 0x9ABC, 0xDEF0, 0x0102, 0x0304});
  const auto r = h.exchange(m);
  ASSERT_TRUE(r);
  EXPECT_EQ(hex(*r), hex(m));
  EXPECT_EQ(h.sim.stats().mirrors, 1U);
  EXPECT_FALSE(h.exchange(telegram(0x40 | 6, {0, 0, 0, 0, 0, 0})));
  EXPECT_EQ(h.sim.drive().stw, 0);  // the content is not evaluated
}

TEST(UssSlaveSim, BroadcastIsExecutedNeverAnswered) {
  Harness h(config(PkwLength::Four, 2));
  // Appendix: word a = flag + PZD1 + PZD2, word b = every STW bit.
  EXPECT_FALSE(h.exchange(telegram(0x20, {0x0007, 0xFFFF, 0, 0, 0x0406, 0x2000})));
  EXPECT_EQ(h.sim.state(), UssDriveState::ReadyToSwitchOn);
  EXPECT_EQ(h.sim.drive().hsw, 0x2000);
  // Only PZD2 enabled: the setpoint changes, STW stays.
  EXPECT_FALSE(h.exchange(telegram(0x20, {0x0005, 0, 0, 0, 0x0407, 0x1000})));
  EXPECT_EQ(h.sim.drive().stw, 0x0406);
  EXPECT_EQ(h.sim.drive().hsw, 0x1000);
  // Without the flag nothing is taken.
  EXPECT_FALSE(h.exchange(telegram(0x20, {0x0006, 0xFFFF, 0, 0, 0x0407, 0x0800})));
  EXPECT_EQ(h.sim.drive().hsw, 0x1000);
  // Bit masks: only STW bit 0 of PZD1.
  EXPECT_FALSE(h.exchange(telegram(0x20, {0x0003, 0x0001, 0, 0, 0x0401, 0})));
  EXPECT_EQ(h.sim.drive().stw, 0x0407);
  EXPECT_EQ(h.sim.state(), UssDriveState::Ready);
  EXPECT_EQ(h.sim.stats().broadcasts, 4U);
  EXPECT_EQ(h.sim.stats().replies, 0U);
}

TEST(UssSlaveSim, SpecialTelegramsEchoOrIgnore) {
  Harness h(config(PkwLength::Four, 2));
  // A fixed-length slave takes only telegrams of its length (A 5.2), specials included.
  const Bytes s = telegram(0x80 | 5, {0xCAFE, 0x0001, 2, 3, 4, 5});
  const auto r = h.exchange(s);
  ASSERT_TRUE(r);
  EXPECT_EQ(hex(*r), hex(s));
  EXPECT_FALSE(h.exchange(telegram(0xA0 | 5, {0xCAFE, 0, 0, 0, 0, 0})));  // special broadcast
  EXPECT_FALSE(h.exchange(telegram(0x80 | 6, {0xCAFE, 0, 0, 0, 0, 0})));
  EXPECT_EQ(h.sim.stats().specials, 2U);
  auto c = config(PkwLength::Four, 2);
  c.special = liftd::uss::sim::UssSpecialMode::Ignore;
  Harness ignore(c);
  EXPECT_FALSE(ignore.exchange(s));
}

TEST(UssSlaveSim, UndefinedAddressTypeNoReactionAndViolation) {
  Harness h(config(PkwLength::Four, 2));
  EXPECT_FALSE(h.exchange(telegram(0x60 | 5, {pke(1, 18), 0, 0, 0, 0x047F, 0})));
  EXPECT_FALSE(h.exchange(telegram(0xC0 | 5, {pke(1, 18), 0, 0, 0, 0x047F, 0})));
  EXPECT_EQ(h.sim.state(), UssDriveState::SwitchOnInhibit);
  const auto v = h.violations();
  ASSERT_EQ(v.size(), 2U);
  EXPECT_EQ(v[0].substr(0, 5), "A 4.3");
}

TEST(UssSlaveSim, RejectedTelegramsAreNotAnswered) {
  Harness h(config(PkwLength::Four, 2));
  Bytes bad_bcc = telegram(5, {pke(1, 18), 0, 0, 0, 0, 0});
  bad_bcc.back() ^= 0x01;
  EXPECT_FALSE(h.exchange(bad_bcc));
  EXPECT_FALSE(h.exchange(telegram(5, {pke(1, 18), 0, 0, 0, 0})));  // LGE 12 instead of 14
  h.send(telegram(5, {pke(1, 18), 0, 0, 0, 0, 0}), 5ms, 4);         // parity error on a byte
  EXPECT_FALSE(h.wait_reply());
  const auto& rx = h.sim.rx_counters();
  EXPECT_EQ(rx.bcc, 1U);
  EXPECT_EQ(rx.lge, 1U);
  EXPECT_EQ(rx.parity, 1U);
  EXPECT_TRUE(h.exchange(telegram(5, {pke(1, 18), 0, 0, 0, 0, 0})));
}

TEST(UssSlaveSim, VariableLengthRequestWithWrongPzdCountIsAViolation) {
  Harness h(config(PkwLength::Variable, 2));
  EXPECT_FALSE(h.exchange(telegram(5, {pke(1, 18), 0})));  // PKE IND only, no PZD
  EXPECT_EQ(h.violations().size(), 1U);
  EXPECT_TRUE(h.exchange(telegram(5, {pke(1, 18), 0, 0, 0, 0})));
}

TEST(UssSlaveSim, TelegramWithoutStartPauseAfterTheReplyIsDropped) {
  Harness h(config(PkwLength::Four, 2));
  ASSERT_TRUE(h.exchange(telegram(5, {pke(1, 18), 0, 0, 0, 0, 0})));
  // The reply ended at h.now; the next STX 1 character time later: no start pause (A 5.1.2).
  h.send(telegram(5, {pke(1, 18), 0, 0, 0, 0, 0}), 0ns);
  EXPECT_FALSE(h.wait_reply());
  const auto v = h.violations();
  ASSERT_EQ(v.size(), 1U);
  EXPECT_EQ(v[0].substr(0, 7), "A 5.1.2");
  // 2 character times of pause: fine.
  h.send(telegram(5, {pke(1, 18), 0, 0, 0, 0, 0}), liftd::uss::start_pause(kBaud));
  EXPECT_TRUE(h.wait_reply());
}

TEST(UssSlaveSim, TelegramBeforeTheReplyIsAViolation) {
  Harness h(config(PkwLength::Four, 2));
  h.send(telegram(5, {pke(1, 18), 0, 0, 0, 0, 0}));
  h.send(telegram(7, {pke(1, 18), 0, 0, 0, 0, 0}), 1ms);  // the reply was due after 2 ms
  EXPECT_FALSE(h.wait_reply());
  const auto v = h.violations();
  ASSERT_EQ(v.size(), 1U);
  EXPECT_EQ(v[0].substr(0, 3), "A 5");
}

// Characters reach the slave no earlier than the master sent them, but on a pseudo-terminal they
// can reach it much later: a request and the master's next telegram, sent 20 ms apart as A 5.2.1.1
// allows, may arrive together. The slave judges a timing rule only where a master keeping the
// spec's times was still bound to wait for its reply.
TEST(UssSlaveSim, TimingRulesBrokenOnlyByALateDeliveryAreCountedNotJudged) {
  Harness h(config(PkwLength::Four, 2));
  const Bytes request = telegram(5, {pke(1, 18), 0, 0, 0, 0, 0});
  ASSERT_TRUE(h.exchange(request));
  const MonoTime last_reply_end = h.now;
  // 40 ms of silence, then the request in one delivery, and the next telegram 1 ms after it
  // while the reply is pending: the master may have sent the request at once and given up on
  // the reply 20 ms later (A 5.2.1.1).
  h.now += 40ms;
  for (const auto x : request) h.sim.on_char({x, liftd::uss::LineError::None}, h.now);
  h.send(request, 1ms);
  EXPECT_TRUE(h.violations().empty());
  EXPECT_EQ(h.sim.stats().unjudged, 1U) << "A 5: telegram before the reply, not judged";
  // The second telegram is answered, late from the master's point of view; a telegram right
  // after that reply has no start pause but may come from a master that gave up on it.
  ASSERT_TRUE(h.wait_reply());
  EXPECT_GT(h.last.send_at, last_reply_end + 20ms);
  h.send(request, 0ns);
  EXPECT_FALSE(h.wait_reply());
  EXPECT_TRUE(h.violations().empty());
  EXPECT_EQ(h.sim.stats().unjudged, 2U) << "A 5.1.2: no start pause, not judged";
  EXPECT_EQ(h.sim.stats().violations, 0U);
}

TEST(UssSlaveSim, AMasterThatDoesNotWaitIsCaughtAfterEveryOnTimeReply) {
  Harness h(config(PkwLength::Four, 2));
  const Bytes request = telegram(5, {pke(1, 18), 0, 0, 0, 0, 0});
  ASSERT_TRUE(h.exchange(request));
  // A 5: the next telegram 1 ms after the request, while the reply (due after 2 ms) is pending.
  h.send(request);
  h.send(request, 1ms);
  auto v = h.violations();
  ASSERT_EQ(v.size(), 1U);
  EXPECT_EQ(v[0].substr(0, 4), "A 5:");
  ASSERT_TRUE(h.wait_reply());
  // A 5.1.2: a request 5 ms after the last reply, its reply, and the next STX straight after it
  // (about 17 ms after that last reply, before a master could give up on this one).
  ASSERT_TRUE(h.exchange(request));
  h.send(request, 0ns);
  v = h.violations();
  ASSERT_EQ(v.size(), 1U);
  EXPECT_EQ(v[0].substr(0, 7), "A 5.1.2");
  EXPECT_EQ(h.sim.stats().unjudged, 0U);
}

// ------------------------------------------------------------------------ drive profile C 5.2.1

struct Step {
  std::uint16_t stw;
  UssDriveState state;
  std::uint16_t zsw_low;  // ZSW bits 0..7
};

TEST(UssSlaveSim, DriveProfileAllowedTransitions) {
  const std::vector<Step> steps = {
      {0x0000, UssDriveState::SwitchOnInhibit, 0x40},   // bit 10 = 0: ignored
      {0x0406, UssDriveState::ReadyToSwitchOn, 0x31},   // OFF1 with OFF2/OFF3 lifted
      {0x0407, UssDriveState::Ready, 0x33},             // ON
      {0x040F, UssDriveState::OperationEnabled, 0x37},  // enable operation
      {0x0407, UssDriveState::Ready, 0x33},             // inhibit operation
      {0x0406, UssDriveState::ReadyToSwitchOn, 0x31},   // OFF1 from ready
      {0x040F, UssDriveState::OperationEnabled, 0x37},  // ON + enable at once
      {0x040E, UssDriveState::ReadyToSwitchOn, 0x31},   // OFF1 at standstill: at once
      {0x040F, UssDriveState::OperationEnabled, 0x37},
      {0x040D, UssDriveState::SwitchOnInhibit, 0x60},  // OFF2: coast
      {0x040E, UssDriveState::ReadyToSwitchOn, 0x31},  // OFF1 first (bit 1 back)
      {0x040F, UssDriveState::OperationEnabled, 0x37},
      {0x040B, UssDriveState::SwitchOnInhibit, 0x50},  // OFF3 at standstill
      {0x0406, UssDriveState::ReadyToSwitchOn, 0x31},
      {0x0403, UssDriveState::SwitchOnInhibit, 0x50},  // OFF3 from ready to switch on
      {0x0406, UssDriveState::ReadyToSwitchOn, 0x31},
      {0x0405, UssDriveState::SwitchOnInhibit, 0x60},  // OFF2 from ready to switch on
      {0x0000, UssDriveState::SwitchOnInhibit, 0x60},  // no control: old data stay
  };
  Harness h(config(PkwLength::None, 2));
  for (std::size_t i = 0; i < steps.size(); ++i) {
    SCOPED_TRACE("step " + std::to_string(i));
    const auto w = h.words(5, {steps[i].stw, 0});
    ASSERT_EQ(w.size(), 2U);
    EXPECT_EQ(h.sim.state(), steps[i].state) << to_string(h.sim.state());
    EXPECT_EQ(w[0] & 0xFF, steps[i].zsw_low);
  }
  EXPECT_TRUE(h.violations().empty());
}

TEST(UssSlaveSim, SwitchOnFromInhibitWithoutOff1IsRefusedAndRecorded) {
  Harness h(config(PkwLength::None, 2));
  h.words(5, {0x047F, 0});
  h.words(5, {0x047F, 0});  // the same word again: recorded once
  EXPECT_EQ(h.sim.state(), UssDriveState::SwitchOnInhibit);
  const auto v = h.violations();
  ASSERT_EQ(v.size(), 1U);
  EXPECT_EQ(v[0].substr(0, 7), "C 5.2.1");
  h.words(5, {0x047E, 0});
  EXPECT_EQ(h.sim.state(), UssDriveState::ReadyToSwitchOn);
  h.words(5, {0x047F, 0});
  EXPECT_EQ(h.sim.state(), UssDriveState::OperationEnabled);
}

TEST(UssSlaveSim, FaultLeftOnlyOnARisingEdgeOfBit7) {
  Harness h(config(PkwLength::None, 2));
  h.words(5, {0x047E, 0});
  h.words(5, {0x047F, 0});
  ASSERT_EQ(h.sim.state(), UssDriveState::OperationEnabled);
  h.sim.set_drive_fault(true);
  auto w = h.words(5, {0x047F, 0});
  EXPECT_EQ(w[0] & 0x0F, 0x08);  // fault, bits 0..2 off
  h.words(5, {0x04FF, 0});       // rising edge while the cause is still there
  EXPECT_EQ(h.sim.state(), UssDriveState::Fault);
  h.sim.set_drive_fault(false);
  h.words(5, {0x04FF, 0});  // bit 7 held: no edge
  EXPECT_EQ(h.sim.state(), UssDriveState::Fault);
  h.words(5, {0x047F, 0});
  w = h.words(5, {0x04FF, 0});  // the edge
  EXPECT_EQ(h.sim.state(), UssDriveState::SwitchOnInhibit);
  EXPECT_EQ(w[0] & 0x4F, 0x40);
  EXPECT_EQ(h.sim.parameter(60), 0U);
}

TEST(UssSlaveSim, TelegramTimeoutTripsAfterTheFirstGoodTelegram) {
  auto c = config(PkwLength::None, 2);
  c.telegram_timeout = 100ms;
  Harness h(c);
  h.now += 1s;  // no monitoring before the first telegram (C 3.1)
  h.sim.on_time(h.now);
  EXPECT_NE(h.sim.state(), UssDriveState::Fault);
  h.words(5, {0x047E, 0});
  h.now += 101ms;
  h.sim.on_time(h.now);
  EXPECT_EQ(h.sim.state(), UssDriveState::Fault);
  EXPECT_EQ(h.sim.parameter(60), 2U);
  EXPECT_EQ(h.sim.rx_counters().error_word & 0x80, 0x80);
  h.words(5, {0x047E, 0});
  h.words(5, {0x04FE, 0});
  EXPECT_EQ(h.sim.state(), UssDriveState::SwitchOnInhibit);
}

// -------------------------------------------------------------------------------- car model

TEST(UssSlaveSim, CarFollowsTheRampOnlyWithOperationEnabled) {
  auto c = config(PkwLength::None, 2);
  c.car.nominal_mps = 1.0;
  c.car.accel_mps2 = 0.5;
  c.car.floors_mm = {0.0, 3000.0};
  Harness h(c);
  h.words(5, {0x0476, 0x4000});  // ready to switch on, setpoint 100 %
  h.words(5, {0x0477, 0x4000});  // ready: no pulses, brake closed
  h.now += 1s;
  h.sim.on_time(h.now);
  EXPECT_EQ(h.sim.position_mm(), 0.0);
  EXPECT_EQ(h.sim.floor_at(), 0);
  h.words(5, {0x047F, 0x4000});          // operation enabled
  const MonoTime start = h.request_end;  // the telegram took effect at its last character
  h.now = start + 1s;
  h.sim.on_time(h.now);
  EXPECT_NEAR(h.sim.velocity_mps(), 0.5, 1e-9);
  EXPECT_NEAR(h.sim.position_mm(), 250.0, 2.0);  // 1/2 a t^2
  h.now = start + 3s;
  h.sim.on_time(h.now);
  EXPECT_NEAR(h.sim.velocity_mps(), 1.0, 1e-9);
  const auto w = h.words(5, {0x047F, 0x4000});
  EXPECT_NEAR(static_cast<std::int16_t>(w[1]), 0x4000, 2);  // HIW
  EXPECT_EQ(w[0] & 0x0500, 0x0500);                         // setpoint and speed reached
  // OFF1: down the ramp, then ready to switch on; the car stands.
  h.words(5, {0x047E, 0x4000});
  EXPECT_EQ(h.sim.state(), UssDriveState::RampStop);
  h.now += 2100ms;
  h.sim.on_time(h.now);
  EXPECT_EQ(h.sim.velocity_mps(), 0.0);
  EXPECT_EQ(h.sim.state(), UssDriveState::ReadyToSwitchOn);
  const double stopped = h.sim.position_mm();
  h.now += 1s;
  h.sim.on_time(h.now);
  EXPECT_EQ(h.sim.position_mm(), stopped);
}

TEST(UssSlaveSim, CoastStopsTheCarAtOnceAndQuickStopRampsFaster) {
  auto c = config(PkwLength::None, 2);
  c.car.accel_mps2 = 0.5;
  c.car.quick_stop_mps2 = 2.0;
  Harness h(c);
  h.words(5, {0x047E, 0x4000});
  h.words(5, {0x047F, 0x4000});
  h.now += 2s;
  h.sim.on_time(h.now);
  h.words(5, {0x047D, 0x4000});  // OFF2
  EXPECT_EQ(h.sim.state(), UssDriveState::SwitchOnInhibit);
  h.now += 1ms;
  h.sim.on_time(h.now);
  EXPECT_EQ(h.sim.velocity_mps(), 0.0);
  h.words(5, {0x047E, 0x4000});
  h.words(5, {0x047F, 0x4000});
  h.now += 2s;
  h.sim.on_time(h.now);
  h.words(5, {0x047B, 0x4000});  // OFF3
  EXPECT_EQ(h.sim.state(), UssDriveState::QuickStop);
  h.now += 520ms;
  h.sim.on_time(h.now);
  EXPECT_EQ(h.sim.velocity_mps(), 0.0);
  EXPECT_EQ(h.sim.state(), UssDriveState::SwitchOnInhibit);
}

TEST(UssSlaveSim, DownwardSetpointAndRampFreeze) {
  auto c = config(PkwLength::None, 2);
  c.car.bottom_mm = -5000.0;
  Harness h(c);
  h.words(5, {0x047E, 0xC000});  // -100 %
  h.words(5, {0x047F, 0xC000});
  h.now += 1s;
  h.sim.on_time(h.now);
  EXPECT_NEAR(h.sim.velocity_mps(), -0.5, 0.01);
  h.words(5, {0x045F, 0xC000});  // bit 5 = 0: ramp frozen
  h.now += 1s;
  h.sim.on_time(h.now);
  EXPECT_NEAR(h.sim.velocity_mps(), -0.5, 0.01);
  EXPECT_LT(h.sim.position_mm(), -500.0);
}

// ------------------------------------------------------------------------ spontaneous reports

TEST(UssSlaveSim, SpontaneousReportRepeatedUntilTheToggleAcknowledges) {
  Harness h(config(PkwLength::Four, 0));
  EXPECT_EQ(h.words(5, {pke(1, 18), 0, 0, 0}), (Words{pke(1, 18), 0, 0, 0x0100}));
  ASSERT_TRUE(h.sim.change_parameter(7, 0, 5));   // active: reported
  ASSERT_TRUE(h.sim.change_parameter(18, 0, 3));  // passive: not reported
  ASSERT_TRUE(h.sim.change_parameter(20, 0, 0x00010002));
  EXPECT_EQ(h.sim.reports_pending(), 2U);
  // The normal reply is interrupted: AK 9, toggle changed to 1, as long as the master keeps 0.
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(h.words(5, {pke(1, 18), 0, 0, 0}), (Words{pke(9, 7, true), 0, 0, 5}));
  }
  // The master acknowledges by changing its bit 11: the next report, toggle back to 0.
  EXPECT_EQ(h.words(5, {pke(1, 18, true), 0, 0, 0}), (Words{pke(10, 20), 0, 1, 2}));
  EXPECT_EQ(h.words(5, {pke(1, 18, true), 0, 0, 0}), (Words{pke(10, 20), 0, 1, 2}));
  // Acknowledged again: the interrupted answer, with the current value and toggle 0.
  EXPECT_EQ(h.words(5, {pke(1, 18), 0, 0, 0}), (Words{pke(1, 18), 0, 0, 3}));
  EXPECT_EQ(h.sim.stats().spontaneous, 2U);
  EXPECT_EQ(h.sim.stats().spontaneous_acknowledged, 2U);
  EXPECT_TRUE(h.violations().empty());
}

TEST(UssSlaveSim, SpontaneousArrayReportAndStrayToggle) {
  Harness h(config(PkwLength::Variable, 0));
  h.words(5, {0, 0, 0});
  EXPECT_FALSE(h.sim.change_parameter(683, 4, 1));  // no place 4
  EXPECT_FALSE(h.sim.change_parameter(7, 0, 11));   // out of range
  EXPECT_FALSE(h.sim.change_parameter(999, 0, 1));
  EXPECT_TRUE(h.sim.change_parameter(683, 1, 1));  // passive
  EXPECT_EQ(h.sim.reports_pending(), 0U);
  ASSERT_TRUE(h.sim.change_parameter(4, 2, 0x12345678));  // active dword array: AK 12, IND 2
  EXPECT_EQ(h.words(5, {0, 0, 0}), (Words{pke(12, 4, true), 2, 0x1234, 0x5678}));
  EXPECT_EQ(h.words(5, {pke(0, 0, true), 0, 0}), (Words{pke(0, 0, true), 0, 0}));
  EXPECT_TRUE(h.violations().empty());
  // A toggle change with nothing to acknowledge.
  h.words(5, {pke(0, 0, false), 0, 0});
  const auto v = h.violations();
  ASSERT_EQ(v.size(), 1U);
  EXPECT_EQ(v[0].substr(0, 9), "C 4.2.1.2");
}

// ------------------------------------------------------------------------------ injected faults

TEST(UssSlaveSim, InjectedReplyFaults) {
  Harness h(config(PkwLength::Four, 2));
  const Bytes request = telegram(5, {pke(1, 18), 0, 0, 0, 0, 0});
  const auto good = h.exchange(request);
  ASSERT_TRUE(good);

  h.sim.inject(UssReplyFault::Silent, 2);
  EXPECT_FALSE(h.exchange(request));
  EXPECT_FALSE(h.exchange(request));
  EXPECT_TRUE(h.exchange(request));

  h.sim.inject(UssReplyFault::BadBcc, 1);
  auto r = h.exchange(request);
  ASSERT_TRUE(r);
  Bytes expected = *good;
  expected.back() ^= 0x01;
  EXPECT_EQ(hex(*r), hex(expected));

  h.sim.inject(UssReplyFault::BadLge, 1);
  r = h.exchange(request);
  ASSERT_TRUE(r);
  EXPECT_EQ((*r)[1], (*good)[1] + 1);
  std::uint8_t bcc = 0;
  for (std::size_t i = 0; i + 1 < r->size(); ++i) bcc ^= (*r)[i];
  EXPECT_EQ(bcc, r->back());

  h.sim.inject(UssReplyFault::Parity, 1);
  r = h.exchange(request);
  ASSERT_TRUE(r);
  EXPECT_EQ(hex(*r), hex(*good));
  EXPECT_EQ(h.last.parity_error_at, 2);

  h.sim.inject(UssReplyFault::Late, 1);
  r = h.exchange(request);
  ASSERT_TRUE(r);
  EXPECT_EQ(h.last.send_at - h.request_end, 25ms);
  EXPECT_EQ(h.sim.stats().faulted_replies, 6U);
  EXPECT_TRUE(h.violations().empty());  // the master repeated its request throughout
}

TEST(UssSlaveSim, StaleReplyAnswersThePreviousRequestOnce) {
  Harness h(config(PkwLength::Four, 0));
  EXPECT_EQ(h.words(5, {pke(1, 18), 0, 0, 0}), (Words{pke(1, 18), 0, 0, 0x0100}));
  h.sim.inject(UssReplyFault::Stale, 1);
  EXPECT_EQ(h.words(5, {pke(1, 52), 0, 0, 0}), (Words{pke(1, 18), 0, 0, 0x0100}));
  EXPECT_EQ(h.words(5, {pke(1, 52), 0, 0, 0}), (Words{pke(1, 52), 0, 0, 0x4000}));
  EXPECT_TRUE(h.violations().empty());
}

TEST(UssSlaveSim, ChangingTheRequestBeforeItsAnswerIsAViolation) {
  Harness h(config(PkwLength::Four, 0));
  h.sim.inject(UssReplyFault::Silent, 1);
  EXPECT_FALSE(h.exchange(telegram(5, {pke(1, 18), 0, 0, 0})));
  EXPECT_TRUE(h.exchange(telegram(5, {pke(1, 52), 0, 0, 0})));
  auto v = h.violations();
  ASSERT_EQ(v.size(), 1U);
  EXPECT_EQ(v[0].substr(0, 9), "C 4.2.1.1");
  // After the give-up count of unanswered repeats a change is the master's own reaction.
  auto c = config(PkwLength::Four, 0);
  c.pkw_give_up_repeats = 2;
  Harness g(c);
  g.sim.inject(UssReplyFault::Silent, 3);
  for (int i = 0; i < 3; ++i) EXPECT_FALSE(g.exchange(telegram(5, {pke(1, 18), 0, 0, 0})));
  EXPECT_TRUE(g.exchange(telegram(5, {pke(1, 52), 0, 0, 0})));
  EXPECT_TRUE(g.violations().empty());
}

TEST(UssSlaveSim, IndexBitsTheMasterMustLeaveZero) {
  Harness h(config(PkwLength::Four, 0));
  h.words(5, {pke(1, 18), 0x0001, 0, 0});   // IND bits 0..9 for a request without index
  h.words(5, {pke(6, 683), 0x0401, 0, 0});  // device bits 10..15
  h.words(5, {pke(2, 18), 0, 1, 5});        // word value with PWE1 != 0
  const auto v = h.violations();
  ASSERT_EQ(v.size(), 3U);
  EXPECT_EQ(v[0].substr(0, 5), "C 4.2");
  EXPECT_EQ(v[1].substr(0, 5), "C 4.2");
  EXPECT_EQ(v[2].substr(0, 7), "C 4.2.3");
}

// ------------------------------------------------------------------------------------- the bus

TEST(UssBusSim, RoutesByAddressAndRejectsDuplicates) {
  std::vector<UssSlaveConfig> slaves = {config(PkwLength::Four, 2, 1),
                                        config(PkwLength::Three, 2, 3)};
  liftd::uss::sim::UssBusSim bus(slaves, kBaud, MonoTime{1s});
  MonoTime now{2s};
  auto send = [&](const Bytes& b) {
    now += 5ms;
    for (const auto x : b) {
      now += liftd::uss::character_time(kBaud);
      bus.on_char({x, liftd::uss::LineError::None}, now);
    }
    UssReply r;
    for (int i = 0; i < 600; ++i) {
      now += 50us;
      bus.on_time(now);
      if (bus.take_reply(now, r)) {
        now = r.send_at + liftd::uss::transmission_time(kBaud, r.size);
        return std::optional<UssReply>(r);
      }
    }
    return std::optional<UssReply>();
  };
  auto r = send(telegram(1, {pke(1, 18), 0, 0, 0, 0, 0}));
  ASSERT_TRUE(r);
  EXPECT_EQ(r->address, 1);
  r = send(telegram(3, {pke(1, 18), 0, 0, 0, 0}));
  ASSERT_TRUE(r);
  EXPECT_EQ(r->address, 3);
  EXPECT_EQ(r->size, 14U);
  EXPECT_FALSE(send(telegram(2, {pke(1, 18), 0, 0, 0, 0})));
  EXPECT_FALSE(send(telegram(0x20, {1, 0xFFFF, 0, 0, 0x0406, 0})));  // broadcast
  EXPECT_EQ(bus.slave(1)->state(), UssDriveState::SwitchOnInhibit);  // flag without PZD1 bit
  EXPECT_EQ(bus.slave(3)->stats().broadcasts, 0U);  // 3-word PKW: other LGE, rejected
  slaves.push_back(config(PkwLength::Four, 2, 1));
  EXPECT_THROW(liftd::uss::sim::UssBusSim(slaves, kBaud, MonoTime{}), std::invalid_argument);
}

}  // namespace
