// USS telegram layer (A 4): the address byte of Tabelle 4.1 / 5.2, the BCC rule of A 4.4 with its
// own worked example, LGE limits of A 4.2, big-endian words (A 4, C 6).
#include <gtest/gtest.h>

#include <array>
#include <vector>

#include "uss/telegram.hpp"

namespace liftd::uss {
namespace {

TEST(UssAdr, EveryTypeBothWays) {
  struct Case {
    std::uint8_t slave;
    TelegramType type;
    std::uint8_t adr;
  };
  for (const Case& c : {
           Case{0, TelegramType::Normal, 0x00},            // 000: normal, address 0
           Case{31, TelegramType::Normal, 0x1F},           // highest address, bits 0..4
           Case{5, TelegramType::Mirror, 0x45},            // 010: bit 6
           Case{0, TelegramType::Broadcast, 0x20},         // 001: bit 5
           Case{7, TelegramType::Special, 0x87},           // 100: bit 7
           Case{3, TelegramType::SpecialBroadcast, 0xA3},  // 101: bits 7 and 5
           Case{0, TelegramType::Undefined, 0x60},         // 011: not in Tabelle 4.1
       }) {
    EXPECT_EQ(make_adr(c.slave, c.type), c.adr) << int(c.adr);
    const AddressByte parsed = parse_adr(c.adr);
    EXPECT_EQ(parsed.slave, c.slave);
    EXPECT_EQ(parsed.type, c.type);
  }
  // Only bits 0..4 of the slave number are used.
  EXPECT_EQ(make_adr(0x3F, TelegramType::Normal), 0x1F);
}

TEST(UssAdr, UndefinedCombinations) {
  // A 4.3 / A 5.4: bit 7 with bit 6 (110, 111) and mirror with broadcast (011) are undefined:
  // "Nicht definierte Kombinationen dürfen ... zu keiner Reaktion führen".
  for (int adr_value : {0x60, 0x7F, 0xC0, 0xC5, 0xE0, 0xFF}) {
    const auto adr = static_cast<std::uint8_t>(adr_value);
    EXPECT_EQ(parse_adr(adr).type, TelegramType::Undefined) << int(adr);
  }
  EXPECT_EQ(parse_adr(0xE5).slave, 5);
}

TEST(UssBcc, WorkedExampleOfA44) {
  // A 4.4: BCC starts at 0; after STX it is 0000 0010; EXOR the second character 1101 0110
  // gives 1101 0100.
  const std::array<std::uint8_t, 1> first{0x02};
  EXPECT_EQ(block_check(first), 0x02);
  const std::array<std::uint8_t, 2> two{0x02, 0xD6};
  EXPECT_EQ(block_check(two), 0xD4);
  EXPECT_EQ(block_check({}), 0x00);
}

TEST(UssTelegram, EncodeByHand) {
  // Payload 04 7F 20 00 to slave 1: LGE = n + 2 = 6. BCC by hand:
  // 02^06=04, ^01=05, ^04=01, ^7F=7E, ^20=5E, ^00=5E.
  const std::vector<std::uint8_t> payload{0x04, 0x7F, 0x20, 0x00};
  std::array<std::uint8_t, 16> out{};
  ASSERT_EQ(encode_telegram(0x01, payload, out), 8U);
  const std::array<std::uint8_t, 8> expected{0x02, 0x06, 0x01, 0x04, 0x7F, 0x20, 0x00, 0x5E};
  EXPECT_TRUE(std::equal(expected.begin(), expected.end(), out.begin()));
}

TEST(UssTelegram, EmptyPayloadIsLge2) {
  // A 4.2: LGE counts ADR and BCC, so an empty payload has LGE 2; BCC = 02^02^05 = 05.
  std::array<std::uint8_t, 4> out{};
  ASSERT_EQ(encode_telegram(0x05, {}, out), 4U);
  EXPECT_EQ(out, (std::array<std::uint8_t, 4>{0x02, 0x02, 0x05, 0x05}));
}

TEST(UssTelegram, LengthLimits) {
  // A 4.2: at most 252 payload bytes, 256 bytes in all, LGE 254.
  std::vector<std::uint8_t> payload(252, 0xAA);
  std::vector<std::uint8_t> out(256);
  ASSERT_EQ(encode_telegram(0x00, payload, out), 256U);
  EXPECT_EQ(out[1], 254);
  // BCC: 02 ^ FE ^ 00 ^ (252 x AA: even count -> 0) = FC
  EXPECT_EQ(out[255], 0xFC);
  payload.push_back(0xAA);
  EXPECT_EQ(encode_telegram(0x00, payload, out), 0U);  // 253 bytes: too long
  payload.pop_back();
  std::vector<std::uint8_t> small(255);
  EXPECT_EQ(encode_telegram(0x00, payload, small), 0U);  // out too small
  EXPECT_EQ(telegram_bytes(252), kMaxTelegramBytes);
  EXPECT_EQ(lge_for_payload(252), kMaxLge);
}

TEST(UssTelegram, DecodeWholeBuffer) {
  const std::array<std::uint8_t, 8> good{0x02, 0x06, 0x01, 0x04, 0x7F, 0x20, 0x00, 0x5E};
  auto t = decode_telegram(good);
  ASSERT_TRUE(t);
  EXPECT_EQ(t->adr, 0x01);
  ASSERT_EQ(t->payload.size(), 4U);
  EXPECT_EQ(t->payload[1], 0x7F);

  struct Case {
    std::vector<std::uint8_t> bytes;
    DecodeError error;
  };
  for (const Case& c : {
           Case{{0x02, 0x02, 0x01}, DecodeError::TooShort},
           Case{{0x03, 0x06, 0x01, 0x04, 0x7F, 0x20, 0x00, 0x5E}, DecodeError::NoStx},
           Case{{0x02, 0x01, 0x01, 0x02}, DecodeError::BadLge},
           Case{{0x02, 0x07, 0x01, 0x04, 0x7F, 0x20, 0x00, 0x5E}, DecodeError::LengthMismatch},
           Case{{0x02, 0x06, 0x01, 0x04, 0x7F, 0x20, 0x00, 0x5F}, DecodeError::Bcc},
       }) {
    DecodeError e{};
    EXPECT_FALSE(decode_telegram(c.bytes, &e));
    EXPECT_EQ(e, c.error);
  }
}

TEST(UssWords, BigEndian) {
  // A 4: "stets zuerst das High-Byte ... dann das Low-Byte"; double words high word first.
  std::array<std::uint8_t, 6> b{};
  put_word(b.data(), 0x1234);
  put_dword(b.data() + 2, 0x40000001);
  EXPECT_EQ(b, (std::array<std::uint8_t, 6>{0x12, 0x34, 0x40, 0x00, 0x00, 0x01}));
  EXPECT_EQ(get_word(b.data()), 0x1234);
  EXPECT_EQ(get_dword(b.data() + 2), 0x40000001U);
  put_word(std::span<std::uint8_t, 2>(b.data(), 2), 0xBEEF);
  EXPECT_EQ(b[0], 0xBE);
  EXPECT_EQ(b[1], 0xEF);
  EXPECT_EQ(high_word(0x40000001), 0x4000);
  EXPECT_EQ(low_word(0x40000001), 0x0001);
  EXPECT_EQ(make_dword(0x4000, 0x0001), 0x40000001U);
}

}  // namespace
}  // namespace liftd::uss
