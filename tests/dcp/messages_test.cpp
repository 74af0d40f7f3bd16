// Expanded I-messages (DCP 5.12), keypad frames (DCP 5.8) and drive error texts (DCP 5.11):
// every message byte for byte against the spec layout, both directions, and every malformed
// variant rejected with its reason.
#include "dcp/messages.hpp"

#include <gtest/gtest.h>

#include <string>

#include "dcp/dcp_test_util.hpp"

namespace liftd::dcp {
namespace {

using test::bytes;

std::string text(const Payload& p) {
  return {p.data.begin(), p.data.begin() + static_cast<long>(p.length)};
}

TEST(DcpMessages, FirstCharacterIsCapitalIHex49) {
  // DCP 5.6.4: 'I' is 0x49 (the tables print a lower-case L, which is 0x6C).
  EXPECT_EQ(kInternalCommand, 0x49);
  auto p = encode(MasterMessage{LoadRequest{0}});
  ASSERT_TRUE(p.ok());
  EXPECT_EQ(p.value.data[0], 0x49);
  EXPECT_EQ(decode_drive_message(bytes("l8")).error, MessageError::NotInternal);
}

TEST(DcpMessages, EncodesEveryMasterMessageByteForByte) {
  // Legend: message from the lift controller -> the characters between 0x1C and ETX.
  struct Case {
    const char* what;
    MasterMessage message;
    std::string expected;
  };
  const std::vector<Case> cases = {
      {"I0: maker BP, version 12.34, date 24.12.14, language DE (5.12.2.1)",
       InitRequest{{'B', 'P'}, 1234, {24, 12, 14}, {'D', 'E'}}, "I0BP1234241214DE"},
      {"I0: version 0.05 keeps its leading zeros",
       InitRequest{{'S', 'T'}, 5, {1, 1, 0}, {'E', 'N'}}, "I0ST0005010100EN"},
      {"I1: extended protocol, data-information-type '3' (5.12.3.1)",
       DataInfoRequest{true, DataInfoType::Decel16}, "I113"},
      {"I1: base protocol, type '0'", DataInfoRequest{false, DataInfoType::Alternating}, "I100"},
      {"I2: trip/fault reset, reserve '0' (5.12.4.1)", SwitchRequest{SwitchFunction::Reset},
       "I20R"},
      {"I2: maximum torque", SwitchRequest{SwitchFunction::MaxTorque}, "I201"},
      {"I2: cancel", SwitchRequest{SwitchFunction::None}, "I200"},
      {"I3: 22.11.2026 03:04:05 as DDMMYYYYHHMMSS (5.12.5.1)",
       DateTimeRequest{{2026, 11, 22, 3, 4, 5}}, "I322112026030405"},
      {"I6: emergency supply, saving mode 2 (5.12.6.1)",
       PowerRequest{PowerSupply::Emergency, EnergySaving::Mode2}, "I6U2"},
      {"I6: mains, no saving", PowerRequest{PowerSupply::Mains, EnergySaving::Off}, "I6N0"},
      {"I7: V4, 1000 cm as five BCD digits (5.12.7.1)", StartParamsRequest{MaxSpeed::V4, 1000},
       "I7201000"},
      {"I7: V3, 300 cm", StartParamsRequest{MaxSpeed::V3, 300}, "I7100300"},
      {"I8: 25 % load as three digits (5.12.8.1)", LoadRequest{25}, "I8025"},
      {"I8: 100 % load", LoadRequest{100}, "I8100"},
      {"I9: +12345 mm as sign and six digits (5.12.9.1)", PositionRequest{12345}, "I9+012345"},
      {"I9: -50 mm (below the lowest level)", PositionRequest{-50}, "I9-000050"},
      {"I9: invalid position", PositionRequest{std::nullopt}, "I9E000000"},
  };
  for (const auto& c : cases) {
    const auto encoded = encode(c.message);
    ASSERT_TRUE(encoded.ok()) << c.what << ": " << to_string(encoded.error);
    EXPECT_EQ(text(encoded.value), c.expected) << c.what;
    const auto decoded = decode_master_message(encoded.value.bytes());
    ASSERT_TRUE(decoded.ok()) << c.what << ": " << to_string(decoded.error);
    EXPECT_EQ(decoded.value, c.message) << c.what;
  }
}

TEST(DcpMessages, EncodesAndDecodesEveryDriveReply) {
  // Legend: reply from the drive <-> the characters between 0x1C and ETX.
  struct Case {
    const char* what;
    DriveMessage message;
    std::string wire;
  };
  const std::vector<Case> cases = {
      {"I0 reply: Ziehl-Abegg, 1.02, 01.02.15, DCP4, DE; DCP type before the language (5.12.2.2)",
       InitReply{{'Z', 'A'}, 102, {1, 2, 15}, Protocol::Dcp4, {'D', 'E'}},
       "I0ZA0102010215"
       "4DE"},
      {"I0 reply: DCP3 drive",
       InitReply{{'K', 'W'}, 9999, {31, 12, 99}, Protocol::Dcp3, {'E', 'N'}},
       "I0KW9999311299"
       "3EN"},
      {"I0 reply: communication channel only",
       InitReply{{'Y', 'E'}, 0, {29, 2, 24}, Protocol::ComChan, {'F', 'R'}},
       "I0YE0000290224"
       "0FR"},
      {"I1 reply: base protocol (5.12.3.2)", DataInfoReply{false}, "I1"},
      {"I1 reply: extended protocol supported", DataInfoReply{true}, "I11"},
      {"I2 reply: reset follows within 1000 ms", SwitchReply{SwitchFunction::Reset}, "I20R"},
      {"I2 reply: no function active", SwitchReply{SwitchFunction::None}, "I200"},
      {"I3 reply", DateTimeReply{}, "I3"},
      {"I6 reply: mains, no saving", PowerReply{PowerSupply::Mains, EnergySaving::Off}, "I6N0"},
      {"I6 reply: emergency, mode 1", PowerReply{PowerSupply::Emergency, EnergySaving::Mode1},
       "I6U1"},
      {"I7 reply, spec example: 300 cm at V4 is short, Sg 300 cm, Sv 143 cm (11.1.2.1)",
       StartParamsReply{TravelKind::Short, 300, 143}, "I7s0030000143"},
      {"I7 reply, spec example: 1000 cm at V4 is long, Sg 520 cm, Sv 250 cm",
       StartParamsReply{TravelKind::Long, 520, 250}, "I7l0052000250"},
      {"I8 reply", LoadReply{}, "I8"},
      {"I9 base reply (5.12.9.2)", PositionReply{false, 0}, "I9"},
      {"I9 extended reply: 1234 mm up", PositionReply{true, 1234}, "I9+001234"},
      {"I9 extended reply: 987 mm down", PositionReply{true, -987}, "I9-000987"},
      {"I9 extended reply: invalid measurement", PositionReply{true, std::nullopt}, "I9E000000"},
  };
  for (const auto& c : cases) {
    const auto encoded = encode(c.message);
    ASSERT_TRUE(encoded.ok()) << c.what;
    EXPECT_EQ(text(encoded.value), c.wire) << c.what;
    const auto decoded = decode_drive_message(bytes(c.wire));
    ASSERT_TRUE(decoded.ok()) << c.what << ": " << to_string(decoded.error) << " at "
                              << decoded.offset;
    EXPECT_EQ(decoded.value, c.message) << c.what;
    EXPECT_EQ(message_id(decoded.value), message_id(c.message));
  }
}

struct BadCase {
  const char* what;
  std::string payload;
  MessageError error;
  std::size_t offset;
};

TEST(DcpMessages, RejectsMalformedDriveReplies) {
  // Legend: what is wrong -> payload from the drive -> the reason and the offending offset.
  const std::string i0 =
      "I0ZA0102010215"
      "4DE";
  auto with = [&](std::size_t at, char c) {
    std::string s = i0;
    s[at] = c;
    return s;
  };
  const std::vector<BadCase> cases = {
      {"nothing at all", "", MessageError::Empty, 0},
      {"first character not 'I'", "X3", MessageError::NotInternal, 0},
      {"lower-case L as printed in the tables", "l3", MessageError::NotInternal, 0},
      {"only the 'I'", "I", MessageError::WrongLength, 0},
      {"I4 is not defined", "I4", MessageError::UnknownId, 1},
      {"I5 is not defined", "I5", MessageError::UnknownId, 1},
      {"letter instead of a number", "IA", MessageError::UnknownId, 1},
      {"I0 reply without its DCP type", i0.substr(0, 14), MessageError::WrongLength, 0},
      {"I0 request layout (no DCP type) as reply", "I0ZA0102010215DE", MessageError::BadDcpType,
       14},
      {"I0 DCP type '2'", with(14, '2'), MessageError::BadDcpType, 14},
      {"I0 DCP type 'A'", with(14, 'A'), MessageError::BadDcpType, 14},
      {"I0 with a control character", with(9, '\x05'), MessageError::NotDataChar, 9},
      {"I1 reply with '2'", "I12", MessageError::BadProtocolType, 2},
      {"I1 reply too long", "I110", MessageError::WrongLength, 0},
      {"I2 reply without reserve", "I2R", MessageError::WrongLength, 0},
      {"I2 reply with function 'X'", "I20X", MessageError::BadSwitchFunction, 3},
      {"I2 reply with lower-case 'r'", "I20r", MessageError::BadSwitchFunction, 3},
      {"I3 reply with a date", "I322112026030405", MessageError::WrongLength, 0},
      {"I6 reply supply 'X'", "I6X0", MessageError::BadPowerSupply, 2},
      {"I6 reply saving '3'", "I6N3", MessageError::BadEnergySaving, 3},
      {"I6 reply too short", "I6N", MessageError::WrongLength, 0},
      {"I7 reply travel type 'x'", "I7x0030000143", MessageError::BadTravelKind, 2},
      {"I7 reply travel type capital 'L'", "I7L0030000143", MessageError::BadTravelKind, 2},
      {"I7 reply Sv with a letter", "I7s00300001X3", MessageError::BadDigit, 11},
      {"I7 reply one digit short", "I7s003000014", MessageError::WrongLength, 0},
      {"I8 reply with a value", "I8025", MessageError::WrongLength, 0},
      {"I9 reply sign '*'", "I9*001234", MessageError::BadSign, 2},
      {"I9 reply sign lower-case 'e'", "I9e001234", MessageError::BadSign, 2},
      {"I9 reply five digits", "I9+00123", MessageError::WrongLength, 0},
      {"I9 reply digit 'O'", "I9+0O1234", MessageError::BadDigit, 4},
      {"I9 reply with 'E' and non-digits", "I9E      ", MessageError::BadDigit, 3},
      {"I9 reply with a control character", "I9\x05", MessageError::NotDataChar, 2},
  };
  for (const auto& c : cases) {
    const auto decoded = decode_drive_message(bytes(c.payload));
    EXPECT_EQ(decoded.error, c.error) << c.what << ": got " << to_string(decoded.error);
    EXPECT_EQ(decoded.offset, c.offset) << c.what;
    EXPECT_FALSE(to_string(decoded.error).empty());
  }
}

TEST(DcpMessages, InitReplyToleratesOddFieldsWhileItsDcpTypeIsReadable) {
  // Issue: older and other drives fill the I0 fields their own way; only the DCP type character
  // (DCP 5.12.2.2) decides. Each odd field is accepted and flagged, never refused.
  const std::string i0 =
      "I0ZA0102010215"
      "4DE";
  auto with = [&](std::size_t at, char c) {
    std::string s = i0;
    s[at] = c;
    return s;
  };
  struct Case {
    std::string what;
    std::string payload;
    std::uint8_t anomalies;
    Protocol dcp_type;
  };
  const std::vector<Case> cases = {
      {"as defined", i0, 0, Protocol::Dcp4},
      {"one character short (no second language letter)", i0.substr(0, 16),
       init_anomaly::kLength | init_anomaly::kLanguage, Protocol::Dcp4},
      {"one character long", i0 + "X", init_anomaly::kLength, Protocol::Dcp4},
      {"without a language", i0.substr(0, 15), init_anomaly::kLength | init_anomaly::kLanguage,
       Protocol::Dcp4},
      {"maker in lower case", with(2, 'z'), init_anomaly::kMaker, Protocol::Dcp4},
      {"maker with a digit", with(3, '1'), init_anomaly::kMaker, Protocol::Dcp4},
      {"version with a letter", with(6, 'A'), init_anomaly::kVersion, Protocol::Dcp4},
      {"version 1.00 with a point",
       "I0ZA1.00010215"
       "3DE",
       init_anomaly::kVersion, Protocol::Dcp3},
      {"date with day 32",
       "I0ZA0102320215"
       "4DE",
       init_anomaly::kDate, Protocol::Dcp4},
      {"date 000000",
       "I0ZA0102000000"
       "0DE",
       init_anomaly::kDate, Protocol::ComChan},
      {"date 29.02.23 (no leap year)",
       "I0ZA0102290223"
       "4DE",
       init_anomaly::kDate, Protocol::Dcp4},
      {"language in lower case", with(16, 'e'), init_anomaly::kLanguage, Protocol::Dcp4},
  };
  for (const auto& c : cases) {
    const auto decoded = decode_drive_message(bytes(c.payload));
    ASSERT_TRUE(decoded.ok()) << c.what << ": " << to_string(decoded.error);
    const auto* reply = std::get_if<InitReply>(&decoded.value);
    ASSERT_NE(reply, nullptr) << c.what;
    EXPECT_EQ(reply->anomalies, c.anomalies) << c.what;
    EXPECT_EQ(reply->dcp_type, c.dcp_type) << c.what;
  }
}

TEST(DcpMessages, RejectsMalformedMasterMessages) {
  // Legend: what is wrong -> payload from the lift controller -> reason and offset.
  const std::vector<BadCase> cases = {
      {"I0 reply layout as request",
       "I0BP1234241214"
       "4DE",
       MessageError::WrongLength, 0},
      {"I0 language with a digit", "I0BP12342412141E", MessageError::BadLanguage, 14},
      {"I1 without type", "I11", MessageError::WrongLength, 0},
      {"I1 protocol type '2'", "I120", MessageError::BadProtocolType, 2},
      {"I1 data-information-type '5'", "I105", MessageError::BadDataInfoType, 3},
      {"I2 function '2'", "I202", MessageError::BadSwitchFunction, 3},
      {"I3 day 31 in November", "I331112026030405", MessageError::BadDate, 2},
      {"I3 year 2009 (range 2010..9999)", "I322112009030405", MessageError::BadDate, 2},
      {"I3 hour 24", "I322112026240405", MessageError::BadTime, 10},
      {"I3 minute 60", "I322112026036005", MessageError::BadTime, 10},
      {"I3 second with a letter", "I32211202603040x", MessageError::BadDigit, 15},
      {"I6 supply lower-case 'n'", "I6n0", MessageError::BadPowerSupply, 2},
      {"I7 Vmax '3'", "I7301000", MessageError::BadMaxSpeed, 2},
      {"I7 four digits", "I720100", MessageError::WrongLength, 0},
      {"I8 four digits", "I80250", MessageError::WrongLength, 0},
      {"I8 with a space", "I8 25", MessageError::BadDigit, 2},
      {"I9 seven digits", "I9+1234567", MessageError::WrongLength, 0},
      {"I9 without sign", "I90012345", MessageError::BadSign, 2},
  };
  for (const auto& c : cases) {
    const auto decoded = decode_master_message(bytes(c.payload));
    EXPECT_EQ(decoded.error, c.error) << c.what << ": got " << to_string(decoded.error);
    EXPECT_EQ(decoded.offset, c.offset) << c.what;
  }
}

TEST(DcpMessages, RefusesToEncodeValuesThatDoNotFit) {
  // Legend: what does not fit -> the error the encoder reports (and no payload).
  struct Case {
    const char* what;
    MasterMessage message;
    MessageError error;
  };
  const std::vector<Case> cases = {
      {"maker in lower case", InitRequest{{'l', 'd'}, 10, {1, 1, 26}, {'E', 'N'}},
       MessageError::BadMaker},
      {"version 100.00", InitRequest{{'L', 'D'}, 10000, {1, 1, 26}, {'E', 'N'}},
       MessageError::ValueOutOfRange},
      {"software date 30.02.", InitRequest{{'L', 'D'}, 10, {30, 2, 26}, {'E', 'N'}},
       MessageError::BadDate},
      {"language with a digit", InitRequest{{'L', 'D'}, 10, {1, 1, 26}, {'E', '1'}},
       MessageError::BadLanguage},
      {"I3 on 29.02.2026", DateTimeRequest{{2026, 2, 29, 0, 0, 0}}, MessageError::BadDate},
      {"I3 at 23:60", DateTimeRequest{{2026, 2, 28, 23, 60, 0}}, MessageError::BadTime},
      {"I7 distance 100000 cm", StartParamsRequest{MaxSpeed::V4, 100000},
       MessageError::ValueOutOfRange},
      {"I8 load 1000 %", LoadRequest{1000}, MessageError::ValueOutOfRange},
      {"I9 position 1 000 000 mm", PositionRequest{1000000}, MessageError::ValueOutOfRange},
      {"I9 position -1 000 000 mm", PositionRequest{-1000000}, MessageError::ValueOutOfRange},
  };
  for (const auto& c : cases) {
    const auto encoded = encode(c.message);
    EXPECT_EQ(encoded.error, c.error) << c.what;
    EXPECT_EQ(encoded.value.length, 0U) << c.what;
  }
}

TEST(DcpMessages, NamesTheMakersOfTable5_12_2_3) {
  EXPECT_EQ(drive_maker_name({'Z', 'A'}), "Ziehl-Abegg AG");
  EXPECT_EQ(drive_maker_name({'S', 'S'}), "Gefran Deutschland GmbH");
  EXPECT_EQ(drive_maker_name({'B', 'P'}), "");  // a lift controller maker, not a drive maker
  EXPECT_EQ(controller_maker_name({'B', 'P'}), "Boehnke + Partner GmbH");
  EXPECT_EQ(controller_maker_name({'L', 'I'}), "Schneider Steuerungstechnik GmbH");
  // An unknown maker code still decodes: makers joined after this spec version.
  EXPECT_TRUE(decode_drive_message(bytes("I0QQ0102010215"
                                         "4DE"))
                  .ok());
}

TEST(DcpKeypad, EncodesButtonBitsAsOneByte) {
  // DCP 5.6.3: button 1..5 = 0x04..0x40, several at once, 0x00 none.
  const auto one_and_three = encode_keypad(keypad_button::k1 | keypad_button::k3);
  ASSERT_TRUE(one_and_three.ok());
  EXPECT_EQ(one_and_three.value.length, 1U);
  EXPECT_EQ(one_and_three.value.data[0], 0x14);
  const auto none = encode_keypad(keypad_button::kNone);
  ASSERT_TRUE(none.ok());
  EXPECT_EQ(none.value.data[0], 0x00);
  EXPECT_EQ(encode_keypad(0x01).error, MessageError::BadButtons);
  EXPECT_EQ(encode_keypad(0x80).error, MessageError::BadButtons);
}

TEST(DcpKeypad, DriveSideDecodesExactlyOneValidByte) {
  // Legend: payload of an STX 1F ... ETX frame received by the drive -> button bits or error.
  EXPECT_EQ(decode_keypad(std::vector<std::uint8_t>{0x40}).value, 0x40);
  EXPECT_EQ(decode_keypad(std::vector<std::uint8_t>{0x00}).value, 0x00);
  EXPECT_EQ(decode_keypad(std::vector<std::uint8_t>{0x7C}).value, 0x7C);
  EXPECT_EQ(decode_keypad(std::vector<std::uint8_t>{}).error, MessageError::Empty);
  EXPECT_EQ(decode_keypad(std::vector<std::uint8_t>{0x04, 0x08}).error, MessageError::WrongLength);
  EXPECT_EQ(decode_keypad(std::vector<std::uint8_t>{0x02}).error, MessageError::BadButtons);
  EXPECT_EQ(decode_keypad(std::vector<std::uint8_t>{0x84}).error, MessageError::BadButtons);
}

TEST(DcpDriveError, DecodesTextAndRejectsControlCharacters) {
  const auto ok = decode_drive_error(bytes("E023 Motor \x94l"));
  ASSERT_TRUE(ok.ok());
  EXPECT_EQ(std::string(ok.value.chars().begin(), ok.value.chars().end()), "E023 Motor \x94l");
  EXPECT_EQ(decode_drive_error(bytes("")).error, MessageError::Empty);
  const auto bad = decode_drive_error(bytes("E0\x05"));
  EXPECT_EQ(bad.error, MessageError::NotDataChar);
  EXPECT_EQ(bad.offset, 2U);
  // Longer than the 20 characters of DCP 5.11: kept whole (documented leniency).
  EXPECT_TRUE(decode_drive_error(bytes("0123456789012345678901234")).ok());
}

TEST(DcpCivilTime, ChecksCalendarAndRange) {
  EXPECT_TRUE(valid_civil_time({2024, 2, 29, 23, 59, 59}));
  EXPECT_FALSE(valid_civil_time({2023, 2, 29, 0, 0, 0}));
  EXPECT_FALSE(valid_civil_time({2009, 12, 31, 0, 0, 0}));
  EXPECT_FALSE(valid_civil_time({2026, 4, 31, 0, 0, 0}));
  EXPECT_FALSE(valid_civil_time({2026, 1, 1, 24, 0, 0}));
}

}  // namespace
}  // namespace liftd::dcp
