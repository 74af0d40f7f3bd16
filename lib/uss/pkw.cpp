#include "uss/pkw.hpp"

#include <algorithm>

#include "uss/telegram.hpp"

namespace liftd::uss {
namespace {

constexpr std::uint8_t kNoId = 0xFF;               // unused slot in positive_reply_ids
constexpr std::uint8_t kMaxId = 15;                // AK is 4 bits (C 4.2.1)
constexpr std::uint16_t kIndCompareMask = 0x03FF;  // C 4.2.2: bits 0..9; 10..15 device-specific
constexpr std::size_t kPkeIndWords = 2;            // PKE and IND precede the PWE words (C 4.1)
constexpr std::size_t kWordBytes = 2;

// C 4.2.1.1 Tabelle 4.3: request id -> positive reply ids.
constexpr std::array<std::array<std::uint8_t, 2>, 16> kPositiveReplies = {{
    {reply::kNone, kNoId},                    // 0 no request -> no reply
    {reply::kValueWord, reply::kValueDword},  // 1 read value
    {reply::kValueWord, kNoId},               // 2 write word
    {reply::kValueDword, kNoId},              // 3 write double word
    {reply::kDescription, kNoId},             // 4 read description element
    {reply::kDescription, kNoId},             // 5 write description element
    {reply::kArrayWord, reply::kArrayDword},  // 6 read array element
    {reply::kArrayWord, kNoId},               // 7 write array word
    {reply::kArrayDword, kNoId},              // 8 write array double word
    {reply::kArrayCount, kNoId},              // 9 read number of array elements
    {kNoId, kNoId},                           // 10 reserved: only "cannot be executed"
    {reply::kArrayDword, kNoId},              // 11 array double word + EEPROM
    {reply::kArrayWord, kNoId},               // 12 array word + EEPROM
    {reply::kValueDword, kNoId},              // 13 double word + EEPROM
    {reply::kValueWord, kNoId},               // 14 word + EEPROM
    {reply::kText, kNoId},                    // 15 text
}};

constexpr std::array<std::string_view, 16> kRequestNames = {
    "no request",
    "read value",
    "write value (word)",
    "write value (double word)",
    "read description element",
    "write description element",
    "read array element",
    "write array element (word)",
    "write array element (double word)",
    "read number of array elements",
    "reserved",
    "write array element (double word) and store in EEPROM",
    "write array element (word) and store in EEPROM",
    "write value (double word) and store in EEPROM",
    "write value (word) and store in EEPROM",
    "read or write text",
};

constexpr std::array<std::string_view, 16> kReplyNames = {
    "no reply",
    "value (word)",
    "value (double word)",
    "description element",
    "array element (word)",
    "array element (double word)",
    "number of array elements",
    "request cannot be executed",
    "no parameter change authority",
    "spontaneous report (word)",
    "spontaneous report (double word)",
    "spontaneous report (array word)",
    "spontaneous report (array double word)",
    "reserved",
    "reserved",
    "text",
};

// C 4.2.1.1 error numbers 0..7, in our words.
constexpr std::array<std::string_view, 8> kErrorTexts = {
    "parameter number does not exist",
    "parameter cannot be changed",
    "value outside the lower or upper limit",
    "wrong index",
    "parameter is not an array",
    "wrong data type",
    "setting is not allowed",
    "description element cannot be changed",
};
constexpr std::uint16_t kReservedError = 100;  // C 4.2.1.1: 100 reserved, above: device-specific

std::size_t fixed_pwe_words(PkwLength len) noexcept {
  switch (len) {
    case PkwLength::Three:
      return 1;  // C 4.1.1 Bild 4.1: PKE IND PWE
    case PkwLength::Four:
      return 2;  // C 4.1.1 Bild 4.2: PKE IND PWE1 PWE2
    case PkwLength::None:
    case PkwLength::Variable:
      break;
  }
  return 0;
}

}  // namespace

std::uint16_t Pkw::pke() const noexcept {
  const unsigned ak = static_cast<unsigned>(id) & 0x0FU;
  const unsigned bits = (ak << kAkShift) | (toggle ? unsigned{kToggleBit} : 0U) |
                        (static_cast<unsigned>(pnu) & kPnuMask);
  return static_cast<std::uint16_t>(bits);
}

void Pkw::set_pke(std::uint16_t pke) noexcept {
  id = static_cast<std::uint8_t>(pke >> kAkShift);
  toggle = (pke & kToggleBit) != 0;
  pnu = static_cast<std::uint16_t>(pke & kPnuMask);
}

bool Pkw::operator==(const Pkw& o) const noexcept {
  if (id != o.id || toggle != o.toggle || pnu != o.pnu || ind != o.ind ||
      pwe_count != o.pwe_count) {
    return false;
  }
  const std::size_t n = std::min<std::size_t>(pwe_count, kMaxPweWords);
  return std::equal(pwe.begin(), pwe.begin() + static_cast<std::ptrdiff_t>(n), o.pwe.begin());
}

std::optional<std::uint8_t> read_request_id(PkwTarget target) noexcept {
  switch (target) {
    case PkwTarget::Value:
      return request::kReadValue;
    case PkwTarget::ArrayElement:
      return request::kReadArray;
    case PkwTarget::Description:
      return request::kReadDescription;
    case PkwTarget::Text:
      return request::kText;
  }
  return std::nullopt;
}

std::optional<std::uint8_t> write_request_id(PkwTarget target, PkwWidth width,
                                             bool eeprom) noexcept {
  const bool dword = width == PkwWidth::Dword;
  switch (target) {
    case PkwTarget::Value:
      if (eeprom) return dword ? request::kEepromDword : request::kEepromWord;
      return dword ? request::kWriteDword : request::kWriteWord;
    case PkwTarget::ArrayElement:
      if (eeprom) return dword ? request::kEepromArrayDword : request::kEepromArrayWord;
      return dword ? request::kWriteArrayDword : request::kWriteArrayWord;
    case PkwTarget::Description:
      if (eeprom) return std::nullopt;
      return request::kWriteDescription;
    case PkwTarget::Text:
      if (eeprom) return std::nullopt;
      return request::kText;
  }
  return std::nullopt;
}

std::uint16_t make_ind(PkwTarget target, std::uint8_t index) noexcept {
  switch (target) {
    case PkwTarget::Value:
      return 0;  // C 4.2.2: bits 0..9 are 0 in all other cases
    case PkwTarget::ArrayElement:
    case PkwTarget::Description:
      return index;  // C 4.2.2 Tab. 4.4: y <= 254, 255 = all
    case PkwTarget::Text:
      return make_text_ind(index, false, false);
  }
  return 0;
}

std::uint16_t make_text_ind(std::uint8_t element, bool write, bool value_texts) noexcept {
  return static_cast<std::uint16_t>(element | (write ? kIndTextWrite : 0U) |
                                    (value_texts ? kIndValueTexts : 0U));
}

std::string_view to_string(ReplyClass cls) noexcept {
  switch (cls) {
    case ReplyClass::Matches:
      return "matches";
    case ReplyClass::Error:
      return "error";
    case ReplyClass::NoAuthority:
      return "no authority";
    case ReplyClass::Spontaneous:
      return "spontaneous";
    case ReplyClass::Unrelated:
      return "unrelated";
  }
  return "?";
}

bool request_uses_ind(std::uint8_t request_id) noexcept {
  switch (request_id) {  // footnote 1) of Tabelle 4.1
    case request::kReadDescription:
    case request::kWriteDescription:
    case request::kReadArray:
    case request::kWriteArrayWord:
    case request::kWriteArrayDword:
    case request::kEepromArrayDword:
    case request::kEepromArrayWord:
    case request::kText:
      return true;
    default:
      return false;
  }
}

bool is_change_request(const Pkw& request) noexcept {
  switch (request.id) {
    case request::kWriteWord:
    case request::kWriteDword:
    case request::kWriteDescription:
    case request::kWriteArrayWord:
    case request::kWriteArrayDword:
    case request::kEepromArrayDword:
    case request::kEepromArrayWord:
    case request::kEepromDword:
    case request::kEepromWord:
      return true;
    case request::kText:
      return (request.ind & kIndTextWrite) != 0;  // Tab. 4.5/4.6: bit 8 = write
    default:
      return false;
  }
}

std::array<std::uint8_t, 2> positive_reply_ids(std::uint8_t request_id) noexcept {
  if (request_id > kMaxId) return {kNoId, kNoId};
  return kPositiveReplies[request_id];
}

bool is_spontaneous(std::uint8_t reply_id) noexcept {
  return reply_id >= reply::kSpontaneousWord && reply_id <= reply::kSpontaneousArrayDword;
}

ReplyClass classify_reply(const Pkw& request, const Pkw& reply) noexcept {
  // C 4.2.1.2: a spontaneous report interrupts the normal request/reply sequence at any time.
  if (is_spontaneous(reply.id)) return ReplyClass::Spontaneous;
  // C 4.2.1.1: "Kein Auftrag" is answered with "Keine Antwort"; anything else is stale.
  if (request.id == request::kNone) {
    return reply.id == reply::kNone ? ReplyClass::Matches : ReplyClass::Unrelated;
  }
  // "Erkennung der Antwort ... durch die Auswertung der Antwortkennung, der Parameternummer
  // (PNU), gegebenenfalls durch den Wert in IND".
  const bool same_pnu = reply.pnu == request.pnu;
  const bool same_ind = !request_uses_ind(request.id) ||
                        (reply.ind & kIndCompareMask) == (request.ind & kIndCompareMask);
  if (!same_pnu || !same_ind) return ReplyClass::Unrelated;
  if (reply.id == reply::kError) return ReplyClass::Error;
  // "Besitzt der Auftraggeber nicht die PKW-Bedienhoheit, so werden alle Änderung- und
  // EEPROM-Aufträge ... mit der Kennung 'Keine PKW-Bedienhoheit' beantwortet. Alle
  // Lese-Aufträge werden bearbeitet": id 8 to a read is stale.
  if (reply.id == reply::kNoAuthority) {
    return is_change_request(request) ? ReplyClass::NoAuthority : ReplyClass::Unrelated;
  }
  for (std::uint8_t id : positive_reply_ids(request.id)) {
    if (id != kNoId && id == reply.id) return ReplyClass::Matches;
  }
  return ReplyClass::Unrelated;  // "Keine Antwort" (first contact) or an older request's reply
}

std::string_view request_name(std::uint8_t id) noexcept {
  return id <= kMaxId ? kRequestNames[id] : std::string_view{"invalid"};
}

std::string_view reply_name(std::uint8_t id) noexcept {
  return id <= kMaxId ? kReplyNames[id] : std::string_view{"invalid"};
}

std::string_view error_text(std::uint16_t error_number) noexcept {
  if (error_number < kErrorTexts.size()) return kErrorTexts[error_number];
  if (error_number < kReservedError) return "error defined by the drive profile";
  if (error_number == kReservedError) return "reserved";
  return "device-specific error";
}

void set_value(Pkw& pkw, PkwLength len, PkwWidth width, std::uint32_t v) noexcept {
  const bool dword = width == PkwWidth::Dword;
  switch (len) {
    case PkwLength::None:
      pkw.pwe_count = 0;
      return;
    case PkwLength::Four:
      // C 4.2.3 note: with PKW_ANZ = 4 a word travels in PWE2 and PWE1 is 0.
      pkw.pwe[0] = dword ? high_word(v) : std::uint16_t{0};
      pkw.pwe[1] = low_word(v);
      pkw.pwe_count = 2;
      return;
    case PkwLength::Three:
    case PkwLength::Variable:
      // C 4.2.3 note: with PKW_ANZ = 127 a word goes in PWE1, a double word in PWE1 (high)
      // and PWE2 (low).
      if (dword) {
        pkw.pwe[0] = high_word(v);
        pkw.pwe[1] = low_word(v);
        pkw.pwe_count = 2;
      } else {
        pkw.pwe[0] = low_word(v);
        pkw.pwe_count = 1;
      }
      return;
  }
}

std::uint32_t value(const Pkw& pkw, PkwLength len, PkwWidth width) noexcept {
  auto word = [&pkw](std::size_t i) -> std::uint16_t { return i < pkw.pwe_count ? pkw.pwe[i] : 0; };
  if (len == PkwLength::None) return 0;
  if (width == PkwWidth::Dword) return make_dword(word(0), word(1));
  return len == PkwLength::Four ? word(1) : word(0);
}

PkwWidth reply_width(std::uint8_t reply_id) noexcept {
  switch (reply_id) {
    case reply::kValueDword:
    case reply::kArrayDword:
    case reply::kSpontaneousDword:
    case reply::kSpontaneousArrayDword:
      return PkwWidth::Dword;
    default:
      return PkwWidth::Word;
  }
}

std::uint16_t error_number(const Pkw& reply, PkwLength len) noexcept {
  return static_cast<std::uint16_t>(value(reply, len, PkwWidth::Word));
}

std::size_t pkw_bytes(PkwLength len, const Pkw& pkw) noexcept {
  switch (len) {
    case PkwLength::None:
      return 0;
    case PkwLength::Three:
    case PkwLength::Four:
      return (kPkeIndWords + fixed_pwe_words(len)) * kWordBytes;
    case PkwLength::Variable: {
      const std::size_t m = std::clamp<std::size_t>(pkw.pwe_count, 1, kMaxPweWords);
      return (kPkeIndWords + m) * kWordBytes;
    }
  }
  return 0;
}

std::uint8_t fixed_lge(PkwLength len, std::uint8_t pzd_words) noexcept {
  if (len == PkwLength::Variable) return 0;
  const std::size_t n = pkw_bytes(len, Pkw{}) + std::size_t{pzd_words} * kWordBytes;
  return n > kMaxPayloadBytes ? std::uint8_t{0} : lge_for_payload(n);
}

std::size_t encode_payload(const Pkw& pkw, PkwLength len, std::span<const std::uint16_t> pzd,
                           std::span<std::uint8_t> out) noexcept {
  if (pzd.size() > kMaxPzdWords) return 0;
  std::size_t pwe_words = 0;
  if (len != PkwLength::None) {
    if (pkw.id > kMaxId || pkw.pnu > kMaxPnu || pkw.pwe_count > kMaxPweWords) return 0;
    if (len == PkwLength::Variable) {
      pwe_words = std::max<std::size_t>(pkw.pwe_count, 1);
    } else {
      pwe_words = fixed_pwe_words(len);
      if (pkw.pwe_count > pwe_words) return 0;  // C 7: the request does not fit the area
    }
  }
  const std::size_t size = pkw_bytes(len, pkw) + pzd.size() * kWordBytes;
  if (size > kMaxPayloadBytes || size > out.size()) return 0;
  std::uint8_t* at = out.data();
  if (len != PkwLength::None) {
    put_word(at, pkw.pke());
    put_word(at + 2, pkw.ind);
    at += kPkeIndWords * kWordBytes;
    for (std::size_t i = 0; i < pwe_words; ++i, at += kWordBytes) {
      put_word(at, i < pkw.pwe_count ? pkw.pwe[i] : std::uint16_t{0});
    }
  }
  for (std::uint16_t w : pzd) {
    put_word(at, w);
    at += kWordBytes;
  }
  return size;
}

bool decode_payload(std::span<const std::uint8_t> payload, PkwLength len, std::uint8_t pzd_words,
                    Pkw& pkw, std::span<std::uint16_t> pzd_out) noexcept {
  if (payload.size() % kWordBytes != 0 || pzd_words > kMaxPzdWords || pzd_out.size() < pzd_words) {
    return false;
  }
  const std::size_t pzd_bytes = std::size_t{pzd_words} * kWordBytes;
  if (payload.size() < pzd_bytes) return false;
  const std::size_t area = payload.size() - pzd_bytes;
  const std::size_t head = kPkeIndWords * kWordBytes;
  switch (len) {
    case PkwLength::None:
      if (area != 0) return false;
      break;
    case PkwLength::Three:
    case PkwLength::Four:
      if (area != (kPkeIndWords + fixed_pwe_words(len)) * kWordBytes) return false;
      break;
    case PkwLength::Variable:
      if (area < head || (area - head) / kWordBytes > kMaxPweWords) return false;
      break;
  }
  pkw = Pkw{};
  const std::uint8_t* at = payload.data();
  if (len != PkwLength::None) {
    pkw.set_pke(get_word(at));
    pkw.ind = get_word(at + 2);
    const std::size_t m = (area - head) / kWordBytes;
    for (std::size_t i = 0; i < m; ++i) pkw.pwe[i] = get_word(at + head + i * kWordBytes);
    pkw.pwe_count = static_cast<std::uint8_t>(m);
  }
  at += area;
  for (std::size_t i = 0; i < pzd_words; ++i) pzd_out[i] = get_word(at + i * kWordBytes);
  return true;
}

}  // namespace liftd::uss
