#include "uss/sim/uss_slave_sim.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "uss/pzd.hpp"
#include "uss/timing.hpp"

namespace liftd::uss::sim {
namespace {

using uss::Pkw;
using uss::PkwLength;
using uss::PkwWidth;
namespace req = uss::request;
namespace rep = uss::reply;

// ---- what the spec forbids the master (each rule quoted) ----
constexpr std::string_view kRuleStartPause =
    "A 5.1.2: telegram without a start pause after the last reply (\"Erst ein STX mit "
    "vorangegangener Startpause kennzeichnet einen gültigen Telegrammbeginn\")";
constexpr std::string_view kRuleReplyPending =
    "A 5: a telegram before the slave's reply (\"muß der Slave nach Empfang des für ihn "
    "bestimmten Auftragstelegramms das Antworttelegramm an den Master senden, bevor der Master "
    "den nächsten Slaveteilnehmer anspricht\")";
constexpr std::string_view kRuleUndefinedAdr =
    "A 4.3: undefined combination of ADR bits 5..7 (\"Nicht definierte Kombinationen dürfen "
    "von Mastern nicht gesendet ... werden\")";
constexpr std::string_view kRuleLength =
    "C 7: request length does not fit PKW_ANZ/PZD_ANZ (\"Der PZD-Bereich muß für das Auftrags- "
    "und für das Antworttelegramm immer gleich groß sein\")";
constexpr std::string_view kRuleVariableMinimum =
    "C 4.2.3 Tab. 4.10 / C 7: variable PKW area shorter than 3 words (\"PKE, IND, PWE 1 "
    "(Minimum 3 Worte)\")";
constexpr std::string_view kRuleRepeat =
    "C 4.2.1.1: request changed before its answer arrived (\"Solange auf die Antwortkennung "
    "gewartet wird, muß der Auftraggeber seinen Auftrag wiederholen!\")";
constexpr std::string_view kRuleToggle =
    "C 4.2.1.2: toggle bit 11 changed with no spontaneous report to acknowledge (\"bis dieser "
    "durch ändern des Toggle-Bits (Bit 11) den sicheren Empfang der Spontanmeldung quittiert "
    "hat\")";
constexpr std::string_view kRuleIndDevice =
    "C 4.2.2 Tab. 4.7: IND bits 10..15 set for a device without a meaning for them (\"Bei "
    "Geräten, die diese Bits nicht verwenden, ist als Defaultwert '0' zu senden\")";
constexpr std::string_view kRuleIndUnused =
    "C 4.2.2: IND bits 0..9 set for a request without index (\"In allen anderen Fällen sind die "
    "Bits 0 bis 9 auf logisch '0' gesetzt\")";
constexpr std::string_view kRulePwe1 =
    "C 4.2.3: word value with PWE1 != 0 in a 4-word PKW area (\"Ist PKW_ANZ = 4 eingestellt, so "
    "werden Wortgrößen im Low-Word (PWE2) gesendet. Das High-Word (PWE1) ist dabei 0.\")";
constexpr std::string_view kRuleBroadcastPkw =
    "C 5.2.3: broadcast without the 4-word broadcast enable array (\"Hierzu wird der PKW-Bereich "
    "mit einer festen Länge von 4 Worten benutzt\")";
constexpr std::string_view kRuleSwitchOn =
    "C 5.2.1 Tab. 5.5 bit 6: ON in switch-on inhibit (\"Wiedereinschalten nur durch 'AUS 1' und "
    "anschließendem 'EIN'\")";

// ---- the parameter table (see the header) ----
constexpr std::uint8_t kI2 = 3;  // drive-profile data types (C 3.1 "Datentyp: siehe /1/")
constexpr std::uint8_t kO2 = 6;
constexpr std::uint8_t kO4 = 7;

constexpr std::uint16_t kPnuActualSpeed = 2;
constexpr std::uint16_t kPnuComparison = 41;
constexpr std::uint16_t kPnuFault = 60;

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

constexpr std::array<ParamSpec, 10> kTable = {{
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
constexpr std::array<std::string_view, 11> kBaudTexts = {
    "---",       "300 BAUD",   "600 BAUD",   "1200 BAUD",  "2400 BAUD",  "4800 BAUD",
    "9600 BAUD", "19200 BAUD", "38400 BAUD", "93750 BAUD", "187500 BAUD"};

constexpr std::size_t kTextWords = 8;  // 16 characters (C 8 example 7)

std::array<char, 16> text16(std::string_view s) {
  std::array<char, 16> t{};
  t.fill(' ');
  std::copy_n(s.begin(), std::min<std::size_t>(s.size(), 16), t.begin());
  return t;
}

// Characters in storage order, the first one in the high byte (C 6 "Übertragung von Texten").
void put_text(std::span<const char> text, Pkw& out) {
  for (std::size_t w = 0; w < kTextWords; ++w) {
    out.pwe[w] = static_cast<std::uint16_t>((static_cast<std::uint8_t>(text[2 * w]) << 8) |
                                            static_cast<std::uint8_t>(text[2 * w + 1]));
  }
  out.pwe_count = kTextWords;
}

double seconds(std::chrono::nanoseconds d) {
  return std::chrono::duration<double>(d).count();
}

}  // namespace

std::string_view to_string(UssDriveState state) noexcept {
  switch (state) {
    case UssDriveState::SwitchOnInhibit:
      return "switch_on_inhibit";
    case UssDriveState::ReadyToSwitchOn:
      return "ready_to_switch_on";
    case UssDriveState::Ready:
      return "ready";
    case UssDriveState::OperationEnabled:
      return "operation_enabled";
    case UssDriveState::RampStop:
      return "ramp_stop";
    case UssDriveState::QuickStop:
      return "quick_stop";
    case UssDriveState::Fault:
      return "fault";
  }
  return "?";
}

std::string_view to_string(UssReplyFault fault) noexcept {
  switch (fault) {
    case UssReplyFault::Silent:
      return "silent";
    case UssReplyFault::BadBcc:
      return "badbcc";
    case UssReplyFault::BadLge:
      return "badlge";
    case UssReplyFault::Parity:
      return "parity";
    case UssReplyFault::Late:
      return "late";
    case UssReplyFault::Stale:
      return "stale";
  }
  return "?";
}

std::optional<UssReplyFault> parse_uss_reply_fault(std::string_view name) noexcept {
  for (std::size_t i = 0; i < kUssReplyFaultCount; ++i) {
    const auto f = static_cast<UssReplyFault>(i);
    if (to_string(f) == name) return f;
  }
  return std::nullopt;
}

// ============================================================================ UssSlaveSim

UssSlaveSim::UssSlaveSim(const UssSlaveConfig& config, std::uint32_t baud, MonoTime now)
    : config_(config),
      baud_(baud),
      receiver_(baud),
      reply_delay_(std::max(config.reply_delay, uss::start_pause(baud))),
      start_pause_(uss::start_pause(baud)),
      last_advance_(now) {
  if (config.address > uss::kMaxSlaveAddress) {
    throw std::invalid_argument("USS slave address " + std::to_string(config.address) +
                                " is above 31 (USS A 4.3)");
  }
  if (config.pzd_words > uss::kMaxPzdWords) {
    throw std::invalid_argument("USS slave " + std::to_string(config.address) + ": " +
                                std::to_string(config.pzd_words) +
                                " PZD words, at most 16 (USS C 2)");
  }
  // A 5.2: fixed length -> the receiver checks LGE; variable (PKW_ANZ = 127) -> any valid LGE.
  if (config.pkw != PkwLength::Variable) {
    const std::size_t words = static_cast<std::size_t>(config.pkw) + config.pzd_words;
    receiver_.set_expected_lge(uss::lge_for_payload(2 * words));
  }
  params_.reserve(kTable.size());
  for (const ParamSpec& s : kTable) {
    Param p;
    p.pnu = s.pnu;
    p.name = s.name;
    p.type = s.type;
    p.elements = s.elements;
    p.read_only = s.read_only;
    p.active = s.active;
    p.min = s.min;
    p.max = s.max;
    p.value_at = values_.size();
    const std::size_t n = std::max<std::size_t>(1, s.elements);
    for (std::size_t i = 0; i < n; ++i) values_.push_back(s.initial[i]);
    if (s.elements > 0) {
      p.place_texts_at = texts_.size();
      for (std::size_t i = 0; i < s.elements; ++i) texts_.push_back(text16(s.place_texts[i]));
      p.place_texts = s.elements;
    }
    if (s.baud_texts) {
      p.value_texts_at = texts_.size();
      for (const auto t : kBaudTexts) texts_.push_back(text16(t));
      p.value_texts = kBaudTexts.size();
    }
    params_.push_back(p);
  }
  position_mm_ = config.car.start_mm;
  refresh_live();
}

// ---- line ----

void UssSlaveSim::on_char(const uss::RxChar& c, MonoTime at) noexcept {
  advance(at);
  const bool before = receiver_.receiving();
  const uss::RxResult r = receiver_.feed(c, at);
  if (receiver_.receiving() && (!before || r.kind == uss::RxResult::Kind::Rejected)) {
    stx_at_ = at;  // a telegram starts with this STX
    // A 5: the master waits for the reply before it addresses anybody. An injected late reply
    // is past the 20 ms the master waits (A 5.2.1.1), so the master may go on.
    for (std::size_t i = 0; i < reply_count_;) {
      if (!reply_late_[i] && replies_[i].send_at > at) {
        violation(at, kRuleReplyPending);
        std::move(replies_.begin() + static_cast<std::ptrdiff_t>(i + 1),
                  replies_.begin() + static_cast<std::ptrdiff_t>(reply_count_),
                  replies_.begin() + static_cast<std::ptrdiff_t>(i));
        std::move(reply_late_.begin() + static_cast<std::ptrdiff_t>(i + 1),
                  reply_late_.begin() + static_cast<std::ptrdiff_t>(reply_count_),
                  reply_late_.begin() + static_cast<std::ptrdiff_t>(i));
        --reply_count_;
      } else {
        ++i;
      }
    }
  }
  if (r.kind == uss::RxResult::Kind::Complete) on_complete(at);
}

void UssSlaveSim::on_time(MonoTime now) noexcept {
  if (const auto d = receiver_.deadline(); d && now >= *d) (void)receiver_.check_time(now);
  advance(now);
}

std::optional<MonoTime> UssSlaveSim::next_reply_at() const noexcept {
  if (reply_count_ == 0) return std::nullopt;
  return replies_[0].send_at;
}

bool UssSlaveSim::take_reply(MonoTime now, UssReply& out) noexcept {
  if (reply_count_ == 0 || replies_[0].send_at > now) return false;
  out = replies_[0];
  std::move(replies_.begin() + 1, replies_.begin() + static_cast<std::ptrdiff_t>(reply_count_),
            replies_.begin());
  std::move(reply_late_.begin() + 1,
            reply_late_.begin() + static_cast<std::ptrdiff_t>(reply_count_), reply_late_.begin());
  --reply_count_;
  ++stats_.replies;
  // Until told otherwise: sent now, back to back at the line's baud rate (A 6.2).
  bus_quiet_from_ = std::max(now, out.send_at) + uss::transmission_time(baud_, out.size);
  return true;
}

void UssSlaveSim::on_complete(MonoTime at) noexcept {
  const uss::Telegram t = receiver_.telegram();
  const uss::AddressByte a = uss::parse_adr(t.adr);
  const bool mine = a.slave == config_.address || a.type == uss::TelegramType::Broadcast ||
                    a.type == uss::TelegramType::SpecialBroadcast;
  // A 5.1.2: the pause counts from the last character on the bus, the replies included (the
  // receiver sees only the master's characters). Stamps mark character ends: STX end minus
  // reply end >= 2 tz leaves at least one character time of silence, the receiver's tolerance.
  if (bus_quiet_from_ && stx_at_ - *bus_quiet_from_ < start_pause_) {
    if (mine) violation(at, kRuleStartPause);
    return;
  }
  switch (a.type) {
    case uss::TelegramType::Normal:
      if (a.slave == config_.address) on_normal(t, at);
      break;
    case uss::TelegramType::Mirror:
      // A 5.3: "Der Slave sendet (spiegelt) dieses Telegramm ohne irgendwelche Veränderungen
      // unmittelbar danach an den Master zurück. Hierbei gelten die Bedingungen von Abschnitt
      // 5.1" (the reply delay).
      if (a.slave == config_.address) {
        good_telegram(at);
        ++stats_.mirrors;
        queue_echo(receiver_.bytes(), at);
      }
      break;
    case uss::TelegramType::Broadcast:
      on_broadcast(t, at);
      break;
    case uss::TelegramType::Special:
      if (a.slave == config_.address && config_.special == UssSpecialMode::Echo) {
        ++stats_.specials;
        queue_echo(receiver_.bytes(), at);
      }
      break;
    case uss::TelegramType::SpecialBroadcast:
      // A 5.4 Tabelle 5.2: taken by every slave with special telegrams, never answered.
      if (config_.special == UssSpecialMode::Echo) ++stats_.specials;
      break;
    case uss::TelegramType::Undefined:
      // A 4.3: "Nicht definierte Kombinationen dürfen ... bei Slaves zu keiner Reaktion führen".
      ++stats_.undefined;
      if (a.slave == config_.address) violation(at, kRuleUndefinedAdr);
      break;
  }
}

void UssSlaveSim::good_telegram(MonoTime at) noexcept {
  have_good_ = true;
  last_good_ = at;
  telegram_failed_ = false;  // the cause is gone; the fault stays until acknowledged
}

void UssSlaveSim::on_normal(uss::Telegram t, MonoTime at) noexcept {
  Pkw request{};
  std::array<std::uint16_t, uss::kMaxPzdWords> pzd{};
  if (!uss::decode_payload(t.payload, config_.pkw, config_.pzd_words, request, pzd)) {
    violation(at, kRuleLength);  // valid frame, payload not as configured: not evaluated
    return;
  }
  good_telegram(at);
  ++stats_.telegrams;
  apply_pzd({pzd.data(), config_.pzd_words}, at);

  Pkw out{};
  bool carries_answer = false;
  if (config_.pkw != PkwLength::None) {
    if (config_.pkw == PkwLength::Variable && request.pwe_count < 1) {
      violation(at, kRuleVariableMinimum);
    }
    if ((request.ind & uss::kIndDeviceMask) != 0) violation(at, kRuleIndDevice);
    if (request.id != req::kNone && !uss::request_uses_ind(request.id) &&
        request.id != req::kReserved10 && (request.ind & 0x03FF) != 0) {
      violation(at, kRuleIndUnused);
    }
    out = pkw_reply(request, at);
    carries_answer = !report_active_;
    if (faults_[static_cast<std::size_t>(UssReplyFault::Stale)] > 0) {
      --faults_[static_cast<std::size_t>(UssReplyFault::Stale)];
      ++stats_.faulted_replies;
      out = previous_answer_;
      out.toggle = toggle_;
      carries_answer = false;
    }
  }
  refresh_live();
  std::array<std::uint16_t, uss::kMaxPzdWords> pzd_out{};
  if (config_.pzd_words >= 1) pzd_out[0] = make_zsw();  // C 5.1 Tabelle 5.1: PZD1 = ZSW
  if (config_.pzd_words >= 2) pzd_out[1] = static_cast<std::uint16_t>(make_hiw());  // HIW
  std::array<std::uint8_t, uss::kMaxPayloadBytes> payload{};
  std::size_t n =
      uss::encode_payload(out, config_.pkw, {pzd_out.data(), config_.pzd_words}, payload);
  if (n == 0) {  // cannot happen with the capacity checks; answer "not possible" rather than hang
    out = error(request, kErrorPkwTooShort);
    out.toggle = toggle_;
    n = uss::encode_payload(out, config_.pkw, {pzd_out.data(), config_.pzd_words}, payload);
  }
  UssReply reply;
  reply.address = config_.address;
  reply.size = uss::encode_telegram(uss::make_adr(config_.address, uss::TelegramType::Normal),
                                    {payload.data(), n}, reply.bytes);
  queue(reply, at, carries_answer);
}

void UssSlaveSim::on_broadcast(uss::Telegram t, MonoTime at) noexcept {
  // A 3: "Auf ein Broadcast-Telegramm darf von den einzelnen Slaves kein Antworttelegramm
  // gesendet werden." Appendix: the PKW area carries the 4-word broadcast enable array.
  ++stats_.broadcasts;
  good_telegram(at);
  Pkw array{};
  std::array<std::uint16_t, uss::kMaxPzdWords> pzd{};
  if (config_.pkw != PkwLength::Four && config_.pkw != PkwLength::Variable) {
    violation(at, kRuleBroadcastPkw);
    return;
  }
  if (!uss::decode_payload(t.payload, config_.pkw, config_.pzd_words, array, pzd) ||
      (config_.pkw == PkwLength::Variable && array.pwe_count != 2)) {
    violation(at, kRuleBroadcastPkw);
    return;
  }
  if (config_.pkw == PkwLength::Variable) {  // decode_payload filled PKE, IND, PWE1, PWE2
    array.pwe_count = 2;
  }
  const uss::BroadcastEnable be = uss::decode_broadcast_enable(array);
  if (local_) return;
  std::array<std::uint16_t, uss::kMaxPzdWords> merged = pzd_in_;
  uss::apply_broadcast(be, {pzd.data(), config_.pzd_words}, {merged.data(), config_.pzd_words});
  if (merged == pzd_in_) return;
  // The merged process data are taken like a telegram's, STW bit 10 included (C 5.2.1).
  apply_pzd({merged.data(), config_.pzd_words}, at);
}

void UssSlaveSim::queue_echo(std::span<const std::uint8_t> bytes, MonoTime at) noexcept {
  UssReply reply;
  reply.address = config_.address;
  reply.size = std::min(bytes.size(), reply.bytes.size());
  std::copy_n(bytes.begin(), reply.size, reply.bytes.begin());
  queue(reply, at, false);
}

void UssSlaveSim::queue(UssReply& reply, MonoTime at, bool carries_answer) noexcept {
  auto take = [&](UssReplyFault f) {
    auto& n = faults_[static_cast<std::size_t>(f)];
    if (n == 0) return false;
    --n;
    return true;
  };
  if (take(UssReplyFault::Silent)) {
    ++stats_.faulted_replies;
    return;
  }
  bool damaged = false;
  bool late = false;
  std::chrono::nanoseconds delay = reply_delay_;
  if (take(UssReplyFault::Late)) {
    delay = config_.late_reply_delay;
    late = true;
  }
  if (take(UssReplyFault::BadBcc)) {
    reply.bytes[reply.size - 1] ^= 0x01;
    damaged = true;
  }
  if (take(UssReplyFault::BadLge)) {
    reply.bytes[1] = static_cast<std::uint8_t>(reply.bytes[1] + 1);
    reply.bytes[reply.size - 1] = uss::block_check({reply.bytes.data(), reply.size - 1});
    damaged = true;
  }
  if (take(UssReplyFault::Parity)) {
    reply.parity_error_at = 2;  // the address byte
    damaged = true;
  }
  if (damaged || late) ++stats_.faulted_replies;
  if (!damaged && !late && carries_answer) answer_delivered_ = true;
  reply.send_at = at + delay;
  if (reply_count_ == replies_.size()) return;  // the master floods us: drop the newest
  std::size_t i = reply_count_;
  while (i > 0 && replies_[i - 1].send_at > reply.send_at) {
    replies_[i] = replies_[i - 1];
    reply_late_[i] = reply_late_[i - 1];
    --i;
  }
  replies_[i] = reply;
  reply_late_[i] = late;
  ++reply_count_;
}

// ---- process data and the drive profile (C 5.2.1) ----

void UssSlaveSim::apply_pzd(std::span<const std::uint16_t> pzd, MonoTime at) noexcept {
  if (local_ || pzd.empty()) return;
  // C 5.2.1 Tabelle 5.4 bit 10: "0 Keine Führung: Prozeßdaten ungültig, d. h., die 'alten'
  // Prozeßdaten bleiben erhalten".
  if ((pzd[0] & uss::stw::kControlByPlc) == 0) return;
  std::copy(pzd.begin(), pzd.end(), pzd_in_.begin());
  apply_stw(pzd[0], at);
}

void UssSlaveSim::enter(UssDriveState s, MonoTime at) noexcept {
  if (s == UssDriveState::Ready && state_ != UssDriveState::Ready) ready_since_ = at;
  state_ = s;
}

void UssSlaveSim::apply_stw(std::uint16_t stw, MonoTime at) noexcept {
  namespace b = uss::stw;
  const std::uint16_t previous = stw_;
  stw_ = stw;
  const bool on = (stw & b::kOn) != 0;
  const bool no_off2 = (stw & b::kNoOff2) != 0;
  const bool no_off3 = (stw & b::kNoOff3) != 0;
  const bool enable = (stw & b::kEnableOperation) != 0;
  // Tabelle 5.3 bit 7: "Sammelmeldung wird bei positiver Flanke quittiert; Umrichter befindet
  // sich bis Fehler erfolgreich behoben wurde, in 'Störung' geht anschließend in
  // 'Einschaltsperre'".
  if (state_ == UssDriveState::Fault) {
    const bool rising = (stw & b::kFaultAcknowledge) != 0 && (previous & b::kFaultAcknowledge) == 0;
    if (rising && !fault_injected_ && !telegram_failed_) {
      fault_number_ = 0;
      enter(UssDriveState::SwitchOnInhibit, at);
    }
    return;
  }
  // Tabelle 5.2 bit 1: OFF2 "Spannungsfreischaltung ... und in Einschaltsperre; Motor trudelt
  // aus" - from every state, at once.
  if (!no_off2) {
    enter(UssDriveState::SwitchOnInhibit, at);
    return;
  }
  // Bit 2: OFF3 "Schnellhalt ... bei n/f = 0 ... in Einschaltsperre".
  if (!no_off3) {
    if (state_ == UssDriveState::OperationEnabled || state_ == UssDriveState::RampStop) {
      enter(UssDriveState::QuickStop, at);
      if (speed_mps_ == 0.0) enter(UssDriveState::SwitchOnInhibit, at);
    } else if (state_ != UssDriveState::QuickStop) {
      enter(UssDriveState::SwitchOnInhibit, at);
    }
    return;
  }
  switch (state_) {
    case UssDriveState::SwitchOnInhibit:
      // Tabelle 5.5 bit 6: "Wiedereinschalten nur durch 'AUS 1' und anschließendem 'EIN'".
      if (!on) {
        enter(UssDriveState::ReadyToSwitchOn, at);
      } else if (stw != previous) {
        violation(at, kRuleSwitchOn);
      }
      break;
    case UssDriveState::ReadyToSwitchOn:
      if (on) {
        enter(UssDriveState::Ready, at);
        if (enable) enter(UssDriveState::OperationEnabled, at);
      }
      break;
    case UssDriveState::Ready:
      if (!on) {
        enter(UssDriveState::ReadyToSwitchOn, at);
      } else if (enable) {
        enter(UssDriveState::OperationEnabled, at);
      }
      break;
    case UssDriveState::OperationEnabled:
      // Bit 0 = 0: OFF1 "Herunterfahren an der Hochlauframpe"; bit 3 = 0: "Antrieb trudelt
      // aus ... und geht in Zustand 'Betriebsbereit'".
      if (!on) {
        enter(UssDriveState::RampStop, at);
      } else if (!enable) {
        enter(UssDriveState::Ready, at);
      }
      break;
    case UssDriveState::RampStop:
      if (!enable) {
        enter(on ? UssDriveState::Ready : UssDriveState::ReadyToSwitchOn, at);
      } else if (on) {
        enter(UssDriveState::OperationEnabled, at);  // ON again during the ramp: carry on
      }
      break;
    case UssDriveState::QuickStop:  // runs to standstill whatever comes
    case UssDriveState::Fault:
      break;
  }
  // A stop at standstill is over at once ("bei n/f = 0").
  if (speed_mps_ == 0.0 && state_ == UssDriveState::RampStop) {
    enter(UssDriveState::ReadyToSwitchOn, at);
  }
  if (speed_mps_ == 0.0 && state_ == UssDriveState::QuickStop) {
    enter(UssDriveState::SwitchOnInhibit, at);
  }
}

void UssSlaveSim::set_drive_fault(bool on) noexcept {
  fault_injected_ = on;
  if (on) {
    fault_number_ = 1;
    enter(UssDriveState::Fault, last_advance_);
  }
}

void UssSlaveSim::advance(MonoTime now) noexcept {
  if (now <= last_advance_) return;
  const double dt = seconds(now - last_advance_);
  last_advance_ = now;
  // C 3.1 Telegrammausfallzeit: "Der Slave beginnt ... erst dann mit der Zeitüberwachung,
  // nachdem das erste fehlerfreie Auftragstelegramm empfangen wurde."
  if (config_.telegram_timeout.count() > 0 && have_good_ && !telegram_failed_ &&
      now - last_good_ > config_.telegram_timeout) {
    telegram_failed_ = true;
    fault_number_ = 2;
    ++stats_.telegram_timeouts;
    receiver_.count_reply_timeout();  // A 5.2.3 error word bit 7 (slave: monitoring time)
    enter(UssDriveState::Fault, now);
  }
  // C 5.2.1 Tabelle 5.2 bit 0: "erfolgt innerhalb einer parametrierbaren Wartezeit (t_wart)
  // kein Weiterschalten, wird in den Zustand 'Einschaltsperre' geschaltet".
  if (state_ == UssDriveState::Ready && config_.ready_timeout.count() > 0 &&
      now - ready_since_ >= config_.ready_timeout) {
    enter(UssDriveState::SwitchOnInhibit, now);
  }

  const UssCarConfig& car = config_.car;
  double target = 0.0;
  double rate = car.brake_mps2;  // no pulses: the brake holds the car
  bool hold = false;
  switch (state_) {
    case UssDriveState::OperationEnabled:
      if ((stw_ & uss::stw::kRampGeneratorEnable) == 0) {
        rate = car.quick_stop_mps2;  // bit 4 = 0: "Ausgang HLG wird auf 0 gesetzt"
      } else if ((stw_ & uss::stw::kRampStart) == 0) {
        hold = true;  // bit 5 = 0: "Einfrieren des aktuellen vom HLG vorgegebenen Sollwertes"
      } else {
        // bit 6 = 0: "Angewählter Wert am Eingang des HLG wird zu 0 gesetzt"
        if ((stw_ & uss::stw::kSetpointEnable) != 0) {
          target = static_cast<std::int16_t>(pzd_in_[1]) / 16384.0 * car.nominal_mps;
        }
        rate = car.accel_mps2;
      }
      if (config_.pzd_words < 2) target = 0.0;
      break;
    case UssDriveState::RampStop:
      rate = car.accel_mps2;
      break;
    case UssDriveState::QuickStop:
      rate = car.quick_stop_mps2;
      break;
    default:
      break;
  }
  // Constant acceleration up to the target, then constant speed: exact for any step size.
  const double v0 = speed_mps_;
  double distance_m = v0 * dt;
  if (!hold) {
    if (rate <= 0.0) {
      speed_mps_ = target;
      distance_m = 0.0;  // the brake (or the drive) stops the car at once
      if (target != 0.0) distance_m = target * dt;
    } else {
      const double reach = std::abs(target - v0) / rate;  // time to the target
      if (reach >= dt) {
        speed_mps_ = v0 + (target > v0 ? rate : -rate) * dt;
        distance_m = (v0 + speed_mps_) / 2.0 * dt;
      } else {
        speed_mps_ = target;
        distance_m = (v0 + target) / 2.0 * reach + target * (dt - reach);
      }
    }
  }
  position_mm_ += distance_m * 1000.0;
  if (position_mm_ <= car.bottom_mm) {
    position_mm_ = car.bottom_mm;
    speed_mps_ = std::max(speed_mps_, 0.0);
  }
  if (position_mm_ >= car.top_mm) {
    position_mm_ = car.top_mm;
    speed_mps_ = std::min(speed_mps_, 0.0);
  }
  if (speed_mps_ == 0.0) {
    if (state_ == UssDriveState::RampStop) enter(UssDriveState::ReadyToSwitchOn, now);
    if (state_ == UssDriveState::QuickStop) enter(UssDriveState::SwitchOnInhibit, now);
  }
  refresh_live();
}

std::uint16_t UssSlaveSim::make_zsw() const noexcept {
  namespace z = uss::zsw;
  std::uint16_t w = 0;
  switch (state_) {
    case UssDriveState::OperationEnabled:
    case UssDriveState::RampStop:
    case UssDriveState::QuickStop:
      w |= z::kOperationEnabled;  // pulses on while the drive brakes the car itself
      [[fallthrough]];
    case UssDriveState::Ready:
      w |= z::kReady;
      [[fallthrough]];
    case UssDriveState::ReadyToSwitchOn:
      w |= z::kReadyToSwitchOn;
      break;
    case UssDriveState::SwitchOnInhibit:
      w |= z::kSwitchOnInhibit;
      break;
    case UssDriveState::Fault:
      w |= z::kFault;
      break;
  }
  if ((stw_ & uss::stw::kNoOff2) != 0) w |= z::kNoOff2;  // Tabelle 5.5 bit 4: "AUS 2 steht an"
  if ((stw_ & uss::stw::kNoOff3) != 0) w |= z::kNoOff3;
  if (warning_) w |= z::kWarning;
  const UssCarConfig& car = config_.car;
  double setpoint = 0.0;
  if (state_ == UssDriveState::OperationEnabled && config_.pzd_words >= 2 &&
      (stw_ & uss::stw::kSetpointEnable) != 0 && (stw_ & uss::stw::kRampGeneratorEnable) != 0) {
    setpoint = static_cast<std::int16_t>(pzd_in_[1]) / 16384.0 * car.nominal_mps;
  }
  // Tabelle 5.6 bit 8: "Istwert innerhalb eines Toleranzbandes".
  if (std::abs(speed_mps_ - setpoint) <= car.tolerance_percent / 100.0 * car.nominal_mps) {
    w |= z::kSetpointReached;
  }
  if (!local_) w |= z::kPlcControlRequested;  // bit 9: "Führung gefordert"
  // Bit 10: "Istwert >= Vergleichswert (Sollwert), der über Parameternummer einstellbar ist".
  const auto cmp = parameter(kPnuComparison);
  if (cmp && std::abs(speed_mps_) >= *cmp / 16384.0 * car.nominal_mps) w |= z::kFrequencyReached;
  return w;
}

std::int16_t UssSlaveSim::make_hiw() const noexcept {
  const double raw = std::round(speed_mps_ / config_.car.nominal_mps * 16384.0);
  return static_cast<std::int16_t>(std::clamp(raw, -32768.0, 32767.0));
}

void UssSlaveSim::refresh_live() noexcept {
  if (const Param* p = find(kPnuActualSpeed)) {
    values_[p->value_at] = static_cast<std::uint16_t>(make_hiw());
  }
  if (const Param* p = find(kPnuFault)) values_[p->value_at] = fault_number_;
}

void UssSlaveSim::move_car(double mm) noexcept {
  if (speed_mps_ == 0.0) position_mm_ += mm;
}

int UssSlaveSim::floor_at(double tolerance_mm) const noexcept {
  const auto& floors = config_.car.floors_mm;
  for (std::size_t i = 0; i < floors.size(); ++i) {
    if (std::abs(position_mm_ - floors[i]) <= tolerance_mm) return static_cast<int>(i);
  }
  return -1;
}

UssDriveView UssSlaveSim::drive() const noexcept {
  UssDriveView v;
  v.state = state_;
  v.stw = stw_;
  v.hsw = static_cast<std::int16_t>(pzd_in_[1]);
  v.zsw = make_zsw();
  v.hiw = make_hiw();
  v.position_mm = position_mm_;
  v.velocity_mps = speed_mps_;
  v.brake_open = state_ == UssDriveState::OperationEnabled || state_ == UssDriveState::RampStop ||
                 state_ == UssDriveState::QuickStop;
  v.fault_number = fault_number_;
  v.fault_cause = fault_injected_ || telegram_failed_;
  return v;
}

// ---- injection ----

void UssSlaveSim::inject(UssReplyFault fault, std::uint32_t count) noexcept {
  faults_[static_cast<std::size_t>(fault)] = count;
}

void UssSlaveSim::clear_faults() noexcept {
  faults_.fill(0);
}

// ---- parameters (C 4) ----

const UssSlaveSim::Param* UssSlaveSim::find(std::uint16_t pnu) const noexcept {
  for (const Param& p : params_) {
    if (p.pnu == pnu) return &p;
  }
  return nullptr;
}

std::optional<std::size_t> UssSlaveSim::slot_of(const Param& p, std::uint8_t place) const noexcept {
  if (p.elements == 0) return p.value_at;
  // C 4.2.1.1: "Z. B. ist IND = 4, so wird der PWE übertragen, der an der 4. Stelle im Array
  // steht" - places count from 1 unless the device counts from 0.
  if (!config_.zero_based_index && place == 0) return std::nullopt;
  const std::size_t element = config_.zero_based_index ? place : place - 1U;
  if (element >= p.elements) return std::nullopt;
  return p.value_at + element;
}

std::uint8_t UssSlaveSim::wire_place(std::size_t element) const noexcept {
  return static_cast<std::uint8_t>(config_.zero_based_index ? element : element + 1);
}

std::optional<std::uint32_t> UssSlaveSim::parameter(std::uint16_t pnu,
                                                    std::uint8_t place) const noexcept {
  const Param* p = find(pnu);
  if (p == nullptr) return std::nullopt;
  const auto slot = slot_of(*p, place);
  if (!slot) return std::nullopt;
  return values_[*slot];
}

std::size_t UssSlaveSim::pkw_capacity() const noexcept {
  switch (config_.pkw) {
    case PkwLength::None:
      return 0;
    case PkwLength::Three:
      return 1;
    case PkwLength::Four:
      return 2;
    case PkwLength::Variable:
      return uss::kMaxPweWords - config_.pzd_words;  // C 4.1.2
  }
  return 0;
}

bool UssSlaveSim::change_parameter(std::uint16_t pnu, std::uint8_t place,
                                   std::uint32_t value) noexcept {
  const Param* p = find(pnu);
  if (p == nullptr) return false;
  const auto slot = slot_of(*p, place);
  if (!slot || value < p->min || value > p->max) return false;
  values_[*slot] = value;
  // C 4.2.1.2: "Ein Slave sendet eine Spontanmeldung an den Master bei Änderung eines
  // Parameterwertes (PWE), wenn diese Änderung nicht über die Schnittstelle erfolgt ist, über
  // die der Master mit dem Slave kommuniziert ... Nur Änderung des PWE bei Aktivparametern
  // führt zu einer Spontanmeldung!"
  if (p->active) push_report(pnu, p->elements > 0 ? place : 0);
  return true;
}

void UssSlaveSim::push_report(std::uint16_t pnu, std::uint8_t place) noexcept {
  const Param* p = find(pnu);
  if (config_.pkw == PkwLength::None || p == nullptr) return;
  if (p->dword() && pkw_capacity() < 2) return;  // a double word does not fit 3 PKW words
  // A report already waiting (not yet on the wire) carries the current value anyway.
  for (std::size_t i = report_active_ ? 1 : 0; i < report_count_; ++i) {
    if (reports_[i].pnu == pnu && reports_[i].place == place) return;
  }
  if (report_count_ == reports_.size()) return;
  reports_[report_count_++] = {pnu, place};
}

std::size_t UssSlaveSim::reports_pending() const noexcept {
  return report_count_;
}

Pkw UssSlaveSim::report_pkw() const noexcept {
  const Report& r = reports_[0];
  const Param* p = find(r.pnu);
  Pkw out{};
  out.pnu = r.pnu;
  if (p == nullptr) return out;
  const bool array = p->elements > 0;
  // Tabelle 4.2: 9 word, 10 double word, 11 array word, 12 array double word.
  out.id = array ? (p->dword() ? rep::kSpontaneousArrayDword : rep::kSpontaneousArrayWord)
                 : (p->dword() ? rep::kSpontaneousDword : rep::kSpontaneousWord);
  out.ind = array ? r.place : 0;
  const auto slot = slot_of(*p, r.place);
  // "mit der entsprechenden Parameternummer (PNU) und dem geänderten Parameterwert (PWE)"
  uss::set_value(out, config_.pkw, p->dword() ? PkwWidth::Dword : PkwWidth::Word,
                 slot ? values_[*slot] : 0);
  return out;
}

Pkw UssSlaveSim::error(const Pkw& request, std::uint16_t number) const noexcept {
  Pkw out{};
  out.id = rep::kError;  // "Auftrag nicht ausführbar" with the error number in PWE
  out.pnu = request.pnu;
  out.ind = request.ind;
  uss::set_value(out, config_.pkw, PkwWidth::Word, number);
  return out;
}

bool UssSlaveSim::value_reply(const Param& p, std::size_t slot, std::uint8_t id_word,
                              std::uint8_t id_dword, std::uint16_t ind, Pkw& out) const noexcept {
  if (p.dword() && pkw_capacity() < 2) return false;  // C 7: a double word needs 4 words
  out.id = p.dword() ? id_dword : id_word;
  out.pnu = p.pnu;
  out.ind = ind;
  uss::set_value(out, config_.pkw, p.dword() ? PkwWidth::Dword : PkwWidth::Word, values_[slot]);
  return true;
}

Pkw UssSlaveSim::pkw_reply(const Pkw& request, MonoTime at) noexcept {
  Pkw identity = request;
  identity.toggle = false;
  // C 4.2.1.2: the report is acknowledged when the master changes bit 11 to the report's.
  if (!toggle_seen_) {
    toggle_seen_ = true;
    master_toggle_ = request.toggle;
    toggle_ = request.toggle;
  } else if (request.toggle != master_toggle_) {
    master_toggle_ = request.toggle;
    if (report_active_ && request.toggle == toggle_) {
      ++stats_.spontaneous_acknowledged;
      std::move(reports_.begin() + 1, reports_.begin() + static_cast<std::ptrdiff_t>(report_count_),
                reports_.begin());
      --report_count_;
      report_active_ = false;
    } else {
      violation(at, kRuleToggle);
    }
  }
  // C 4.2.1.1: "Jede Änderung des Auftrags bedeutet einen Neuauftrag".
  const bool repeat = request_.valid && request_.pkw == identity;
  if (!repeat) {
    if (request_.valid && !answer_delivered_ &&
        undelivered_repeats_ < config_.pkw_give_up_repeats) {
      violation(at, kRuleRepeat);
    }
    previous_answer_ = answer_;
    request_.pkw = identity;
    request_.valid = true;
    ++stats_.pkw_requests;
    answer_ = execute(identity, false, at);
    if (answer_.id == rep::kError) ++stats_.pkw_errors;
    answer_delivered_ = false;
    undelivered_repeats_ = 0;
  } else {
    // "Bei Antworten die Parameterwerte enthalten, antwortet der Slave bei der Wiederholung der
    // Antworttelegramme immer mit dem aktuellen Wert."
    if (answer_.id != rep::kError && answer_.id != rep::kNoAuthority) {
      answer_ = execute(identity, true, at);
    }
    if (!answer_delivered_) ++undelivered_repeats_;
  }
  // "Der normale Auftrags- / Antwortablauf ... wird vom Slave sofort unterbrochen ...
  // Gleichzeitig wird vom Slave das Spontanmelde-Toggle-Bit (Nr. 11) geändert".
  if (!report_active_ && report_count_ > 0) {
    report_active_ = true;
    toggle_ = !toggle_;
    ++stats_.spontaneous;
  }
  Pkw out = report_active_ ? report_pkw() : answer_;
  out.toggle = toggle_;
  return out;
}

Pkw UssSlaveSim::execute(const Pkw& request, bool repeat, MonoTime) noexcept {
  Pkw out{};
  const std::uint8_t id = request.id;
  if (id == req::kNone) return out;  // "Kein Auftrag" -> "Keine Antwort", all fields 0
  if (id == req::kReserved10) return error(request, kErrorReservedRequest);
  const Param* pp = find(request.pnu);
  if (pp == nullptr) return error(request, 0);  // 0: unzulässige PNU
  const Param& p = *pp;
  // "Besitzt der Auftraggeber nicht die PKW-Bedienhoheit, so werden alle Änderung- und
  // EEPROM-Aufträge vom Gerät nicht bearbeitet und mit der Kennung 'Keine PKW-Bedienhoheit'
  // beantwortet. Alle Lese-Aufträge werden bearbeitet."
  if (!authority_ && uss::is_change_request(request)) {
    out.id = rep::kNoAuthority;
    out.pnu = request.pnu;
    out.ind = request.ind;
    uss::set_value(out, config_.pkw, PkwWidth::Word, 0);
    return out;
  }
  const bool variable = config_.pkw == PkwLength::Variable;
  const std::uint8_t element = uss::ind_element(request.ind);
  const bool eeprom = id == req::kEepromWord || id == req::kEepromDword ||
                      id == req::kEepromArrayWord || id == req::kEepromArrayDword;
  // A change re-sent unchanged is answered with the current value, not done again.
  const bool write = !repeat && (id == req::kWriteWord || id == req::kWriteDword ||
                                 id == req::kEepromWord || id == req::kEepromDword ||
                                 id == req::kWriteArrayWord || id == req::kWriteArrayDword ||
                                 id == req::kEepromArrayWord || id == req::kEepromArrayDword);
  const bool word_write = id == req::kWriteWord || id == req::kEepromWord ||
                          id == req::kWriteArrayWord || id == req::kEepromArrayWord;
  const bool dword_write = id == req::kWriteDword || id == req::kEepromDword ||
                           id == req::kWriteArrayDword || id == req::kEepromArrayDword;

  switch (id) {
    case req::kReadValue:
    case req::kWriteWord:
    case req::kWriteDword:
    case req::kEepromWord:
    case req::kEepromDword: {
      if (p.elements > 0) return error(request, 3);           // an array needs its place in IND
      if (word_write && p.dword()) return error(request, 5);  // falscher Datentyp
      if (dword_write && !p.dword()) return error(request, 5);
      if (dword_write && pkw_capacity() < 2) return error(request, kErrorPkwTooShort);
      if (write) {
        if (p.read_only) return error(request, 1);  // Parameter nicht änderbar
        if (word_write && config_.pkw == PkwLength::Four && request.pwe[0] != 0) {
          violation(last_advance_, kRulePwe1);
        }
        const std::uint32_t v =
            uss::value(request, config_.pkw, dword_write ? PkwWidth::Dword : PkwWidth::Word);
        if (v < p.min || v > p.max) return error(request, 2);  // Wertgrenze
        values_[p.value_at] = v;
        if (eeprom) ++stats_.eeprom_writes;
      }
      if (!value_reply(p, p.value_at, rep::kValueWord, rep::kValueDword, 0, out)) {
        return error(request, kErrorPkwTooShort);
      }
      return out;
    }
    case req::kReadArray:
    case req::kWriteArrayWord:
    case req::kWriteArrayDword:
    case req::kEepromArrayWord:
    case req::kEepromArrayDword: {
      if (p.elements == 0) return error(request, 4);  // kein Array
      if (word_write && p.dword()) return error(request, 5);
      if (dword_write && !p.dword()) return error(request, 5);
      const std::size_t width = p.dword() ? 2 : 1;
      if (element == uss::kIndWhole) {
        // C 4.2.2: "Die fehlerfreie Bearbeitung eines solchen Auftrages setzt die
        // Parameterierung auf variable Telegrammlänge (PKW_ANZ = 127) voraus."
        if (!variable || p.elements * width > pkw_capacity()) {
          return error(request, kErrorPkwTooShort);
        }
        if (write) {
          if (p.read_only) return error(request, 1);
          if (request.pwe_count != p.elements * width) return error(request, 3);
          for (std::size_t i = 0; i < p.elements; ++i) {
            const std::uint32_t v =
                width == 2 ? uss::make_dword(request.pwe[2 * i], request.pwe[2 * i + 1])
                           : request.pwe[i];
            if (v < p.min || v > p.max) return error(request, 2);
          }
          for (std::size_t i = 0; i < p.elements; ++i) {
            values_[p.value_at + i] =
                width == 2 ? uss::make_dword(request.pwe[2 * i], request.pwe[2 * i + 1])
                           : request.pwe[i];
          }
          if (eeprom) ++stats_.eeprom_writes;
        }
        out.id = p.dword() ? rep::kArrayDword : rep::kArrayWord;
        out.pnu = p.pnu;
        out.ind = request.ind;
        for (std::size_t i = 0; i < p.elements; ++i) {
          const std::uint32_t v = values_[p.value_at + i];
          if (width == 2) {
            out.pwe[2 * i] = uss::high_word(v);
            out.pwe[2 * i + 1] = uss::low_word(v);
          } else {
            out.pwe[i] = static_cast<std::uint16_t>(v);
          }
        }
        out.pwe_count = static_cast<std::uint8_t>(p.elements * width);
        return out;
      }
      const auto slot = slot_of(p, element);
      if (!slot) return error(request, 3);  // fehlerhafter IND
      if (dword_write && pkw_capacity() < 2) return error(request, kErrorPkwTooShort);
      if (write) {
        if (p.read_only) return error(request, 1);
        if (word_write && config_.pkw == PkwLength::Four && request.pwe[0] != 0) {
          violation(last_advance_, kRulePwe1);
        }
        const std::uint32_t v =
            uss::value(request, config_.pkw, dword_write ? PkwWidth::Dword : PkwWidth::Word);
        if (v < p.min || v > p.max) return error(request, 2);
        values_[*slot] = v;
        if (eeprom) ++stats_.eeprom_writes;
      }
      if (!value_reply(p, *slot, rep::kArrayWord, rep::kArrayDword, request.ind, out)) {
        return error(request, kErrorPkwTooShort);
      }
      return out;
    }
    case req::kReadArrayCount:
      if (p.elements == 0) return error(request, 4);
      out.id = rep::kArrayCount;
      out.pnu = p.pnu;
      out.ind = request.ind;
      uss::set_value(out, config_.pkw, PkwWidth::Word, p.elements);
      return out;
    case req::kWriteDescription:
      return error(request, 7);  // Beschreibungselement nicht änderbar
    case req::kReadDescription: {
      // Elements 1..10 (C 6; layout in the header). 255 = the whole description.
      std::array<std::uint16_t, 24> words{};
      std::array<std::size_t, 11> start{};
      std::size_t n = 0;
      const std::size_t width = p.dword() ? 2 : 1;
      auto put = [&](std::uint32_t v, std::size_t count) {
        if (count == 2) {
          words[n++] = uss::high_word(v);
          words[n++] = uss::low_word(v);
        } else {
          words[n++] = static_cast<std::uint16_t>(v);
        }
      };
      const bool texts = p.place_texts > 0 || p.value_texts > 0;
      start[1] = n;
      put(static_cast<std::uint32_t>(p.type | (p.read_only ? 1U << 9 : 0U) |
                                     (texts ? 1U << 10 : 0U) | (p.active ? 1U << 11 : 0U) |
                                     (p.elements > 0 ? 1U << 14 : 0U)),
          1);
      start[2] = n;
      put(p.elements, 1);
      start[3] = n;
      put(0x3F800000, 2);  // standardisation factor 1.0 (float)
      start[4] = n;
      put(0, 1);  // variable attribute
      start[5] = n;
      put(0, 2);  // reserved
      start[6] = n;
      const auto name = text16(p.name);
      for (std::size_t w = 0; w < kTextWords; ++w) {
        words[n++] = static_cast<std::uint16_t>((static_cast<std::uint8_t>(name[2 * w]) << 8) |
                                                static_cast<std::uint8_t>(name[2 * w + 1]));
      }
      start[7] = n;
      put(p.min, width);
      start[8] = n;
      put(p.max, width);
      start[9] = n;
      put(0, 1);  // reserved
      start[10] = n;
      put(0, 1);  // identifier extension
      const std::size_t total = n;
      out.id = rep::kDescription;
      out.pnu = p.pnu;
      out.ind = request.ind;
      std::size_t first = 0;
      std::size_t count = 0;
      if (element == uss::kIndWhole) {
        first = 0;
        count = total;
        if (!variable) return error(request, kErrorPkwTooShort);
      } else if (element >= 1 && element <= 10) {
        first = start[element];
        count = (element == 10 ? total : start[element + 1U]) - first;
      } else {
        return error(request, 3);
      }
      // C 6: "Ist die Länge des PKW-Bereichs (in Worten) kleiner definiert ... als die Länge
      // des zu übertragenden Elements, wird der Auftrag vom Slave mit der negativen
      // Antwortkennung 'Auftrag nicht ausführbar' beantwortet."
      if (count > pkw_capacity()) return error(request, kErrorPkwTooShort);
      if (variable || count > 2) {
        std::copy_n(words.begin() + static_cast<std::ptrdiff_t>(first), count, out.pwe.begin());
        out.pwe_count = static_cast<std::uint8_t>(count);
      } else if (count == 2) {
        uss::set_value(out, config_.pkw, PkwWidth::Dword,
                       uss::make_dword(words[first], words[first + 1]));
      } else {
        uss::set_value(out, config_.pkw, PkwWidth::Word, words[first]);
      }
      return out;
    }
    case req::kText: {
      // C 4.2.2: "Die fehlerfreie Bearbeitung mit Auftragskennung 15 erfordert immer eine
      // Parametrierung auf variable Telegrammlänge (PKW_ANZ = 127)."
      if (!variable || pkw_capacity() < kTextWords) return error(request, kErrorPkwTooShort);
      // "Die Sonderstellung Low-Byte = 255 ist ohne Bedeutung!" and 1 <= y <= 254.
      if (element == 0 || element == uss::kIndWhole) return error(request, 3);
      const bool value_field = (request.ind & uss::kIndValueTexts) != 0;
      std::size_t at = 0;
      std::size_t count = 0;
      if (p.elements > 0 && !value_field) {
        at = p.place_texts_at;  // the meaning of each place (Tabelle 4.5, y = place)
        count = p.place_texts;
      } else if (p.elements > 0 || !value_field) {
        at = p.value_texts_at;  // the meaning of each value (y = value + 1, Tabelle 4.6)
        count = p.value_texts;
      }
      if (element > count) return error(request, 3);
      auto& text = texts_[at + element - 1U];
      if ((request.ind & uss::kIndTextWrite) != 0 && !repeat) {
        text.fill(' ');
        for (std::size_t w = 0; w < std::min<std::size_t>(request.pwe_count, kTextWords); ++w) {
          text[2 * w] = static_cast<char>(request.pwe[w] >> 8);
          text[2 * w + 1] = static_cast<char>(request.pwe[w] & 0xFF);
        }
      }
      out.id = rep::kText;
      out.pnu = p.pnu;
      out.ind = request.ind;
      put_text(text, out);
      return out;
    }
    default:
      break;
  }
  return error(request, kErrorReservedRequest);
}

void UssSlaveSim::violation(MonoTime at, std::string_view rule) noexcept {
  ++stats_.violations;
  const std::size_t cap = violations_.size();
  if (violation_count_ == cap) {  // full: the oldest goes
    violation_first_ = (violation_first_ + 1) % cap;
    --violation_count_;
  }
  violations_[(violation_first_ + violation_count_) % cap] = {at, config_.address, rule};
  ++violation_count_;
}

std::size_t UssSlaveSim::take_violations(std::span<UssViolation> out) noexcept {
  std::size_t n = 0;
  while (n < out.size() && violation_count_ > 0) {
    out[n++] = violations_[violation_first_];
    violation_first_ = (violation_first_ + 1) % violations_.size();
    --violation_count_;
  }
  return n;
}

// ============================================================================ UssBusSim

UssBusSim::UssBusSim(std::span<const UssSlaveConfig> slaves, std::uint32_t baud, MonoTime now)
    : baud_(baud) {
  if (slaves.empty()) throw std::invalid_argument("a USS bus needs at least one slave");
  slaves_.reserve(slaves.size());
  for (const UssSlaveConfig& c : slaves) {
    for (const UssSlaveSim& s : slaves_) {
      if (s.address() == c.address) {
        throw std::invalid_argument("USS slave address " + std::to_string(c.address) +
                                    " given twice (USS A 5.4: \"Eine Adresse (Bit 0 bis 4) "
                                    "darf nur einmal am Bus vorkommen\")");
      }
    }
    slaves_.emplace_back(c, baud, now);
  }
}

void UssBusSim::on_char(const uss::RxChar& c, MonoTime at) noexcept {
  for (UssSlaveSim& s : slaves_) s.on_char(c, at);
}

void UssBusSim::on_time(MonoTime now) noexcept {
  for (UssSlaveSim& s : slaves_) s.on_time(now);
}

void UssBusSim::advance(MonoTime now) noexcept {
  for (UssSlaveSim& s : slaves_) s.advance(now);
}

std::optional<MonoTime> UssBusSim::deadline() const noexcept {
  std::optional<MonoTime> d;
  for (const UssSlaveSim& s : slaves_) {
    if (const auto x = s.deadline(); x && (!d || *x < *d)) d = x;
  }
  return d;
}

std::optional<MonoTime> UssBusSim::next_reply_at() const noexcept {
  std::optional<MonoTime> d;
  for (const UssSlaveSim& s : slaves_) {
    if (const auto x = s.next_reply_at(); x && (!d || *x < *d)) d = x;
  }
  return d;
}

bool UssBusSim::take_reply(MonoTime now, UssReply& out) noexcept {
  UssSlaveSim* first = nullptr;
  for (UssSlaveSim& s : slaves_) {
    const auto x = s.next_reply_at();
    if (x && *x <= now && (first == nullptr || *x < *first->next_reply_at())) first = &s;
  }
  if (first == nullptr || !first->take_reply(now, out)) return false;
  reply_sent(std::max(now, out.send_at) + uss::transmission_time(baud_, out.size));
  return true;
}

void UssBusSim::reply_sent(MonoTime end) noexcept {
  for (UssSlaveSim& s : slaves_) s.reply_sent(end);
}

UssSlaveSim* UssBusSim::slave(std::uint8_t address) noexcept {
  for (UssSlaveSim& s : slaves_) {
    if (s.address() == address) return &s;
  }
  return nullptr;
}

const UssSlaveSim* UssBusSim::slave(std::uint8_t address) const noexcept {
  for (const UssSlaveSim& s : slaves_) {
    if (s.address() == address) return &s;
  }
  return nullptr;
}

std::size_t UssBusSim::take_violations(std::span<UssViolation> out) noexcept {
  std::size_t n = 0;
  for (UssSlaveSim& s : slaves_) {
    n += s.take_violations(out.subspan(n));
  }
  return n;
}

}  // namespace liftd::uss::sim
