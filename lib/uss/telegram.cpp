#include "uss/telegram.hpp"

namespace liftd::uss {
namespace {

// A 4.3 Tabelle 4.1 / A 5.4 Tabelle 5.2: bits 7, 6, 5 of ADR.
constexpr std::uint8_t kTypeMask = kAdrSpecial | kAdrMirror | kAdrBroadcast;

}  // namespace

std::uint8_t make_adr(std::uint8_t slave, TelegramType type) noexcept {
  const auto address = static_cast<std::uint8_t>(slave & kAdrAddressMask);
  std::uint8_t bits = 0;
  switch (type) {
    case TelegramType::Normal:
      bits = 0;
      break;
    case TelegramType::Mirror:
      bits = kAdrMirror;
      break;
    case TelegramType::Broadcast:
      bits = kAdrBroadcast;
      break;
    case TelegramType::Special:
      bits = kAdrSpecial;
      break;
    case TelegramType::SpecialBroadcast:
      bits = kAdrSpecial | kAdrBroadcast;
      break;
    case TelegramType::Undefined:
      bits = kAdrMirror | kAdrBroadcast;  // 011: not in Tabelle 4.1
      break;
  }
  return static_cast<std::uint8_t>(address | bits);
}

AddressByte parse_adr(std::uint8_t adr) noexcept {
  AddressByte out;
  out.slave = static_cast<std::uint8_t>(adr & kAdrAddressMask);
  switch (adr & kTypeMask) {
    case 0:
      out.type = TelegramType::Normal;
      break;
    case kAdrMirror:
      out.type = TelegramType::Mirror;
      break;
    case kAdrBroadcast:
      out.type = TelegramType::Broadcast;
      break;
    case kAdrSpecial:
      out.type = TelegramType::Special;
      break;
    case kAdrSpecial | kAdrBroadcast:
      out.type = TelegramType::SpecialBroadcast;
      break;
    default:  // 011 (mirror + broadcast), 110, 111: A 5.4 "Spiegeltelegramm ist nur mit Bit 7=0
              // möglich"; undefined combinations lead to no reaction.
      out.type = TelegramType::Undefined;
      break;
  }
  return out;
}

std::uint8_t block_check(std::span<const std::uint8_t> bytes) noexcept {
  std::uint8_t bcc = 0;  // A 4.4: BCC = 0 before STX
  for (std::uint8_t b : bytes) bcc = static_cast<std::uint8_t>(bcc ^ b);
  return bcc;
}

std::size_t encode_telegram(std::uint8_t adr, std::span<const std::uint8_t> payload,
                            std::span<std::uint8_t> out) noexcept {
  if (payload.size() > kMaxPayloadBytes) return 0;
  const std::size_t total = telegram_bytes(payload.size());
  if (out.size() < total) return 0;
  out[0] = kStx;
  out[1] = lge_for_payload(payload.size());
  out[2] = adr;
  for (std::size_t i = 0; i < payload.size(); ++i) out[3 + i] = payload[i];
  out[total - 1] = block_check(out.first(total - 1));
  return total;
}

std::optional<Telegram> decode_telegram(std::span<const std::uint8_t> bytes,
                                        DecodeError* error) noexcept {
  auto fail = [error](DecodeError e) -> std::optional<Telegram> {
    if (error != nullptr) *error = e;
    return std::nullopt;
  };
  if (bytes.size() < telegram_bytes(0)) return fail(DecodeError::TooShort);
  if (bytes[0] != kStx) return fail(DecodeError::NoStx);
  const std::uint8_t lge = bytes[1];
  if (lge < kMinLge || lge > kMaxLge) return fail(DecodeError::BadLge);
  if (bytes.size() != static_cast<std::size_t>(lge) + 2) return fail(DecodeError::LengthMismatch);
  if (block_check(bytes.first(bytes.size() - 1)) != bytes.back()) return fail(DecodeError::Bcc);
  return Telegram{bytes[2], bytes.subspan(3, static_cast<std::size_t>(lge) - 2)};
}

}  // namespace liftd::uss
