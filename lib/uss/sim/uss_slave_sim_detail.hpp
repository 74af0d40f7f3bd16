// What the parts of UssSlaveSim (uss_slave_sim.cpp, uss_slave_drive.cpp,
// uss_slave_parameters.cpp) share: the rules the spec sets the master, each quoted, and the
// parameter table the simulated slave serves. Included only by those files.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "uss/pkw.hpp"

namespace liftd::uss::sim::detail {

using uss::Pkw;
using uss::PkwLength;
using uss::PkwWidth;
namespace req = uss::request;
namespace rep = uss::reply;

// ---- what the spec forbids the master (each rule quoted) ----
inline constexpr std::string_view kRuleStartPause =
    "A 5.1.2: telegram without a start pause after the last reply (\"Erst ein STX mit "
    "vorangegangener Startpause kennzeichnet einen gültigen Telegrammbeginn\")";
inline constexpr std::string_view kRuleReplyPending =
    "A 5: a telegram before the slave's reply (\"muß der Slave nach Empfang des für ihn "
    "bestimmten Auftragstelegramms das Antworttelegramm an den Master senden, bevor der Master "
    "den nächsten Slaveteilnehmer anspricht\")";
inline constexpr std::string_view kRuleUndefinedAdr =
    "A 4.3: undefined combination of ADR bits 5..7 (\"Nicht definierte Kombinationen dürfen "
    "von Mastern nicht gesendet ... werden\")";
inline constexpr std::string_view kRuleLength =
    "C 7: request length does not fit PKW_ANZ/PZD_ANZ (\"Der PZD-Bereich muß für das Auftrags- "
    "und für das Antworttelegramm immer gleich groß sein\")";
inline constexpr std::string_view kRuleVariableMinimum =
    "C 4.2.3 Tab. 4.10 / C 7: variable PKW area shorter than 3 words (\"PKE, IND, PWE 1 "
    "(Minimum 3 Worte)\")";
inline constexpr std::string_view kRuleRepeat =
    "C 4.2.1.1: request changed before its answer arrived (\"Solange auf die Antwortkennung "
    "gewartet wird, muß der Auftraggeber seinen Auftrag wiederholen!\")";
inline constexpr std::string_view kRuleToggle =
    "C 4.2.1.2: toggle bit 11 changed with no spontaneous report to acknowledge (\"bis dieser "
    "durch ändern des Toggle-Bits (Bit 11) den sicheren Empfang der Spontanmeldung quittiert "
    "hat\")";
inline constexpr std::string_view kRuleIndDevice =
    "C 4.2.2 Tab. 4.7: IND bits 10..15 set for a device without a meaning for them (\"Bei "
    "Geräten, die diese Bits nicht verwenden, ist als Defaultwert '0' zu senden\")";
inline constexpr std::string_view kRuleIndUnused =
    "C 4.2.2: IND bits 0..9 set for a request without index (\"In allen anderen Fällen sind die "
    "Bits 0 bis 9 auf logisch '0' gesetzt\")";
inline constexpr std::string_view kRulePwe1 =
    "C 4.2.3: word value with PWE1 != 0 in a 4-word PKW area (\"Ist PKW_ANZ = 4 eingestellt, so "
    "werden Wortgrößen im Low-Word (PWE2) gesendet. Das High-Word (PWE1) ist dabei 0.\")";
inline constexpr std::string_view kRuleBroadcastPkw =
    "C 5.2.3: broadcast without the 4-word broadcast enable array (\"Hierzu wird der PKW-Bereich "
    "mit einer festen Länge von 4 Worten benutzt\")";
inline constexpr std::string_view kRuleSwitchOn =
    "C 5.2.1 Tab. 5.5 bit 6: ON in switch-on inhibit (\"Wiedereinschalten nur durch 'AUS 1' und "
    "anschließendem 'EIN'\")";

// ---- the parameter table (see the header) ----
inline constexpr std::uint8_t kI2 = 3;  // drive-profile data types (C 3.1 "Datentyp: siehe /1/")
inline constexpr std::uint8_t kO2 = 6;
inline constexpr std::uint8_t kO4 = 7;

inline constexpr std::uint16_t kPnuActualSpeed = 2;
inline constexpr std::uint16_t kPnuComparison = 41;
inline constexpr std::uint16_t kPnuFault = 60;

struct ParamSpec {
  std::uint16_t pnu;
  std::string_view name;
  std::uint8_t type;
  std::uint8_t elements;
  bool read_only;
  bool active;
  std::uint32_t min;
  std::uint32_t max;
  std::array<std::uint32_t, 4> initial;
  std::array<std::string_view, 3> place_texts;
  bool baud_texts;  // texts per value 0..10 (C 8 example 7)
};

inline constexpr std::array<ParamSpec, 10> kTable = {{
    {1, "FIRMWARE", kO2, 0, true, false, 0, 0xFFFF, {0x0100}, {}, false},
    {kPnuActualSpeed, "ACTUAL SPEED", kI2, 0, true, false, 0, 0xFFFF, {0}, {}, false},
    {4, "SPEED TABLE", kO4, 4, false, true, 0, 0xFFFFFFFF, {0, 0, 0, 0}, {}, false},
    {7, "BAUD RATE", kO2, 0, false, true, 1, 10, {8}, {}, true},
    {18, "RAMP TIME", kO2, 0, false, false, 0, 0xFFFF, {0x0100}, {}, false},
    {20, "TRAVEL COUNTER", kO4, 0, false, true, 0, 0xFFFFFFFF, {0}, {}, false},
    {kPnuComparison, "COMPARE SPEED", kO2, 0, false, false, 0, 0x7FFF, {0x4000}, {}, false},
    {52, "REF SPEED", kO2, 0, false, false, 0, 0xFFFF, {0x4000}, {}, false},
    {kPnuFault, "FAULT NUMBER", kO2, 0, true, false, 0, 0xFFFF, {0}, {}, false},
    {683,
     "SST/SCB BUSADR",
     kO2,
     3,
     false,
     false,
     0,
     30,
     {0, 0, 0},
     {"SST 1", "SCB", "SST 2"},
     false},
}};

// C 3.1 baud rate codes, the texts of P7's values 0..10 (y = value + 1, C 8 example 7).
inline constexpr std::array<std::string_view, 11> kBaudTexts = {
    "---",       "300 BAUD",   "600 BAUD",   "1200 BAUD",  "2400 BAUD",  "4800 BAUD",
    "9600 BAUD", "19200 BAUD", "38400 BAUD", "93750 BAUD", "187500 BAUD"};

inline constexpr std::size_t kTextWords = 8;  // 16 characters (C 8 example 7)

inline std::array<char, 16> text16(std::string_view s) {
  std::array<char, 16> t{};
  t.fill(' ');
  std::copy_n(s.begin(), std::min<std::size_t>(s.size(), 16), t.begin());
  return t;
}

}  // namespace liftd::uss::sim::detail
