// The SCH001 card's frames bit by bit, as its document ("CAN Kommunikation mit Steuerung") lays
// them out: identifiers from P479/P480 (1.6, 2), the 0x61 status frame (3b), our 0x68 answer
// (3c), the timeout commands and their acknowledgements (3f).
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "sch001/protocol.hpp"

namespace liftd::sch001 {
namespace {

std::vector<std::uint8_t> bytes_of(const can::Frame& f) {
  return {f.bytes().begin(), f.bytes().end()};
}

TEST(Sch001Ids, FromTheCardParameters) {
  struct Case {
    std::uint32_t p479, p480, to_card, from_card;
  };
  for (const Case& c : {
           Case{0, 49, 0x551, 0x581},      // 2.1: P479 = 0 is base 0x550; 1.6: 0x551 / 0x581
           Case{0x550, 49, 0x551, 0x581},  // the same base given explicitly
           Case{0x300, 49, 0x301, 0x331},  // another base: both move with it
           Case{0x100, 2, 0x101, 0x102},   // the lowest usable node offset
           Case{0, 95, 0x551, 0x5AF},      // the last of the 96 reserved identifiers (0x5AF)
           Case{0x7A0, 49, 0x7A1, 0x7D1},  // the highest base whose block ends at 0x7FF
       }) {
    std::string why;
    const auto ids = ids_for(c.p479, c.p480, &why);
    ASSERT_TRUE(ids) << std::hex << c.p479 << " " << std::dec << c.p480 << ": " << why;
    EXPECT_EQ(ids->to_card, c.to_card);
    EXPECT_EQ(ids->from_card, c.from_card);
  }
}

TEST(Sch001Ids, RefusesWhatCannotWork) {
  struct Case {
    std::uint32_t p479, p480;
    const char* why;
  };
  for (const Case& c :
       {Case{0, 0, "P480 = 0 makes the card ignore every command"}, Case{0, 1, "must be 2..95"},
        Case{0, 96, "must be 2..95"}, Case{0x7A1, 49, "within 0x7FF"}}) {
    std::string why;
    EXPECT_FALSE(ids_for(c.p479, c.p480, &why)) << c.p479 << " " << c.p480;
    EXPECT_NE(why.find(c.why), std::string::npos) << why;
  }
}

TEST(Sch001StatusFrame, EveryBitHasItsName) {
  // 3b: MSB first ERR PNP2 AVV T1 P1 P2 RDY PNP1.
  struct Case {
    int bit;
    bool CardStatus::*member;
  };
  const std::vector<Case> cases = {
      {7, &CardStatus::err}, {6, &CardStatus::pnp2}, {5, &CardStatus::avv}, {4, &CardStatus::t1},
      {3, &CardStatus::p1},  {2, &CardStatus::p2},   {1, &CardStatus::rdy}, {0, &CardStatus::pnp1}};
  for (const Case& c : cases) {
    const auto byte = static_cast<std::uint8_t>(1U << c.bit);
    const auto decoded =
        decode_card_frame(can::make_frame(0x581, std::vector<std::uint8_t>{0x61, byte}));
    const auto* status = std::get_if<StatusFrame>(&decoded);
    ASSERT_NE(status, nullptr) << "bit " << c.bit;
    for (const Case& other : cases) {
      EXPECT_EQ(status->status.*(other.member), other.bit == c.bit)
          << "bit " << c.bit << " read as bit " << other.bit;
    }
    EXPECT_EQ(status->status.to_byte(), byte);
  }
}

TEST(Sch001CardFrames, TimeoutCommandsAndRejections) {
  using Bytes = std::vector<std::uint8_t>;
  const auto decode = [](const Bytes& b) { return decode_card_frame(can::make_frame(0x581, b)); };
  EXPECT_TRUE(std::get<TimeoutCommand>(decode({0x52})).enable);
  EXPECT_FALSE(std::get<TimeoutCommand>(decode({0x5A})).enable);
  // The document gives the timeout commands no length: the first byte decides.
  EXPECT_TRUE(std::get<TimeoutCommand>(decode({0x52, 0x00})).enable);
  struct Case {
    Bytes bytes;
    Rejection why;
  };
  for (const Case& c : {Case{{}, Rejection::WrongLength}, Case{{0x61}, Rejection::WrongLength},
                        Case{{0x61, 0x02, 0x00}, Rejection::WrongLength},
                        Case{{0x68, 0x01, 0x00, 0x00}, Rejection::UnknownFirstByte},
                        Case{{0x65}, Rejection::UnknownFirstByte},
                        Case{{0x00, 0x00}, Rejection::UnknownFirstByte}}) {
    const auto decoded = decode(c.bytes);
    ASSERT_TRUE(std::holds_alternative<Rejection>(decoded)) << c.bytes.size();
    EXPECT_EQ(std::get<Rejection>(decoded), c.why) << to_string(c.why);
  }
}

TEST(Sch001CommandFrame, EveryBitHasItsPlace) {
  // 3c: MSB first SP3 SP2 SP1 SFY MSP HSP DW UP.
  const std::vector<std::pair<int, bool CommandBits::*>> cases = {
      {7, &CommandBits::sp3}, {6, &CommandBits::sp2}, {5, &CommandBits::sp1},
      {4, &CommandBits::sfy}, {3, &CommandBits::msp}, {2, &CommandBits::hsp},
      {1, &CommandBits::dw},  {0, &CommandBits::up}};
  const Ids ids;
  for (const auto& [bit, member] : cases) {
    Command c;
    c.bits.*member = true;
    c.current_floor = 2;
    c.destination_floor = 5;
    const can::Frame f = encode_command(ids, c);
    EXPECT_EQ(f.id, 0x551U);
    EXPECT_EQ(bytes_of(f),
              (std::vector<std::uint8_t>{0x68, static_cast<std::uint8_t>(1U << bit), 2, 5}))
        << "bit " << bit;
    EXPECT_EQ(CommandBits::from_byte(static_cast<std::uint8_t>(1U << bit)), c.bits);
  }
}

TEST(Sch001CommandFrame, FastUpToTheTopFloor) {
  // Up at fast speed with the motors on, from floor 0 to floor 3: SFY HSP UP = 0x15.
  Command c;
  c.bits.up = c.bits.hsp = c.bits.sfy = true;
  c.destination_floor = 3;
  EXPECT_EQ(bytes_of(encode_command(*ids_for(0x300, 49), c)),
            (std::vector<std::uint8_t>{0x68, 0x15, 0x00, 0x03}));
  EXPECT_EQ(encode_command(*ids_for(0x300, 49), c).id, 0x301U);
}

TEST(Sch001CommandFrame, TimeoutAcknowledgements) {
  const Ids ids;
  EXPECT_EQ(bytes_of(encode_timeout_ack(ids, true)), (std::vector<std::uint8_t>{0x65}));
  EXPECT_EQ(bytes_of(encode_timeout_ack(ids, false)), (std::vector<std::uint8_t>{0x6B}));
  EXPECT_EQ(encode_timeout_ack(ids, true).id, 0x551U);
}

}  // namespace
}  // namespace liftd::sch001
