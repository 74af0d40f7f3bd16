#include "uss/master/master.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>
#include <utility>

namespace liftd::uss {
namespace {

std::string address_text(std::uint8_t address) {
  return std::to_string(static_cast<unsigned>(address));
}

std::string us_text(std::chrono::nanoseconds d) {
  return std::to_string(d.count() / 1000) + " us";
}

bool valid_pkw_length(PkwLength len) noexcept {
  return len == PkwLength::None || len == PkwLength::Three || len == PkwLength::Four ||
         len == PkwLength::Variable;
}

// Payload bytes of a poll without a PKW request ("kein Auftrag", C 4.2.1.1): PKW area of the
// slave's length plus its PZD words (C 2).
std::size_t idle_payload_bytes(const SlaveConfig& s) noexcept {
  return pkw_bytes(s.pkw, Pkw{}) + 2U * s.pzd_words;
}

}  // namespace

Master::Master(MasterConfig config)
    : config_(std::move(config)),
      char_time_(character_time(config_.baud)),
      start_pause_(uss::start_pause(config_.baud)),
      rx_(config_.baud) {
  const std::string where = "uss master: ";
  if (config_.baud == 0) throw std::invalid_argument(where + "baud rate 0");
  for (const SlaveConfig& s : config_.slaves) {
    if (s.address > kMaxSlaveAddress) {
      throw std::invalid_argument(where + "slave address " + address_text(s.address) +
                                  " is above 31 (A 4.3: ADR bits 0..4)");
    }
    Slot& slot = slots_[s.address];
    if (slot.configured) {
      throw std::invalid_argument(where + "slave address " + address_text(s.address) +
                                  " is configured twice (A 5.4: an address occurs once on a bus)");
    }
    if (s.pzd_words > kMaxPzdWords) {
      throw std::invalid_argument(where + "slave " + address_text(s.address) + ": " +
                                  std::to_string(static_cast<unsigned>(s.pzd_words)) +
                                  " PZD words, at most 16 (C 3.1 PZD_ANZ)");
    }
    if (!valid_pkw_length(s.pkw)) {
      throw std::invalid_argument(where + "slave " + address_text(s.address) + ": PKW length " +
                                  std::to_string(static_cast<unsigned>(s.pkw)) +
                                  " is none of 0, 3, 4, 127 (C 3.1 PKW_ANZ)");
    }
    slot.configured = true;
    slot.config = s;
    slot.state.configured = true;
    // C 7: with fixed lengths request and reply have the same PKW and PZD size; variable
    // length (127) replies are checked for a valid LGE only (A 5.2).
    slot.reply_lge = s.pkw == PkwLength::Variable ? 0 : lge_for_payload(idle_payload_bytes(s));
    if (config_.mirror_at_start) {
      slot.mirror_pending = true;
      slot.mirror_tag = kStartMirrorTag;
    }
  }
  if (config_.polling_list.empty()) {
    throw std::invalid_argument(where +
                                "the polling list is empty (A 5.1: the Umlaufliste names the "
                                "slaves to poll)");
  }
  for (const std::uint8_t a : config_.polling_list) {
    if (a > kMaxSlaveAddress || !slots_[a].configured) {
      throw std::invalid_argument(where + "polling list entry " + address_text(a) +
                                  " is not a configured slave");
    }
  }
  if (config_.reply_delay > kMaxReplyDelay) {
    throw std::invalid_argument(where + "reply delay " + us_text(config_.reply_delay) +
                                " is above the 20 ms maximum (A 5.2.1.1)");
  }
  if (config_.reply_delay < start_pause_) {
    throw std::invalid_argument(where + "reply delay " + us_text(config_.reply_delay) +
                                " is below the start pause of " + us_text(start_pause_) + " at " +
                                std::to_string(config_.baud) +
                                " baud (A 5.2.1.1: never below the start pause)");
  }
  if (config_.cycle_time && config_.cycle_time->count() <= 0) {
    throw std::invalid_argument(where + "fixed cycle time must be above 0 (A 5.1.1)");
  }
  if (config_.expected_reply_delay && config_.expected_reply_delay->count() < 0) {
    throw std::invalid_argument(where + "negative expected reply delay");
  }
  if (config_.pkw_repeat_limit == 0) {
    throw std::invalid_argument(where +
                                "pkw_repeat_limit must be at least 1 (C 4.2.1.1: the "
                                "request is repeated until its reply comes)");
  }
  polling_ = config_.polling_list;

  std::vector<Exchange> exchanges;
  exchanges.reserve(polling_.size());
  for (const std::uint8_t a : polling_) {
    const SlaveConfig& s = slots_[a].config;
    const std::size_t bytes = telegram_bytes(idle_payload_bytes(s));
    exchanges.push_back(
        Exchange{bytes, bytes, config_.expected_reply_delay.value_or(config_.reply_delay)});
  }
  expected_cycle_ = uss::expected_cycle_time(config_.baud, exchanges);
  if (config_.cycle_time) expected_cycle_ = std::max(expected_cycle_, *config_.cycle_time);
}

// ---- runner side ----

Master::Choice Master::choose() const noexcept {
  Choice c;
  if (startup_) {
    // mirror_at_start: every slave once, in configuration order, before the first poll.
    for (const SlaveConfig& s : config_.slaves) {
      if (slots_[s.address].mirror_pending) {
        c.what = Choice::What::Mirror;
        c.address = s.address;
        return c;
      }
    }
  } else if (extra_allowed_) {
    for (std::size_t i = 0; i < kSlots; ++i) {
      const std::size_t a = (mirror_cursor_ + i) % kSlots;
      if (slots_[a].mirror_pending) {
        c.what = Choice::What::Mirror;
        c.address = static_cast<std::uint8_t>(a);
        return c;
      }
    }
    if (!extras_.empty()) {
      c.what = Choice::What::Extra;
      c.address = extras_.front()->address;
      return c;
    }
  }
  c.what = Choice::What::Poll;
  c.address = polling_[poll_index_];
  return c;
}

MonoTime Master::send_at() const noexcept {
  // A 5.1.2: a character-free start pause of at least 2 character times before the STX.
  MonoTime at = line_free_ + start_pause_;
  const Choice c = choose();
  if (c.what == Choice::What::Poll && poll_index_ == 0 && config_.cycle_time && pass_started_) {
    // A 5.1.1: wait until the defined cycle time has elapsed before a new pass begins.
    at = std::max(at, pass_start_ + *config_.cycle_time);
  }
  return at;
}

std::size_t Master::build_poll(Slot& s, std::uint8_t adr) noexcept {
  Pkw request = s.pkw_active ? s.request : Pkw{};
  request.toggle = s.toggle;  // C 4.2.1.2: our acknowledgement bit in every request
  const std::size_t n = encode_payload(
      request, s.config.pkw, std::span<const std::uint16_t>(s.pzd_out.data(), s.config.pzd_words),
      payload_);
  return encode_telegram(adr, std::span<const std::uint8_t>(payload_.data(), n), tx_);
}

std::span<const std::uint8_t> Master::next_telegram(MonoTime now) noexcept {
  if (phase_ != Phase::Idle) return {};
  const Choice c = choose();
  current_ = Current{};
  current_.started = now;
  current_.address = c.address;
  switch (c.what) {
    case Choice::What::Mirror: {
      Slot& s = slots_[c.address];
      s.mirror_pending = false;
      current_.kind = TelegramKind::Mirror;
      current_.tag = s.mirror_tag;
      current_.expects_reply = true;
      // A 5.3: the normal telegram with ADR bit 6 set.
      tx_size_ = build_poll(s, make_adr(c.address, TelegramType::Mirror));
      mirror_cursor_ = (static_cast<std::size_t>(c.address) + 1) % kSlots;
      extra_allowed_ = false;
      ++counters_.mirrors;
      break;
    }
    case Choice::What::Extra: {
      const Extra* e = extras_.front();
      current_.kind = e->kind;
      current_.tag = e->tag;
      // A 3 / A 5.4: no slave answers a broadcast; a special telegram to one slave is answered.
      current_.expects_reply = e->kind == TelegramKind::Special;
      std::copy_n(e->bytes.data(), e->size, tx_.data());
      tx_size_ = e->size;
      extras_.drop_front();
      extra_allowed_ = false;
      if (current_.kind == TelegramKind::Broadcast) {
        ++counters_.broadcasts;
      } else {
        ++counters_.specials;
      }
      break;
    }
    case Choice::What::Poll: {
      startup_ = false;
      Slot& s = slots_[c.address];
      if (poll_index_ == 0) {
        current_.pass_start = true;
        if (pass_started_) {
          last_cycle_ = now - pass_start_;
          ++cycles_;
        }
        pass_start_ = now;
        pass_started_ = true;
      }
      poll_index_ = (poll_index_ + 1) % polling_.size();
      current_.kind = TelegramKind::Poll;
      current_.carried_pkw = s.pkw_active;
      current_.expects_reply = true;
      tx_size_ = build_poll(s, make_adr(c.address, TelegramType::Normal));
      extra_allowed_ = true;
      ++counters_.polls;
      break;
    }
  }
  phase_ = Phase::Sent;
  return {tx_.data(), tx_size_};
}

void Master::on_sent(MonoTime end_of_last_byte) noexcept {
  if (phase_ != Phase::Sent) return;
  sent_end_ = end_of_last_byte;
  line_free_ = std::max(line_free_, end_of_last_byte);
  if (!current_.expects_reply) {
    phase_ = Phase::Idle;
    last_outcome_ = ExchangeOutcome::NoReplyExpected;
    return;
  }
  std::uint8_t lge = 0;
  if (current_.kind == TelegramKind::Poll) {
    Slot& s = slots_[current_.address];
    lge = s.reply_lge;
    if (current_.carried_pkw) ++s.pkw_polls;
  } else if (current_.kind == TelegramKind::Mirror) {
    lge = tx_[1];  // A 5.3: the same telegram comes back
  }
  rx_.restart();
  rx_.set_expected_lge(lge);
  reply_started_ = false;
  phase_ = Phase::Awaiting;
}

MonoTime Master::reply_deadline() const noexcept {
  // A 5.2.1.1: the STX must begin within the reply delay after our BCC; it is stamped when it
  // is complete, one character time later. The first late instant, as Receiver::deadline().
  return sent_end_ + config_.reply_delay + char_time_ + std::chrono::nanoseconds(1);
}

MonoTime Master::deadline() const noexcept {
  if (phase_ != Phase::Awaiting) return MonoTime::max();
  if (rx_.receiving()) {
    if (const auto d = rx_.deadline()) return *d;  // A 5.2.1.2 residual time
  }
  return reply_deadline();
}

void Master::on_char(const RxChar& c, MonoTime at) noexcept {
  if (phase_ != Phase::Awaiting) {
    ++counters_.stray_chars;
    return;
  }
  if (!rx_.receiving() && at >= reply_deadline()) {
    // The reply delay ran out before this character (A 5.2.1.1).
    on_time(at);
    ++counters_.stray_chars;
    return;
  }
  const bool was_receiving = rx_.receiving();
  const RxResult r = rx_.feed(c, at);
  line_free_ = std::max(line_free_, at);
  if (!was_receiving && (rx_.receiving() || r.kind == RxResult::Kind::Complete)) {
    reply_started_ = true;
    stx_at_ = at;
  }
  switch (r.kind) {
    case RxResult::Kind::Pending:
      return;
    case RxResult::Kind::Complete:
      finish_reply(at);
      return;
    case RxResult::Kind::Rejected:
      // A character that is no STX before the reply (A 5.2.3 counter 12) does not end the
      // wait; any other rejection is an unusable reply (A 5.2.2).
      if (r.error == RxError::NoStx) return;
      ++counters_.bad_replies;
      fail_exchange(ExchangeOutcome::BadReply, at);
      return;
  }
}

void Master::on_collision(MonoTime at) noexcept {
  if (phase_ != Phase::Awaiting) return;
  line_free_ = std::max(line_free_, at);
  ++counters_.bad_replies;
  fail_exchange(ExchangeOutcome::BadReply, at);
}

void Master::on_time(MonoTime now) noexcept {
  if (phase_ != Phase::Awaiting) return;
  if (rx_.receiving()) {
    const RxResult r = rx_.check_time(now);
    if (r.kind == RxResult::Kind::Rejected) {
      // A 5.2.1.2: residual time exceeded; the rest of the telegram may still be on the line.
      line_free_ = std::max(line_free_, now);
      ++counters_.bad_replies;
      fail_exchange(ExchangeOutcome::BadReply, now);
    }
    return;
  }
  if (now >= reply_deadline()) {
    rx_.count_reply_timeout();  // A 5.2.3: error word bit 7, counter 16
    ++counters_.reply_timeouts;
    fail_exchange(ExchangeOutcome::Timeout, now);
  }
}

void Master::reset_link(MonoTime now) noexcept {
  if (phase_ != Phase::Idle) {
    ++counters_.abandoned;
    if (phase_ == Phase::Awaiting) {
      if (current_.kind == TelegramKind::Poll && current_.carried_pkw) {
        Slot& s = slots_[current_.address];
        if (s.pkw_polls > 0) --s.pkw_polls;
      } else if (current_.kind == TelegramKind::Mirror) {
        push_mirror_result(false, std::chrono::nanoseconds{0});
      } else if (current_.kind == TelegramKind::Special) {
        push_special_result(false);
      }
    } else if (current_.kind == TelegramKind::Mirror) {
      push_mirror_result(false, std::chrono::nanoseconds{0});
    } else if (current_.kind == TelegramKind::Special) {
      push_special_result(false);
    }
    phase_ = Phase::Idle;
    last_outcome_ = ExchangeOutcome::Abandoned;
  }
  rx_.restart();
  line_free_ = now;
  // What the slaves answered before is void: the line (or the device behind it) may be another
  // now. A slave's process data (its status word, C 5.1) counts again only once it answers.
  for (Slot& slot : slots_) {
    slot.state.responding = false;
    slot.state.pzd_in = {};
    slot.state.pzd_in_count = 0;
    slot.state.consecutive_failures = 0;
  }
}

void Master::finish_reply(MonoTime at) noexcept {
  const Telegram t = rx_.telegram();
  // A 6.2: k characters take at least k character times on the line; the STX was stamped at
  // its end, one character time after the telegram began.
  const std::size_t k = telegram_bytes(t.payload.size());
  line_free_ = std::max(line_free_, stx_at_ - char_time_ + transmission_time(config_.baud, k));
  switch (current_.kind) {
    case TelegramKind::Poll:
      finish_poll_reply(slots_[current_.address], t, at);
      return;
    case TelegramKind::Mirror: {
      // A 5.3: sent back "ohne irgendwelche Veränderungen": compared byte for byte.
      const std::span<const std::uint8_t> got = rx_.bytes();
      const bool ok = got.size() == tx_size_ && std::equal(got.begin(), got.end(), tx_.begin());
      Slot& s = slots_[current_.address];
      push_mirror_result(ok, at - current_.started);
      if (ok) {
        note_good(s, at);
        ++counters_.good_replies;
        end_exchange(ExchangeOutcome::Reply);
      } else {
        ++counters_.mirror_mismatches;
        ++counters_.bad_replies;
        note_failure(s, at);
        end_exchange(ExchangeOutcome::BadReply);
      }
      return;
    }
    case TelegramKind::Special: {
      // A 5.2: a reply must come from the addressed slave (ADR bits 0..4).
      if (parse_adr(t.adr).slave != current_.address) {
        ++counters_.wrong_address;
        ++counters_.bad_replies;
        fail_exchange(ExchangeOutcome::BadReply, at);
        return;
      }
      push_special_result(true);
      if (slots_[current_.address].configured) note_good(slots_[current_.address], at);
      ++counters_.good_replies;
      end_exchange(ExchangeOutcome::Reply);
      return;
    }
    case TelegramKind::Broadcast:
    case TelegramKind::SpecialBroadcast:
      return;  // never awaited
  }
}

void Master::finish_poll_reply(Slot& s, const Telegram& t, MonoTime at) noexcept {
  // A 5.2: "Entspricht das Adreßbyte (ADR) nicht ... der erwarteten Slave-Teilnehmernummer
  // (beim Master), so wird das Telegramm verworfen."
  if (parse_adr(t.adr) != AddressByte{current_.address, TelegramType::Normal}) {
    ++counters_.wrong_address;
    ++counters_.bad_replies;
    fail_exchange(ExchangeOutcome::BadReply, at);
    return;
  }
  if (!decode_payload(t.payload, s.config.pkw, s.config.pzd_words, reply_pkw_, pzd_scratch_)) {
    ++counters_.bad_payload;
    ++counters_.bad_replies;
    fail_exchange(ExchangeOutcome::BadReply, at);
    return;
  }
  std::copy_n(pzd_scratch_.data(), s.config.pzd_words, s.state.pzd_in.data());
  s.state.pzd_in_count = s.config.pzd_words;
  note_good(s, at);
  if (s.config.pkw != PkwLength::None) handle_pkw_reply(s, reply_pkw_, at);
  ++counters_.good_replies;
  end_exchange(ExchangeOutcome::Reply);
}

void Master::handle_pkw_reply(Slot& s, const Pkw& reply, MonoTime at) noexcept {
  if (is_spontaneous(reply.id)) {
    // C 4.2.1.2: the report interrupts the answer to our request; that poll does not count.
    if (current_.carried_pkw && s.pkw_active && s.pkw_polls > 0) --s.pkw_polls;
    if (reply.toggle != s.toggle) {
      // New: surface it; taking its bit changes ours in the next request (acknowledgement).
      s.toggle = reply.toggle;
      s.toggle_known = true;
      ++counters_.spontaneous;
      if (!reports_.push(SpontaneousReport{current_.address, reply, at})) {
        ++counters_.dropped_reports;
      }
    } else {
      ++counters_.spontaneous_repeats;
    }
    return;
  }
  if (!s.toggle_known) {
    s.toggle = reply.toggle;
    s.toggle_known = true;
  }
  if (!current_.carried_pkw || !s.pkw_active) return;  // "keine Antwort" to "kein Auftrag"
  switch (classify_reply(s.request, reply)) {
    case ReplyClass::Matches:
      finish_pkw(s, PkwResult::Outcome::Done, &reply);
      return;
    case ReplyClass::Error:
      finish_pkw(s, PkwResult::Outcome::Error, &reply);
      return;
    case ReplyClass::NoAuthority:
      finish_pkw(s, PkwResult::Outcome::NoAuthority, &reply);
      return;
    case ReplyClass::Spontaneous:  // handled above
    case ReplyClass::Unrelated:
      // C 4.2.1.1: the slave still answers the old request; keep repeating ours.
      ++counters_.pkw_stale_replies;
      return;
  }
}

void Master::finish_pkw(Slot& s, PkwResult::Outcome outcome, const Pkw* reply) noexcept {
  s.result.tag = s.pkw_tag;
  s.result.address = s.config.address;
  s.result.outcome = outcome;
  if (reply != nullptr) {
    s.result.reply = *reply;
  } else {
    s.result.reply = Pkw{};
  }
  s.result.error_number = outcome == PkwResult::Outcome::Error && reply != nullptr
                              ? error_number(*reply, s.config.pkw)
                              : std::uint16_t{0};
  s.result_ready = true;
  s.pkw_active = false;
  s.pkw_polls = 0;
  s.state.pkw_busy = true;  // until poll_pkw_result() takes the result
}

void Master::fail_exchange(ExchangeOutcome outcome, MonoTime at) noexcept {
  Slot& s = slots_[current_.address];
  if (s.configured) note_failure(s, at);
  if (current_.kind == TelegramKind::Mirror) {
    const bool got_something = reply_started_;
    push_mirror_result(false, got_something ? at - current_.started : std::chrono::nanoseconds{0});
  } else if (current_.kind == TelegramKind::Special) {
    push_special_result(false);
  }
  end_exchange(outcome);
}

void Master::end_exchange(ExchangeOutcome outcome) noexcept {
  if (current_.kind == TelegramKind::Poll && current_.carried_pkw) {
    Slot& s = slots_[current_.address];
    // C 4.2.1.1: "Erhält der Auftraggeber ... keine zum Auftrag gehörende Antwortkennung, so
    // ist im Auftraggeber für eine entsprechende Reaktion zu sorgen."
    if (s.pkw_active && s.pkw_polls >= config_.pkw_repeat_limit) {
      ++counters_.pkw_unanswered;
      finish_pkw(s, PkwResult::Outcome::Unanswered, nullptr);
    }
  }
  phase_ = Phase::Idle;
  last_outcome_ = outcome;
}

void Master::note_good(Slot& s, MonoTime at) noexcept {
  s.state.heard = true;
  ++s.state.good;
  s.state.consecutive_failures = 0;
  s.state.last_good = at;
  s.down_announced = false;
  if (!s.state.responding) {
    // A 5.2.1.1: "sendet nicht" is cleared by an error-free telegram from the slave.
    s.state.responding = true;
    if (!link_changes_.push(LinkChange{s.config.address, true, at})) {
      ++counters_.dropped_link_changes;
    }
  }
}

void Master::note_failure(Slot& s, MonoTime at) noexcept {
  ++s.state.failures;
  ++s.state.consecutive_failures;
  s.state.responding = false;
  s.toggle_known = false;  // adopt the slave's bit 11 again when it is back (it may restart)
  if (!s.down_announced) {
    s.down_announced = true;
    if (!link_changes_.push(LinkChange{s.config.address, false, at})) {
      ++counters_.dropped_link_changes;
    }
  }
}

void Master::push_mirror_result(bool ok, std::chrono::nanoseconds round_trip) noexcept {
  if (!mirror_results_.push(MirrorResult{current_.tag, current_.address, ok, round_trip})) {
    ++counters_.dropped_results;
  }
}

void Master::push_special_result(bool answered) noexcept {
  SpecialResult r;
  r.tag = current_.tag;
  r.address = current_.address;
  r.answered = answered;
  if (answered) {
    const Telegram t = rx_.telegram();
    r.adr = t.adr;
    r.size = static_cast<std::uint8_t>(t.payload.size());
    std::copy(t.payload.begin(), t.payload.end(), r.payload.begin());
  }
  if (!special_results_.push(r)) ++counters_.dropped_results;
}

// ---- user side ----

void Master::set_pzd(std::uint8_t address, std::span<const std::uint16_t> words) noexcept {
  if (address > kMaxSlaveAddress || !slots_[address].configured) return;
  Slot& s = slots_[address];
  const std::size_t n = std::min<std::size_t>(words.size(), s.config.pzd_words);
  std::copy_n(words.data(), n, s.pzd_out.data());
}

const SlaveState& Master::slave(std::uint8_t address) const noexcept {
  static const SlaveState kUnconfigured{};
  if (address > kMaxSlaveAddress) return kUnconfigured;
  return slots_[address].state;
}

bool Master::submit_pkw(std::uint8_t address, const Pkw& request, std::uint32_t tag) noexcept {
  if (address > kMaxSlaveAddress) return false;
  Slot& s = slots_[address];
  if (!s.configured || s.config.pkw == PkwLength::None || s.pkw_active || s.result_ready) {
    return false;
  }
  if (request.id == request::kNone) return false;  // "kein Auftrag" is what idle polls send
  Pkw r = request;
  r.toggle = false;
  std::array<std::uint8_t, kMaxPayloadBytes> scratch{};
  if (encode_payload(r, s.config.pkw,
                     std::span<const std::uint16_t>(s.pzd_out.data(), s.config.pzd_words),
                     scratch) == 0) {
    return false;  // does not fit the slave's PKW length (C 7)
  }
  s.request = r;
  s.pkw_active = true;
  s.pkw_tag = tag;
  s.pkw_polls = 0;
  s.state.pkw_busy = true;
  return true;
}

bool Master::poll_pkw_result(PkwResult& out) noexcept {
  for (std::size_t i = 0; i < kSlots; ++i) {
    const std::size_t a = (result_cursor_ + i) % kSlots;
    Slot& s = slots_[a];
    if (s.result_ready) {
      out = s.result;
      s.result_ready = false;
      s.state.pkw_busy = s.pkw_active;
      result_cursor_ = (a + 1) % kSlots;
      return true;
    }
  }
  return false;
}

bool Master::poll_spontaneous(SpontaneousReport& out) noexcept {
  const SpontaneousReport* r = reports_.front();
  if (r == nullptr) return false;
  out = *r;
  reports_.drop_front();
  return true;
}

bool Master::request_mirror(std::uint8_t address, std::uint32_t tag) noexcept {
  if (address > kMaxSlaveAddress) return false;
  Slot& s = slots_[address];
  if (!s.configured || s.mirror_pending) return false;
  s.mirror_pending = true;
  s.mirror_tag = tag;
  return true;
}

bool Master::poll_mirror(MirrorResult& out) noexcept {
  const MirrorResult* r = mirror_results_.front();
  if (r == nullptr) return false;
  out = *r;
  mirror_results_.drop_front();
  return true;
}

bool Master::send_broadcast(const BroadcastEnable& enable,
                            std::span<const std::uint16_t> pzd) noexcept {
  if (pzd.size() > kMaxPzdWords || extras_.full()) return false;
  // Appendix: the PKW area carries the 4-word broadcast enable array.
  Pkw pkw;
  encode_broadcast_enable(enable, pkw);
  std::array<std::uint8_t, kMaxPayloadBytes> payload{};
  const std::size_t n = encode_payload(pkw, PkwLength::Four, pzd, payload);
  if (n == 0) return false;
  Extra e;
  e.kind = TelegramKind::Broadcast;
  e.address = 0;
  e.size = static_cast<std::uint16_t>(
      encode_telegram(make_adr(0, TelegramType::Broadcast),
                      std::span<const std::uint8_t>(payload.data(), n), e.bytes));
  if (e.size == 0) return false;
  return extras_.push(e);
}

bool Master::send_special(std::uint8_t address, bool broadcast,
                          std::span<const std::uint8_t> payload, std::uint32_t tag) noexcept {
  if (address > kMaxSlaveAddress || payload.size() > kMaxPayloadBytes || extras_.full()) {
    return false;
  }
  Extra e;
  e.kind = broadcast ? TelegramKind::SpecialBroadcast : TelegramKind::Special;
  e.address = address;
  e.tag = tag;
  e.size = static_cast<std::uint16_t>(encode_telegram(
      make_adr(address, broadcast ? TelegramType::SpecialBroadcast : TelegramType::Special),
      payload, e.bytes));
  if (e.size == 0) return false;
  return extras_.push(e);
}

bool Master::poll_special(SpecialResult& out) noexcept {
  const SpecialResult* r = special_results_.front();
  if (r == nullptr) return false;
  out = *r;
  special_results_.drop_front();
  return true;
}

bool Master::poll_link_change(LinkChange& out) noexcept {
  const LinkChange* r = link_changes_.front();
  if (r == nullptr) return false;
  out = *r;
  link_changes_.drop_front();
  return true;
}

}  // namespace liftd::uss
