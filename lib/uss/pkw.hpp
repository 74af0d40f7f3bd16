// The PKW (parameter id value) area of the USS payload (spec chapter C 4): PKE (AK, toggle bit,
// PNU), IND, PWE; the request and reply ids, which reply belongs to which request, the error
// numbers, spontaneous reports; and the payload codec PKW + PZD (C 2). Pure code.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>

namespace liftd::uss {

/// PKW_ANZ (C 3, C 4.1): no PKW area, fixed 3 or 4 words, or variable length (127).
enum class PkwLength : std::uint8_t { None = 0, Three = 3, Four = 4, Variable = 127 };
/// C 4.1.2: at most m = 124 PWE words (no PZD; 108 with 16 PZD words).
inline constexpr std::size_t kMaxPweWords = 124;

/// One PKW area, request or reply.
struct Pkw {
  std::uint8_t id = 0;         ///< AK 0..15 (request or reply id), PKE bits 12..15
  bool toggle = false;         ///< PKE bit 11 (spontaneous-report toggle, C 4.2.1.2)
  std::uint16_t pnu = 0;       ///< PKE bits 0..10 (C 4.2.1.3)
  std::uint16_t ind = 0;       ///< IND word as on the wire (C 4.2.2)
  std::uint8_t pwe_count = 0;  ///< PWE words in use
  std::array<std::uint16_t, kMaxPweWords> pwe{};
  /// PKE as on the wire: AK << 12 | toggle << 11 | PNU (PNU masked to 11 bits, AK to 4).
  std::uint16_t pke() const noexcept;
  /// Sets id, toggle and pnu from a PKE word.
  void set_pke(std::uint16_t pke) noexcept;
  std::span<const std::uint16_t> pwe_words() const noexcept { return {pwe.data(), pwe_count}; }
  bool operator==(const Pkw& o) const noexcept;
};

/// PKE fields (C 4.2.1).
inline constexpr unsigned kAkShift = 12;
inline constexpr std::uint16_t kToggleBit = 1U << 11;
inline constexpr std::uint16_t kPnuMask = 0x07FF;
inline constexpr std::uint16_t kMaxPnu = 0x07FF;

/// Request ids AK, master -> slave (C 4.2.1.1 Tabelle 4.1).
namespace request {
inline constexpr std::uint8_t kNone = 0;               ///< no request
inline constexpr std::uint8_t kReadValue = 1;          ///< request PWE
inline constexpr std::uint8_t kWriteWord = 2;          ///< change PWE (word)
inline constexpr std::uint8_t kWriteDword = 3;         ///< change PWE (double word)
inline constexpr std::uint8_t kReadDescription = 4;    ///< request PBE element (IND)
inline constexpr std::uint8_t kWriteDescription = 5;   ///< change PBE element (IND)
inline constexpr std::uint8_t kReadArray = 6;          ///< request PWE (array, IND)
inline constexpr std::uint8_t kWriteArrayWord = 7;     ///< change PWE (array word)
inline constexpr std::uint8_t kWriteArrayDword = 8;    ///< change PWE (array double word)
inline constexpr std::uint8_t kReadArrayCount = 9;     ///< request number of array elements
inline constexpr std::uint8_t kReserved10 = 10;        ///< reserved
inline constexpr std::uint8_t kEepromArrayDword = 11;  ///< change PWE (array dword) + EEPROM
inline constexpr std::uint8_t kEepromArrayWord = 12;   ///< change PWE (array word) + EEPROM
inline constexpr std::uint8_t kEepromDword = 13;       ///< change PWE (dword) + EEPROM
inline constexpr std::uint8_t kEepromWord = 14;        ///< change PWE (word) + EEPROM
inline constexpr std::uint8_t kText = 15;              ///< request or change text (IND bit 8)
}  // namespace request

/// Reply ids AK, slave -> master (C 4.2.1.1 Tabelle 4.2).
namespace reply {
inline constexpr std::uint8_t kNone = 0;               ///< no reply
inline constexpr std::uint8_t kValueWord = 1;          ///< transfer PWE (word)
inline constexpr std::uint8_t kValueDword = 2;         ///< transfer PWE (double word)
inline constexpr std::uint8_t kDescription = 3;        ///< transfer PBE element
inline constexpr std::uint8_t kArrayWord = 4;          ///< transfer PWE (array word)
inline constexpr std::uint8_t kArrayDword = 5;         ///< transfer PWE (array double word)
inline constexpr std::uint8_t kArrayCount = 6;         ///< transfer number of array elements
inline constexpr std::uint8_t kError = 7;              ///< request cannot be executed (PWE = error)
inline constexpr std::uint8_t kNoAuthority = 8;        ///< no PKW authority (C 4.2.1.1)
inline constexpr std::uint8_t kSpontaneousWord = 9;    ///< spontaneous report (word)
inline constexpr std::uint8_t kSpontaneousDword = 10;  ///< spontaneous report (double word)
inline constexpr std::uint8_t kSpontaneousArrayWord = 11;   ///< spontaneous report (array word)
inline constexpr std::uint8_t kSpontaneousArrayDword = 12;  ///< spontaneous report (array dword)
inline constexpr std::uint8_t kReserved13 = 13;
inline constexpr std::uint8_t kReserved14 = 14;
inline constexpr std::uint8_t kText = 15;  ///< transfer text
}  // namespace reply

/// What a request addresses.
enum class PkwTarget : std::uint8_t {
  Value,         ///< the parameter value (IND = 0)
  ArrayElement,  ///< one element of an array parameter (IND low byte = element, 255 = all)
  Description,   ///< a parameter description element (IND low byte = element, 255 = all)
  Text,          ///< a text element (IND low byte 1..254, IND bits 8/9, C 4.2.2)
};
/// Word (16 bit) or double word (32 bit) value.
enum class PkwWidth : std::uint8_t { Word, Dword };

/// The read request id for a target: 1, 6, 4, 15.
std::optional<std::uint8_t> read_request_id(PkwTarget target) noexcept;
/// The change request id (C 4.2.1.1): Value 2/3 (EEPROM 14/13), ArrayElement 7/8 (EEPROM
/// 12/11), Description 5, Text 15 (set IND bit 8 with make_text_ind). nullopt where the spec has
/// no such request (EEPROM for descriptions and texts).
std::optional<std::uint8_t> write_request_id(PkwTarget target, PkwWidth width,
                                             bool eeprom) noexcept;

// ---- IND (C 4.2.2) ----
/// IND low byte 255: the whole array or the whole description (needs PKW_ANZ = 127).
inline constexpr std::uint8_t kIndWhole = 255;
/// IND bit 8 with request id 15: write the text element instead of reading it (Tab. 4.5/4.6).
inline constexpr std::uint16_t kIndTextWrite = 1U << 8;
/// IND bit 9 with request id 15: the second text field of an array parameter, one text per
/// parameter value, element y = parameter value + 1 (SIMOVERT Master Drives, Tab. 4.6).
inline constexpr std::uint16_t kIndValueTexts = 1U << 9;
/// IND bits 10..15: device-specific; 0 for devices without a meaning for them (Tab. 4.7).
inline constexpr std::uint16_t kIndDeviceMask = 0xFC00;

/// The IND word for a target (C 4.2.2): Value -> 0 (bits 0..9 are 0 in all other cases);
/// ArrayElement / Description -> the element number in the low byte (255 = all; the spec calls
/// it "the y-th place": the number is passed unchanged, many drives count from 0); Text -> a
/// read of text element `index` (1..254) of the first text field (bits 8/9 = 0).
std::uint16_t make_ind(PkwTarget target, std::uint8_t index) noexcept;
/// IND for request id 15 (Tab. 4.5/4.6): element 1..254, bit 8 = write, bit 9 = value texts of
/// an array parameter.
std::uint16_t make_text_ind(std::uint8_t element, bool write, bool value_texts = false) noexcept;
/// IND low byte (the element / array place).
constexpr std::uint8_t ind_element(std::uint16_t ind) noexcept {
  return static_cast<std::uint8_t>(ind & 0xFF);
}

// ---- request / reply relation (C 4.2.1.1 Tabelle 4.3) ----

/// How a reply relates to the outstanding request.
enum class ReplyClass : std::uint8_t {
  Matches,      ///< a positive reply to this request (AK of Tab. 4.3, same PNU, same IND)
  Error,        ///< reply id 7 for this PNU (and IND): PWE1 carries the error number
  NoAuthority,  ///< reply id 8 to a change or EEPROM request for this PNU
  Spontaneous,  ///< reply id 9..12: a spontaneous report, whatever was asked (C 4.2.1.2)
  Unrelated,    ///< anything else: a stale reply to an older request, "no reply", reserved ids
};
std::string_view to_string(ReplyClass cls) noexcept;

/// Whether the request id carries its meaning in IND (footnote 1 of Tab. 4.1: 4..8, 11, 12, 15).
bool request_uses_ind(std::uint8_t request_id) noexcept;
/// Whether the request changes something (change and EEPROM requests, and 15 with IND bit 8):
/// those are refused with "no PKW authority"; reads are always processed (C 4.2.1.1).
bool is_change_request(const Pkw& request) noexcept;
/// The positive reply ids for a request id (Tab. 4.3): up to two, 0xFF for an unused slot.
/// Request 10 (reserved) has none ("Auftrag nicht ausführbar").
std::array<std::uint8_t, 2> positive_reply_ids(std::uint8_t request_id) noexcept;

/// Classifies a reply against the outstanding request (C 4.2.1.1 "Erkennung der Antwort": reply
/// id, PNU and, for the requests of footnote 1, IND; C 4.2.1.2 for spontaneous reports).
/// IND is compared in bits 0..9 (element and text bits), the device bits 10..15 are ignored.
/// For "no request" (0) the matching reply is "no reply" (0), whatever its PNU. The value is
/// not compared (a slave repeats replies with the current value).
ReplyClass classify_reply(const Pkw& request, const Pkw& reply) noexcept;
/// Reply ids 9..12 (C 4.2.1.2).
bool is_spontaneous(std::uint8_t reply_id) noexcept;

/// English names of request and reply ids ("read value", ...); "reserved" for 10, 13, 14,
/// "invalid" above 15.
std::string_view request_name(std::uint8_t id) noexcept;
std::string_view reply_name(std::uint8_t id) noexcept;
/// The meaning of an error number in PWE1 of a reply id 7 (C 4.2.1.1, numbers 0..7; 8..99
/// come from the drive profile, 100 is reserved, above 100 device-specific).
std::string_view error_text(std::uint16_t error_number) noexcept;

// ---- PWE (C 4.2.3) ----

/// Stores a value in pkw.pwe (C 4.2.3 and its note): a word goes into PWE1 with 3 words or
/// variable length, into PWE2 with PWE1 = 0 with 4 words; a double word goes into PWE1 (high
/// word) and PWE2 (low word). None stores nothing (pwe_count 0). A double word with Three sets
/// two PWE words, which encode_payload then refuses (C 7: a double word needs PKW_ANZ = 4).
void set_value(Pkw& pkw, PkwLength len, PkwWidth width, std::uint32_t value) noexcept;
/// Reads a value back by the same rules (missing words read as 0).
std::uint32_t value(const Pkw& pkw, PkwLength len, PkwWidth width) noexcept;
/// The width of the value a reply id carries: double word for 2, 5, 10, 12, else word.
PkwWidth reply_width(std::uint8_t reply_id) noexcept;
/// The error number of an error reply (id 7): the word in PWE1 (variable and 3 words) or in
/// PWE2 (4 words, word sizes travel in PWE2).
std::uint16_t error_number(const Pkw& reply, PkwLength len) noexcept;

// ---- payload codec (C 2: PKW area then PZD area; C 6: words high byte first) ----

/// Bytes of the PKW area: 0, 6, 8, or 2 * (2 + max(1, pwe_count)) for variable length (the
/// variable area has at least PKE, IND, PWE1, C 7 example).
std::size_t pkw_bytes(PkwLength len, const Pkw& pkw) noexcept;
/// The LGE every telegram of a slave carries with a fixed PKW length and pzd_words PZD words
/// (A 4.2: LGE = n + 2, C 7: request and reply have the same length); 0 for variable length,
/// ready for Receiver::set_expected_lge (0 = any valid LGE). E.g. Three + 2 PZD -> 12.
std::uint8_t fixed_lge(PkwLength len, std::uint8_t pzd_words) noexcept;
/// PKE IND PWE... then the PZD words into out; returns the payload size, 0 = does not fit
/// (out too small, more PWE words than a fixed length holds, AK > 15, PNU > 2047, more than 16
/// PZD words, or more than 252 bytes). Unused PWE words of a fixed area are sent as 0.
std::size_t encode_payload(const Pkw& pkw, PkwLength len, std::span<const std::uint16_t> pzd,
                           std::span<std::uint8_t> out) noexcept;
/// Takes a payload apart: the PKW area of the given length (variable: everything before the
/// last 2 * pzd_words bytes, at least PKE and IND) and pzd_words words into pzd_out. false if
/// the size does not fit the lengths, is odd, or pzd_out is too small.
bool decode_payload(std::span<const std::uint8_t> payload, PkwLength len, std::uint8_t pzd_words,
                    Pkw& pkw, std::span<std::uint16_t> pzd_out) noexcept;

}  // namespace liftd::uss
