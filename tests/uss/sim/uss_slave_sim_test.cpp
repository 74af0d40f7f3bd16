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
#include "uss_slave_sim_harness.hpp"

namespace {

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

}  // namespace
