// The worked examples of C 8 and the broadcast appendix, byte for byte. Our copy of the spec lost
// the figures, so the telegrams are rebuilt from the descriptions; slave address 1 and the PZD
// contents (STW 047F, HSW 2000, ZSW 0737, HIW 2000) are our choice. Every BCC is worked out by
// hand in the comment (XOR of STX through the last payload byte, A 4.4), not by the code.
#include <gtest/gtest.h>

#include <array>
#include <vector>

#include "uss/pkw.hpp"
#include "uss/pzd.hpp"
#include "uss/receiver.hpp"
#include "uss/telegram.hpp"

namespace liftd::uss {
namespace {

using Bytes = std::vector<std::uint8_t>;

constexpr std::uint8_t kSlave = 1;
const std::array<std::uint16_t, 2> kStwHsw{0x047F, 0x2000};
const std::array<std::uint16_t, 2> kZswHiw{0x0737, 0x2000};

// Whole telegram from a PKW area and PZD words, through the codec under test.
Bytes build(std::uint8_t adr, const Pkw& pkw, PkwLength len, std::span<const std::uint16_t> pzd) {
  std::array<std::uint8_t, kMaxPayloadBytes> payload{};
  const std::size_t n = encode_payload(pkw, len, pzd, payload);
  EXPECT_NE(n, 0U);
  Bytes out(kMaxTelegramBytes);
  out.resize(encode_telegram(adr, {payload.data(), n}, out));
  return out;
}

// Receives a telegram through the receiver and takes its payload apart.
Pkw receive(const Bytes& bytes, PkwLength len, std::uint8_t pzd_words,
            std::array<std::uint16_t, 16>& pzd) {
  Receiver rx(38400);
  MonoTime at{};
  RxResult r;
  for (std::uint8_t b : bytes) {
    r = rx.feed(RxChar{b, LineError::None}, at);
    at += std::chrono::microseconds(287);
  }
  EXPECT_EQ(r.kind, RxResult::Kind::Complete);
  Pkw pkw;
  EXPECT_TRUE(decode_payload(rx.telegram().payload, len, pzd_words, pkw, pzd));
  return pkw;
}

TEST(UssExamples, Example1ProcessDataOnly) {
  // PKW_ANZ = 0, PZD_ANZ = 2: STW + HSW. LGE = 4 + 2 = 6.
  // BCC: 02^06=04 ^01=05 ^04=01 ^7F=7E ^20=5E ^00=5E.
  const Bytes request{0x02, 0x06, 0x01, 0x04, 0x7F, 0x20, 0x00, 0x5E};
  EXPECT_EQ(build(kSlave, Pkw{}, PkwLength::None, kStwHsw), request);
  // Reply ZSW + HIW. BCC: 02^06=04 ^01=05 ^07=02 ^37=35 ^20=15 ^00=15.
  const Bytes reply{0x02, 0x06, 0x01, 0x07, 0x37, 0x20, 0x00, 0x15};
  std::array<std::uint16_t, 16> pzd{};
  (void)receive(reply, PkwLength::None, 2, pzd);
  EXPECT_EQ(pzd[0], 0x0737);
  EXPECT_EQ(pzd[1], 0x2000);
}

TEST(UssExamples, Example2ReadParameter52) {
  // PKW_ANZ = 3, PZD_ANZ = 2; read the value of P52 (AK 1): PKE = 1034, IND = 0, PWE = x (0).
  // LGE = 10 + 2 = 12 (0C). BCC: 02^0C=0E ^01=0F ^10=1F ^34=2B ^04=2F ^7F=50 ^20=70.
  const Bytes request{0x02, 0x0C, 0x01, 0x10, 0x34, 0x00, 0x00,
                      0x00, 0x00, 0x04, 0x7F, 0x20, 0x00, 0x70};
  Pkw read;
  read.id = *read_request_id(PkwTarget::Value);
  read.pnu = 52;
  read.ind = make_ind(PkwTarget::Value, 0);
  EXPECT_EQ(build(kSlave, read, PkwLength::Three, kStwHsw), request);
  // Reply AK 1 (value word) PNU 52, value 4000 hex.
  // BCC: 02^0C=0E ^01=0F ^10=1F ^34=2B ^40=6B ^07=6C ^37=5B ^20=7B.
  const Bytes reply{0x02, 0x0C, 0x01, 0x10, 0x34, 0x00, 0x00,
                    0x40, 0x00, 0x07, 0x37, 0x20, 0x00, 0x7B};
  std::array<std::uint16_t, 16> pzd{};
  const Pkw got = receive(reply, PkwLength::Three, 2, pzd);
  EXPECT_EQ(classify_reply(read, got), ReplyClass::Matches);
  EXPECT_EQ(value(got, PkwLength::Three, reply_width(got.id)), 0x4000U);
  EXPECT_EQ(pzd[0], 0x0737);
}

TEST(UssExamples, Example3WholeDescriptionWithFixedLengthFails) {
  // As example 2, but the whole description of P52: AK 4, IND low byte 255 (C 4.2.2: needs
  // variable length, so the slave answers AK 7 with an error number; we take device-specific 101).
  // Request BCC: 02^0C=0E ^01=0F ^40=4F ^34=7B ^FF=84 ^04=80 ^7F=FF ^20=DF.
  const Bytes request{0x02, 0x0C, 0x01, 0x40, 0x34, 0x00, 0xFF,
                      0x00, 0x00, 0x04, 0x7F, 0x20, 0x00, 0xDF};
  Pkw read;
  read.id = *read_request_id(PkwTarget::Description);
  read.pnu = 52;
  read.ind = make_ind(PkwTarget::Description, kIndWhole);
  EXPECT_EQ(build(kSlave, read, PkwLength::Three, kStwHsw), request);
  // Reply PKE 7034, IND 00FF, PWE 0065 (101).
  // BCC: 02^0C=0E ^01=0F ^70=7F ^34=4B ^FF=B4 ^65=D1 ^07=D6 ^37=E1 ^20=C1.
  const Bytes reply{0x02, 0x0C, 0x01, 0x70, 0x34, 0x00, 0xFF,
                    0x00, 0x65, 0x07, 0x37, 0x20, 0x00, 0xC1};
  std::array<std::uint16_t, 16> pzd{};
  const Pkw got = receive(reply, PkwLength::Three, 2, pzd);
  EXPECT_EQ(classify_reply(read, got), ReplyClass::Error);
  EXPECT_EQ(error_number(got, PkwLength::Three), 101);
  EXPECT_EQ(error_text(101), "device-specific error");
}

TEST(UssExamples, Example4ReadDescriptionElement7) {
  // Element 7 ("lower limit") of the description of P52: AK 4, IND 7. Reply AK 3, value 5FFF.
  // Request BCC: 02^0C=0E ^01=0F ^40=4F ^34=7B ^07=7C ^04=78 ^7F=07 ^20=27.
  const Bytes request{0x02, 0x0C, 0x01, 0x40, 0x34, 0x00, 0x07,
                      0x00, 0x00, 0x04, 0x7F, 0x20, 0x00, 0x27};
  Pkw read;
  read.id = request::kReadDescription;
  read.pnu = 52;
  read.ind = make_ind(PkwTarget::Description, 7);
  EXPECT_EQ(build(kSlave, read, PkwLength::Three, kStwHsw), request);
  // Reply BCC: 02^0C=0E ^01=0F ^30=3F ^34=0B ^07=0C ^5F=53 ^FF=AC ^07=AB ^37=9C ^20=BC.
  const Bytes reply{0x02, 0x0C, 0x01, 0x30, 0x34, 0x00, 0x07,
                    0x5F, 0xFF, 0x07, 0x37, 0x20, 0x00, 0xBC};
  std::array<std::uint16_t, 16> pzd{};
  const Pkw got = receive(reply, PkwLength::Three, 2, pzd);
  EXPECT_EQ(got.id, reply::kDescription);
  EXPECT_EQ(classify_reply(read, got), ReplyClass::Matches);
  EXPECT_EQ(value(got, PkwLength::Three, PkwWidth::Word), 0x5FFFU);
}

TEST(UssExamples, Example5WriteDwordToArrayElement2OfP4) {
  // PKW_ANZ = 4, PZD_ANZ = 0: write 4000 0000 hex as double word to element 2 of P4: AK 8,
  // PKE 8004, IND 0002, PWE1 4000 (high word), PWE2 0000. LGE = 8 + 2 = 10 (0A).
  // BCC: 02^0A=08 ^01=09 ^80=89 ^04=8D ^02=8F ^40=CF.
  const Bytes request{0x02, 0x0A, 0x01, 0x80, 0x04, 0x00, 0x02, 0x40, 0x00, 0x00, 0x00, 0xCF};
  Pkw write;
  write.id = *write_request_id(PkwTarget::ArrayElement, PkwWidth::Dword, false);
  write.pnu = 4;
  write.ind = make_ind(PkwTarget::ArrayElement, 2);
  set_value(write, PkwLength::Four, PkwWidth::Dword, 0x40000000);
  EXPECT_EQ(build(kSlave, write, PkwLength::Four, {}), request);
  // Reply AK 5 (array double word), same IND and value. BCC: 02^0A=08 ^01=09 ^50=59 ^04=5D
  // ^02=5F ^40=1F.
  const Bytes reply{0x02, 0x0A, 0x01, 0x50, 0x04, 0x00, 0x02, 0x40, 0x00, 0x00, 0x00, 0x1F};
  std::array<std::uint16_t, 16> pzd{};
  const Pkw got = receive(reply, PkwLength::Four, 0, pzd);
  EXPECT_EQ(classify_reply(write, got), ReplyClass::Matches);
  EXPECT_EQ(value(got, PkwLength::Four, reply_width(got.id)), 0x40000000U);
  // A stale reply for element 1 is not ours.
  Pkw stale = got;
  stale.ind = 1;
  EXPECT_EQ(classify_reply(write, stale), ReplyClass::Unrelated);
}

TEST(UssExamples, Example6WordWithFourPkwWords) {
  // As example 5, write the word 7000 hex to P18 (AK 2, PKE 2012): the word travels in PWE2,
  // PWE1 = 0 (C 4.2.3). BCC: 02^0A=08 ^01=09 ^20=29 ^12=3B ^70=4B.
  const Bytes request{0x02, 0x0A, 0x01, 0x20, 0x12, 0x00, 0x00, 0x00, 0x00, 0x70, 0x00, 0x4B};
  Pkw write;
  write.id = *write_request_id(PkwTarget::Value, PkwWidth::Word, false);
  write.pnu = 18;
  set_value(write, PkwLength::Four, PkwWidth::Word, 0x7000);
  EXPECT_EQ(build(kSlave, write, PkwLength::Four, {}), request);
  // Reply AK 1 (value word) PKE 1012. BCC: 02^0A=08 ^01=09 ^10=19 ^12=0B ^70=7B.
  const Bytes reply{0x02, 0x0A, 0x01, 0x10, 0x12, 0x00, 0x00, 0x00, 0x00, 0x70, 0x00, 0x7B};
  std::array<std::uint16_t, 16> pzd{};
  const Pkw got = receive(reply, PkwLength::Four, 0, pzd);
  EXPECT_EQ(classify_reply(write, got), ReplyClass::Matches);
  EXPECT_EQ(value(got, PkwLength::Four, PkwWidth::Word), 0x7000U);
}

TEST(UssExamples, Example7ReadTextElement3OfP7VariableLength) {
  // PKW_ANZ = 127, PZD_ANZ = 0. Text of parameter value 2 of P7: element = value + 1 = 3, first
  // text field (IND bits 9 8 = 00): AK 15, PKE F007, IND 0003, PWE1 = x (0); "Minimum 3 Worte".
  // LGE = 6 + 2 = 8. BCC: 02^08=0A ^01=0B ^F0=FB ^07=FC ^03=FF.
  const Bytes request{0x02, 0x08, 0x01, 0xF0, 0x07, 0x00, 0x03, 0x00, 0x00, 0xFF};
  Pkw read;
  read.id = *read_request_id(PkwTarget::Text);
  read.pnu = 7;
  read.ind = make_ind(PkwTarget::Text, 3);
  EXPECT_EQ(build(kSlave, read, PkwLength::Variable, {}), request);
  // Reply: AK 15, IND 0003, PWE1..PWE8 = "300 BAUD" and 8 blanks (16 characters, sent in memory
  // order, C 6). LGE = 4 + 16 + 2 = 22 (16).
  // BCC: 02^16=14 ^01=15 ^F0=E5 ^07=E2 ^03=E1; the text: 33^30=03 ^30=33 ^20=13 ^42=51 ^41=10
  // ^55=45 ^44=01, 8 blanks cancel: 01; E1^01 = E0.
  const Bytes reply{0x02, 0x16, 0x01, 0xF0, 0x07, 0x00, 0x03, '3', '0', '0', ' ', 'B',
                    'A',  'U',  'D',  ' ',  ' ',  ' ',  ' ',  ' ', ' ', ' ', ' ', 0xE0};
  std::array<std::uint16_t, 16> pzd{};
  const Pkw got = receive(reply, PkwLength::Variable, 0, pzd);
  EXPECT_EQ(classify_reply(read, got), ReplyClass::Matches);
  ASSERT_EQ(got.pwe_count, 8);
  EXPECT_EQ(got.pwe[0], 0x3330);  // '3' '0'
  EXPECT_EQ(got.pwe[3], 0x5544);  // 'U' 'D'
  EXPECT_EQ(got.pwe[7], 0x2020);
}

TEST(UssExamples, BroadcastAppendixExamples) {
  // Appendix example 1: only the main setpoint (PZD2): word a = 0000 0000 0000 0101, b..d = 0.
  // Broadcast ADR = bit 5 (20). PKW 4 words + 2 PZD: LGE = 12 + 2 = 14 (0E).
  // BCC: 02^0E=0C ^20=2C ^05=29 ^04=2D ^7F=52 ^20=72.
  BroadcastEnable be1;
  be1.enable = true;
  be1.pzd_words = pzd_word_bit(2);
  Pkw pkw;
  encode_broadcast_enable(be1, pkw);
  const Bytes t1{0x02, 0x0E, 0x20, 0x00, 0x05, 0x00, 0x00, 0x00,
                 0x00, 0x00, 0x00, 0x04, 0x7F, 0x20, 0x00, 0x72};
  EXPECT_EQ(build(make_adr(0, TelegramType::Broadcast), pkw, PkwLength::Four, kStwHsw), t1);
  EXPECT_EQ(decode_broadcast_enable(pkw), be1);
  // Example 2: start all ramp generators: a = 0000 0000 0000 0011 (flag + PZD1), b = 0020
  // (control bit 5). BCC: 02^0E=0C ^20=2C ^03=2F ^20=0F ^04=0B ^7F=74 ^20=54.
  BroadcastEnable be2;
  be2.enable = true;
  be2.pzd_words = pzd_word_bit(1);
  be2.mask_pzd1 = 0x0020;
  encode_broadcast_enable(be2, pkw);
  const Bytes t2{0x02, 0x0E, 0x20, 0x00, 0x03, 0x00, 0x20, 0x00,
                 0x00, 0x00, 0x00, 0x04, 0x7F, 0x20, 0x00, 0x54};
  EXPECT_EQ(build(make_adr(0, TelegramType::Broadcast), pkw, PkwLength::Four, kStwHsw), t2);
  EXPECT_EQ(be2.word_a(), 0x0003);
}

}  // namespace
}  // namespace liftd::uss
