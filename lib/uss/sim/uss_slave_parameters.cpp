// The simulated USS slave's PKW parameter store (USS C 4 and C 6): the parameters, their
// descriptions and texts, the requests of C 4.2.1 with their answers and errors, and the
// spontaneous reports (C 4.2.1.2).
#include "uss/sim/uss_slave_sim.hpp"

#include <algorithm>
#include <array>
#include <optional>

#include "uss/sim/uss_slave_sim_detail.hpp"

namespace liftd::uss::sim {

using namespace detail;

namespace {

// Characters in storage order, the first one in the high byte (C 6 "Übertragung von Texten").
void put_text(std::span<const char> text, Pkw& out) {
  for (std::size_t w = 0; w < kTextWords; ++w) {
    out.pwe[w] = static_cast<std::uint16_t>((static_cast<std::uint8_t>(text[2 * w]) << 8) |
                                            static_cast<std::uint8_t>(text[2 * w + 1]));
  }
  out.pwe_count = kTextWords;
}

}  // namespace

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

// Over 120 lines: one case per request id of C 4.2.1.1 Tabelle 4.1, each read on its own.
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

}  // namespace liftd::uss::sim
