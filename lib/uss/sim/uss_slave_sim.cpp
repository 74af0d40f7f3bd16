// The simulated USS slave's names, its line and telegram handling (USS A 4 and A 5: receive,
// mirror, broadcast, special telegrams, the reply and its injected faults), the record of what
// the spec forbids the master, and UssBusSim. The drive profile is in uss_slave_drive.cpp, the
// PKW parameter store in uss_slave_parameters.cpp.
#include "uss/sim/uss_slave_sim.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

#include "uss/pzd.hpp"
#include "uss/sim/uss_slave_sim_detail.hpp"
#include "uss/timing.hpp"

namespace liftd::uss::sim {

using namespace detail;

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
        timing_rule(at, replies_[i].awaited_until, kRuleReplyPending);
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
  last_reply_awaited_until_ = out.awaited_until;
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
    if (mine) timing_rule(stx_at_, last_reply_awaited_until_, kRuleStartPause);
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
  // A 5.1.2, A 5.2.1.1: the master sent the request after the bus's last reply at the earliest
  // (without one, the request's own STX stands in), and waits a start pause plus at most 20 ms.
  reply.awaited_until = bus_quiet_from_.value_or(stx_at_) + start_pause_ + uss::kMaxReplyDelay;
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

// ---- injection ----

void UssSlaveSim::inject(UssReplyFault fault, std::uint32_t count) noexcept {
  faults_[static_cast<std::size_t>(fault)] = count;
}

void UssSlaveSim::clear_faults() noexcept {
  faults_.fill(0);
}

void UssSlaveSim::timing_rule(MonoTime at, MonoTime awaited_until, std::string_view rule) noexcept {
  // Characters reach the slave no earlier than the master sent them: one that arrived while a
  // master keeping the spec's times was still bound to wait was sent early for certain. Later
  // it may follow a reply the machine delivered late, which the slave cannot see.
  if (at < awaited_until) {
    violation(at, rule);
  } else {
    ++stats_.unjudged;
  }
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
  const MonoTime end = std::max(now, out.send_at) + uss::transmission_time(baud_, out.size);
  for (UssSlaveSim& s : slaves_) s.reply_sent(end, out.awaited_until);
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
