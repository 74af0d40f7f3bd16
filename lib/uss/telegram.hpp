// USS telegram layer (USS spec chapter A 4): the frame STX LGE ADR payload BCC, the address byte,
// the block check and the big-endian word order. Pure code: no I/O, no clock, no allocation.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>

namespace liftd::uss {

/// A 4.1: every telegram starts with STX = 02 hex.
inline constexpr std::uint8_t kStx = 0x02;
/// A 4.2: "Die maximale Gesamtlänge eines Telegramms ist 256 Byte."
inline constexpr std::size_t kMaxTelegramBytes = 256;
/// A 4.2: at most n = 252 payload bytes per telegram.
inline constexpr std::size_t kMaxPayloadBytes = 252;
/// C 2: at most 16 PZD words per telegram.
inline constexpr std::size_t kMaxPzdWords = 16;
/// A 4.3 / A 1: addresses 0..31 in ADR bits 0..4.
inline constexpr std::uint8_t kMaxSlaveAddress = 31;
/// A 4.2: LGE = n + 2 (ADR and BCC are counted, STX and LGE are not). The spec writes
/// "1 <= LGE <= 254", but with n >= 0 the smallest possible LGE is 2 (ADR and BCC only).
inline constexpr std::uint8_t kMinLge = 2;
/// A 4.2: LGE <= 254, i.e. n <= 252 and at most 256 bytes in all.
inline constexpr std::uint8_t kMaxLge = 254;
/// STX, LGE, ADR and BCC around the payload (A 4, Bild 4.1).
inline constexpr std::size_t kFrameOverheadBytes = 4;

/// ADR bits 7, 6, 5 (A 4.3 Tabelle 4.1 and A 5.4 Tabelle 5.2).
enum class TelegramType : std::uint8_t {
  Normal,            ///< 000: normal data exchange, address evaluated
  Mirror,            ///< 010: the addressed slave sends the telegram back unchanged (A 5.3)
  Broadcast,         ///< 001: all slaves take it, none answers, address not evaluated (A 3)
  Special,           ///< 100: special telegram for the addressed slave (A 5.4)
  SpecialBroadcast,  ///< 101: special telegram to every slave that handles them, no answer
  Undefined,         ///< 011, 110, 111: masters must not send, slaves must not react (A 4.3)
};

/// ADR bit masks (A 4.3).
inline constexpr std::uint8_t kAdrAddressMask = 0x1F;  ///< bits 0..4: slave address
inline constexpr std::uint8_t kAdrBroadcast = 0x20;    ///< bit 5
inline constexpr std::uint8_t kAdrMirror = 0x40;       ///< bit 6
inline constexpr std::uint8_t kAdrSpecial = 0x80;      ///< bit 7

/// The address byte for a slave (only bits 0..4 are used) and a telegram type (A 4.3).
/// Undefined gives bits 6 and 5 set (011), a combination nobody may react to.
std::uint8_t make_adr(std::uint8_t slave, TelegramType type) noexcept;

/// An address byte taken apart.
struct AddressByte {
  std::uint8_t slave = 0;  ///< bits 0..4 (meaningless for the broadcast types)
  TelegramType type = TelegramType::Normal;
  bool operator==(const AddressByte&) const = default;
};
/// A 4.3 / A 5.4: bits 0..4 address, bits 7/6/5 the telegram type.
AddressByte parse_adr(std::uint8_t adr) noexcept;

/// A 4.4: XOR of all bytes (BCC starts at 0 before STX). For a telegram pass STX through the
/// last payload byte; the result is the BCC.
std::uint8_t block_check(std::span<const std::uint8_t> bytes) noexcept;

/// Bytes on the wire for a payload of `payload_bytes` (A 4.2: LGE + 2).
constexpr std::size_t telegram_bytes(std::size_t payload_bytes) noexcept {
  return payload_bytes + kFrameOverheadBytes;
}
/// LGE for a payload of n bytes (A 4.2: LGE = n + 2). Only meaningful for n <= 252.
constexpr std::uint8_t lge_for_payload(std::size_t payload_bytes) noexcept {
  return static_cast<std::uint8_t>(payload_bytes + 2);
}

/// STX LGE ADR payload BCC into out; returns payload.size()+4, or 0 if the payload is longer
/// than 252 bytes or out is too small.
std::size_t encode_telegram(std::uint8_t adr, std::span<const std::uint8_t> payload,
                            std::span<std::uint8_t> out) noexcept;

/// A received telegram: its address byte and a view of its payload (n bytes, A 4.2).
struct Telegram {
  std::uint8_t adr = 0;
  std::span<const std::uint8_t> payload;
};

/// Why decode_telegram refused a buffer.
enum class DecodeError : std::uint8_t { TooShort, NoStx, BadLge, LengthMismatch, Bcc };

/// Checks one whole telegram held in `bytes` (exactly STX..BCC, no timing): STX, LGE in 2..254
/// and equal to bytes.size() - 2, BCC. The payload views `bytes`. For streams with timing use
/// Receiver (receiver.hpp).
std::optional<Telegram> decode_telegram(std::span<const std::uint8_t> bytes,
                                        DecodeError* error = nullptr) noexcept;

// ---- big-endian words (A 4: high byte first; double words: high word first) ----

/// Writes a word high byte first (A 4, C 6).
constexpr void put_word(std::uint8_t* at, std::uint16_t word) noexcept {
  at[0] = static_cast<std::uint8_t>(word >> 8);
  at[1] = static_cast<std::uint8_t>(word & 0xFF);
}
/// Same, into a two-byte span.
constexpr void put_word(std::span<std::uint8_t, 2> at, std::uint16_t word) noexcept {
  put_word(at.data(), word);
}
/// Reads a word, high byte first.
constexpr std::uint16_t get_word(const std::uint8_t* at) noexcept {
  return static_cast<std::uint16_t>((at[0] << 8) | at[1]);
}
/// Writes a double word: high word first, each word high byte first (A 4, C 6).
constexpr void put_dword(std::uint8_t* at, std::uint32_t dword) noexcept {
  put_word(at, static_cast<std::uint16_t>(dword >> 16));
  put_word(at + 2, static_cast<std::uint16_t>(dword & 0xFFFF));
}
/// Reads a double word, high word first.
constexpr std::uint32_t get_dword(const std::uint8_t* at) noexcept {
  return (static_cast<std::uint32_t>(get_word(at)) << 16) | get_word(at + 2);
}
/// The high and low word of a double word (C 4.2.3: PWE1 = high word, PWE2 = low word).
constexpr std::uint16_t high_word(std::uint32_t dword) noexcept {
  return static_cast<std::uint16_t>(dword >> 16);
}
constexpr std::uint16_t low_word(std::uint32_t dword) noexcept {
  return static_cast<std::uint16_t>(dword & 0xFFFF);
}
constexpr std::uint32_t make_dword(std::uint16_t high, std::uint16_t low) noexcept {
  return (static_cast<std::uint32_t>(high) << 16) | low;
}

}  // namespace liftd::uss
