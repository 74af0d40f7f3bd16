// Table-driven tests of the DCP process frames against DCP 1.0.0.13 chapters 3 and 4.
#include "dcp/frame.hpp"

#include <gtest/gtest.h>

#include <vector>

namespace liftd::dcp {
namespace {

TEST(DcpChecksum, IsXorOfFirstFiveBytes) {
  // Legend: bytes 1..5 -> expected byte 6 (DCP 3.4).
  struct Case {
    std::array<std::uint8_t, 5> bytes;
    std::uint8_t expected;
  };
  const std::vector<Case> cases = {
      {{0x00, 0x00, 0x00, 0x00, 0x00}, 0x00},
      {{0x09, 0x00, 0x80, 0x02, 0x1C}, 0x97},
      {{0xFF, 0xFF, 0xFF, 0xFF, 0xFF}, 0xFF},
      {{0x01, 0x02, 0x04, 0x08, 0x10}, 0x1F},
  };
  for (const auto& c : cases) EXPECT_EQ(checksum(c.bytes), c.expected);
}

TEST(DcpMasterFrame, EncodesBytesInOrderWithChecksum) {
  MasterFrame f{0x05, 0x12, 0x34, 0x02, 0x1C};
  EXPECT_EQ(encode(f),
            (FrameBytes{0x05, 0x12, 0x34, 0x02, 0x1C, 0x05 ^ 0x12 ^ 0x34 ^ 0x02 ^ 0x1C}));
}

TEST(DcpSlaveFrame, RoundTripsAndRejectsBadChecksum) {
  SlaveFrame f{0x61, 0x80, 0x07, 0x49, 0x30};
  FrameBytes bytes = encode(f);
  auto decoded = decode_slave(bytes);
  ASSERT_TRUE(decoded.has_value());
  EXPECT_EQ(*decoded, f);
  for (std::size_t i = 0; i < kFrameSize; ++i) {
    FrameBytes corrupt = bytes;
    corrupt[i] ^= 0x10;  // any single flipped bit breaks an XOR checksum
    EXPECT_FALSE(decode_slave(corrupt).has_value()) << "byte " << i;
    EXPECT_FALSE(decode_master(corrupt).has_value()) << "byte " << i;
  }
}

TEST(DcpCommandByte, EveryBitHasItsName) {
  // Legend: bit mask -> the one Command field it sets (DCP 3.1).
  struct Case {
    std::uint8_t mask;
    bool Command::*field;
  };
  const std::vector<Case> cases = {
      {0x01, &Command::drive_enable},     {0x02, &Command::travel},
      {0x04, &Command::stop_switch},      {0x08, &Command::speed_data},
      {0x10, &Command::direction_down},   {0x20, &Command::speed_change},
      {0x40, &Command::desired_distance}, {0x80, &Command::reply_error},
  };
  for (const auto& c : cases) {
    Command cmd = Command::from_byte(c.mask);
    EXPECT_TRUE(cmd.*(c.field)) << int(c.mask);
    Command only{};
    only.*(c.field) = true;
    EXPECT_EQ(only, cmd);
    EXPECT_EQ(only.to_byte(), c.mask);
  }
}

TEST(DcpStatusByte, EveryBitHasItsName) {
  // Legend: bit mask -> the one Status field it sets (DCP 4.1).
  struct Case {
    std::uint8_t mask;
    bool Status::*field;
  };
  const std::vector<Case> cases = {
      {0x01, &Status::ready},           {0x02, &Status::travel_active},
      {0x04, &Status::advance_warning}, {0x08, &Status::general_fault},
      {0x10, &Status::below_levelling}, {0x20, &Status::accepted},
      {0x40, &Status::brake_open},      {0x80, &Status::message_error},
  };
  for (const auto& c : cases) {
    Status st = Status::from_byte(c.mask);
    EXPECT_TRUE(st.*(c.field)) << int(c.mask);
    Status only{};
    only.*(c.field) = true;
    EXPECT_EQ(only, st);
    EXPECT_EQ(only.to_byte(), c.mask);
  }
  for (int b = 0; b < 256; ++b) {
    EXPECT_EQ(Status::from_byte(static_cast<std::uint8_t>(b)).to_byte(), b);
    EXPECT_EQ(Command::from_byte(static_cast<std::uint8_t>(b)).to_byte(), b);
  }
}

TEST(DcpMessageType, ClassifiesEveryLowNibbleInBothDialects) {
  // Legend: command byte, dialect -> message type (DCP 3.5.1 and 3.5.2 tables).
  struct Case {
    std::uint8_t command;
    Protocol protocol;
    MessageType expected;
  };
  const std::vector<Case> cases = {
      {0x00, Protocol::Dcp3, MessageType::Idle},
      {0x01, Protocol::Dcp3, MessageType::Stop},
      {0x03, Protocol::Dcp3, MessageType::Relevelling},
      {0x05, Protocol::Dcp3, MessageType::DistanceOrDecel},
      {0x07, Protocol::Dcp3, MessageType::Travel},
      {0x09, Protocol::Dcp3, MessageType::Speed},
      {0x0F, Protocol::Dcp3, MessageType::SpeedAfterFastStart},
      {0x0D, Protocol::Dcp3, MessageType::Invalid},  // 1101 is DCP4's code only
      {0x0D, Protocol::Dcp4, MessageType::SpeedAfterFastStart},
      {0x0F, Protocol::Dcp4, MessageType::Invalid},  // 1111 is DCP3's code only
      {0x05, Protocol::Dcp4, MessageType::DistanceOrDecel},
      {0x02, Protocol::Dcp4, MessageType::Invalid},
      {0x04, Protocol::Dcp4, MessageType::Invalid},
      {0x06, Protocol::Dcp4, MessageType::Invalid},
      {0x08, Protocol::Dcp4, MessageType::Invalid},
      {0x0A, Protocol::Dcp4, MessageType::Invalid},
      {0x0B, Protocol::Dcp4, MessageType::Invalid},
      {0x0C, Protocol::Dcp4, MessageType::Invalid},
      {0x0E, Protocol::Dcp4, MessageType::Invalid},
      // B4 (direction), B5 (speed change) and B7 (reply error) do not change the type.
      {0x95, Protocol::Dcp4, MessageType::DistanceOrDecel},
      {0xB9, Protocol::Dcp3, MessageType::Speed},
      // B6 is 0 in every message of both tables.
      {0x45, Protocol::Dcp4, MessageType::Invalid},
  };
  for (const auto& c : cases) {
    EXPECT_EQ(classify_command(c.command, c.protocol), c.expected)
        << "command 0x" << std::hex << int(c.command);
  }
}

TEST(DcpMessageType, NibbleRoundTrips) {
  for (Protocol p : {Protocol::Dcp3, Protocol::Dcp4}) {
    for (MessageType t : {MessageType::Idle, MessageType::Stop, MessageType::Relevelling,
                          MessageType::DistanceOrDecel, MessageType::Travel, MessageType::Speed,
                          MessageType::SpeedAfterFastStart}) {
      EXPECT_EQ(classify_command(command_nibble(t, p), p), t) << to_string(t);
    }
  }
  EXPECT_EQ(command_nibble(MessageType::SpeedAfterFastStart, Protocol::Dcp3), 0x0F);
  EXPECT_EQ(command_nibble(MessageType::SpeedAfterFastStart, Protocol::Dcp4), 0x0D);
}

TEST(DcpDistanceModeTracker, MessageAfterSpeedDecidesMeaningOf0101) {
  using M = DistanceModeTracker::Meaning;
  DistanceModeTracker remaining;
  EXPECT_EQ(remaining.meaning(), M::Undecided);
  remaining.observe(MessageType::Speed);
  remaining.observe(MessageType::DistanceOrDecel);
  EXPECT_EQ(remaining.meaning(), M::RemainingDistance);
  remaining.observe(MessageType::DistanceOrDecel);
  EXPECT_EQ(remaining.meaning(), M::RemainingDistance);

  DistanceModeTracker decel;
  decel.observe(MessageType::Speed);
  decel.observe(MessageType::Travel);
  decel.observe(MessageType::DistanceOrDecel);
  EXPECT_EQ(decel.meaning(), M::Deceleration);
  // A later travel that starts with 0101 after its speed message switches the meaning back.
  decel.observe(MessageType::Idle);
  decel.observe(MessageType::Speed);
  decel.observe(MessageType::DistanceOrDecel);
  EXPECT_EQ(decel.meaning(), M::RemainingDistance);
}

TEST(DcpSpeed, WordsAreSingleBitsG0ToG10) {
  // Legend: speed -> bit number in the data word (DCP 3.5.3.7), data1 = high byte.
  struct Case {
    Speed speed;
    int bit;
    std::string_view name;
  };
  const std::vector<Case> cases = {
      {Speed::V0, 0, "V0"}, {Speed::VN, 1, "VN"}, {Speed::VF, 2, "VF"},  {Speed::V1, 3, "V1"},
      {Speed::VI, 4, "VI"}, {Speed::V2, 5, "V2"}, {Speed::V3, 6, "V3"},  {Speed::V4, 7, "V4"},
      {Speed::V5, 8, "V5"}, {Speed::V6, 9, "V6"}, {Speed::V7, 10, "V7"},
  };
  for (const auto& c : cases) {
    EXPECT_EQ(speed_word(c.speed), 1U << c.bit);
    EXPECT_EQ(speed_from_word(static_cast<std::uint16_t>(1U << c.bit)), c.speed);
    EXPECT_EQ(to_string(c.speed), c.name);
    EXPECT_EQ(speed_from_string(c.name), c.speed);
  }
  MasterFrame f;
  f.set_data_word(speed_word(Speed::V7));
  EXPECT_EQ(f.data1, 0x04);  // G10 lives in the high byte
  EXPECT_EQ(f.data2, 0x00);
}

TEST(DcpSpeed, RejectsNoneSeveralOrUndefinedBits) {
  for (int w : {0x0000, 0x00C0, 0x0800, 0x8000, 0x0101, 0xFFFF}) {
    EXPECT_FALSE(speed_from_word(static_cast<std::uint16_t>(w)).has_value()) << w;
  }
  EXPECT_FALSE(speed_from_string("V8").has_value());
  EXPECT_FALSE(speed_from_string("v4").has_value());
}

TEST(DcpSpeed, Dcp4HasNoIntermediateSpeeds) {
  for (Speed s : {Speed::V1, Speed::V2, Speed::V5, Speed::V6, Speed::V7}) {
    EXPECT_FALSE(speed_allowed(s, Protocol::Dcp4)) << to_string(s);
    EXPECT_TRUE(speed_allowed(s, Protocol::Dcp3)) << to_string(s);
  }
  for (Speed s : {Speed::V0, Speed::VN, Speed::VF, Speed::VI, Speed::V3, Speed::V4}) {
    EXPECT_TRUE(speed_allowed(s, Protocol::Dcp4)) << to_string(s);
  }
  EXPECT_FALSE(speed_allowed(Speed::V4, Protocol::ComChan));
}

TEST(DcpSpeed, Dcp3SpeedTableByInstallationSpeedCount) {
  // DCP 3.5.3.7: 1 speed V4; 2 V4 V3; ... 7 adds V7, V6, V5.
  EXPECT_TRUE(dcp3_travel_speeds(0).empty());
  EXPECT_TRUE(dcp3_travel_speeds(8).empty());
  auto seven = dcp3_travel_speeds(7);
  const std::vector<Speed> expected = {Speed::V4, Speed::V3, Speed::V2, Speed::V1,
                                       Speed::V7, Speed::V6, Speed::V5};
  EXPECT_EQ(std::vector<Speed>(seven.begin(), seven.end()), expected);
  for (int n = 1; n <= 7; ++n) {
    auto s = dcp3_travel_speeds(n);
    EXPECT_EQ(s.size(), static_cast<std::size_t>(n));
    EXPECT_EQ(s.front(), Speed::V4);
  }
}

TEST(DcpRemainingDistance, ClampsPerWidth) {
  // Legend: mm, width -> data word (DCP 3.5.3.4).
  struct Case {
    std::int64_t mm;
    DistanceWidth width;
    std::uint16_t word;
  };
  const std::vector<Case> cases = {
      {-5, DistanceWidth::Bits15, 0x0000},  // level passed: 0
      {0, DistanceWidth::Bits15, 0x0000},      {1234, DistanceWidth::Bits15, 1234},
      {0x7FFE, DistanceWidth::Bits15, 0x7FFE}, {0x7FFF, DistanceWidth::Bits15, 0x7FFF},
      {40000, DistanceWidth::Bits15, 0x7FFF},  {40000, DistanceWidth::Bits16, 40000},
      {70000, DistanceWidth::Bits16, 0xFFFF},  {-1, DistanceWidth::Bits16, 0x0000},
  };
  for (const auto& c : cases) EXPECT_EQ(remaining_distance_word(c.mm, c.width), c.word) << c.mm;
}

TEST(DcpDriveData, DecodesEveryDataInformationType) {
  // Legend: word, data-information-type -> kind, distance, saturated, or rejected.
  using K = DriveData::Kind;
  struct Case {
    std::uint16_t word;
    DataInfoType type;
    bool ok;
    K kind;
    std::uint32_t distance;
    bool saturated;
  };
  const std::vector<Case> cases = {
      {0x0123, DataInfoType::Alternating, true, K::DecelerationDistance, 0x0123, false},
      {0x7FFF, DataInfoType::Alternating, true, K::DecelerationDistance, 0x7FFF, true},
      {0x8001, DataInfoType::Alternating, true, K::ExtendedStatus, 0, false},
      {0x0456, DataInfoType::Decel15, true, K::DecelerationDistance, 0x0456, false},
      {0x8456, DataInfoType::Decel15, false, K::DecelerationDistance, 0, false},
      {0x8000, DataInfoType::Extended, true, K::ExtendedStatus, 0, false},
      {0x0000, DataInfoType::Extended, false, K::ExtendedStatus, 0, false},
      {0x9234, DataInfoType::Decel16, true, K::DecelerationDistance, 0x9234, false},
      {0xFFFF, DataInfoType::Decel16, true, K::DecelerationDistance, 0xFFFF, true},
      {0x8000, DataInfoType::ExtendedDist16, true, K::ExtendedStatus, 0, false},
      {0x7000, DataInfoType::ExtendedDist16, false, K::ExtendedStatus, 0, false},
  };
  for (const auto& c : cases) {
    DriveDataError err{};
    auto d = decode_drive_data(c.word, c.type, &err);
    ASSERT_EQ(d.has_value(), c.ok) << std::hex << c.word << " type " << char(c.type);
    if (!c.ok) continue;
    EXPECT_EQ(d->kind, c.kind);
    if (c.kind == K::DecelerationDistance) {
      EXPECT_EQ(d->deceleration_distance_mm, c.distance);
      EXPECT_EQ(d->saturated, c.saturated);
    }
  }
  DriveDataError err{};
  decode_drive_data(0x8000, DataInfoType::Decel15, &err);
  EXPECT_EQ(err, DriveDataError::ExpectedDistance);
  decode_drive_data(0x0000, DataInfoType::Extended, &err);
  EXPECT_EQ(err, DriveDataError::ExpectedExtended);
}

TEST(DcpDriveData, ExtendedStatusBitsByName) {
  // Legend: bit number -> field (DCP 4.2.1.1).
  struct Case {
    int bit;
    bool ExtendedStatus::*field;
  };
  const std::vector<Case> cases = {
      {0, &ExtendedStatus::below_unlocking_speed},
      {1, &ExtendedStatus::below_border_speed},
      {2, &ExtendedStatus::below_overspeed},
      {9, &ExtendedStatus::emergency_reduced_voltage},
      {10, &ExtendedStatus::emergency_direction_down},
      {11, &ExtendedStatus::motor_temperature_limit},
      {12, &ExtendedStatus::drive_temperature_limit},
  };
  for (const auto& c : cases) {
    const auto word = static_cast<std::uint16_t>(0x8000U | (1U << c.bit));
    auto s = ExtendedStatus::from_word(word);
    ASSERT_TRUE(s.has_value());
    ExtendedStatus only{};
    only.*(c.field) = true;
    EXPECT_EQ(*s, only) << c.bit;
    EXPECT_EQ(only.to_word(), word);
  }
  auto weight = ExtendedStatus::from_word(0x81F0);
  ASSERT_TRUE(weight.has_value());
  EXPECT_EQ(weight->weight_bits, 0x1F);
  EXPECT_FALSE(ExtendedStatus::from_word(0x7FFF).has_value());
}

TEST(DcpDriveData, DecelerationDistanceEncodingSaturates) {
  EXPECT_EQ(encode_deceleration_distance(1430, DistanceWidth::Bits15), 1430);
  EXPECT_EQ(encode_deceleration_distance(50000, DistanceWidth::Bits15), 0x7FFF);
  EXPECT_EQ(encode_deceleration_distance(50000, DistanceWidth::Bits16), 50000);
  EXPECT_EQ(encode_deceleration_distance(70000, DistanceWidth::Bits16), 0xFFFF);
}

TEST(DcpDataInfoType, ParsesOnlyZeroToFourAndPicksWidth) {
  for (char c : {'0', '1', '2', '3', '4'}) EXPECT_TRUE(data_info_type_from_char(c).has_value());
  for (char c : {'5', '/', 'a', '\0'}) EXPECT_FALSE(data_info_type_from_char(c).has_value());
  EXPECT_EQ(remaining_distance_width(DataInfoType::Alternating), DistanceWidth::Bits15);
  EXPECT_EQ(remaining_distance_width(DataInfoType::Decel15), DistanceWidth::Bits15);
  EXPECT_EQ(remaining_distance_width(DataInfoType::Extended), DistanceWidth::Bits15);
  EXPECT_EQ(remaining_distance_width(DataInfoType::Decel16), DistanceWidth::Bits16);
  EXPECT_EQ(remaining_distance_width(DataInfoType::ExtendedDist16), DistanceWidth::Bits16);
}

}  // namespace
}  // namespace liftd::dcp
