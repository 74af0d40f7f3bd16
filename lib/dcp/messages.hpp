// Payload codecs of the communication channel (DCP 5.7, 5.8, 5.11, 5.12): the expanded data
// I-messages in both directions, remote keypad frames and drive error messages.
// A payload here is what lies between the mode byte and ETX (see ChannelFrame).
// Pure code: no I/O, no clock, no logging, no allocation.
//
// Note on the letter: the spec's tables print the first character as 'l' (lower-case L), but
// DCP 5.6.4 defines it as 0x49, 'I'. We send and accept only 0x49.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>
#include <variant>

#include "dcp/channel.hpp"
#include "dcp/frame.hpp"

namespace liftd::dcp {

/// DCP 5.6.4: the first character of every expanded message, "internal command".
inline constexpr std::uint8_t kInternalCommand = 'I';  // 0x49

/// The second character: which I-message (DCP 5.6.4, 5.12.2 to 5.12.9).
enum class MessageId : std::uint8_t {
  Init = '0',         ///< I0: manufacturer identification / initialisation
  DataInfo = '1',     ///< I1: data-information-type and protocol type
  Switch = '2',       ///< I2: switching function (maximum torque, trip reset)
  DateTime = '3',     ///< I3: date and time
  Power = '6',        ///< I6: emergency power supply / energy saving mode
  StartParams = '7',  ///< I7: start parameters (travel distance)
  Load = '8',         ///< I8: car load
  Position = '9',     ///< I9: actual position
};

/// "I0", "I1", ...
std::string_view to_string(MessageId id) noexcept;

/// Why a payload is not a valid message. Every decoder reports the first problem it finds.
enum class MessageError : std::uint8_t {
  None,
  Empty,              ///< no payload at all
  NotInternal,        ///< first character is not 'I' (0x49)
  UnknownId,          ///< second character names no I-message defined in DCP 5.12
  WrongLength,        ///< payload length does not fit the message (or its direction)
  NotDataChar,        ///< a control character (0x00..0x1F) inside an expanded message
  BadDigit,           ///< a character that must be a decimal digit is not one
  BadMaker,           ///< manufacturer code is not two upper-case letters A..Z
  BadLanguage,        ///< language code is not two upper-case letters (ISO 639)
  BadDate,            ///< day / month / year out of range or not a calendar date
  BadTime,            ///< hour / minute / second out of range
  BadDcpType,         ///< DCP type not '0', '3' or '4'
  BadProtocolType,    ///< I1 protocol type not '0' or '1' (reply: not absent or '1')
  BadDataInfoType,    ///< I1 data-information-type not '0'..'4'
  BadSwitchFunction,  ///< I2 switching function not '0', '1' or 'R'
  BadPowerSupply,     ///< I6 power supply not 'N' or 'U'
  BadEnergySaving,    ///< I6 energy saving mode not '0', '1' or '2'
  BadMaxSpeed,        ///< I7 Vmax not '1' or '2'
  BadTravelKind,      ///< I7 travel type not 's' or 'l'
  BadSign,            ///< I9 sign not '+', '-' or 'E'
  ValueOutOfRange,    ///< a value to encode does not fit its digits
  BadButtons,         ///< keypad byte with bits other than 0x04..0x40
};

/// Plain-English reason, e.g. "a character that must be a digit is not one".
std::string_view to_string(MessageError error) noexcept;

/// A decoded value or the reason it could not be decoded, and where (payload offset).
template <typename T>
struct Decoded {
  T value{};
  MessageError error = MessageError::None;
  std::size_t offset = 0;  ///< index of the offending payload byte (0 for length errors)
  bool ok() const noexcept { return error == MessageError::None; }
};

/// Longest expanded payload: the I0 reply, 'I' '0' + 2 + 4 + 6 + 1 + 2 = 17 characters.
inline constexpr std::size_t kMaxExpandedPayload = 17;

/// An encoded payload (without STX, mode and ETX) in fixed storage.
struct Payload {
  std::array<std::uint8_t, kMaxExpandedPayload> data{};
  std::size_t length = 0;
  std::span<const std::uint8_t> bytes() const noexcept { return {data.data(), length}; }
  bool operator==(const Payload& other) const noexcept {
    return std::equal(data.begin(), data.begin() + static_cast<std::ptrdiff_t>(length),
                      other.data.begin(),
                      other.data.begin() + static_cast<std::ptrdiff_t>(other.length));
  }
};

// ---- field types ----------------------------------------------------------------------------

/// Two upper-case letters: a manufacturer code (DCP 5.12.2.3) or an ISO 639 language code.
using Code2 = std::array<char, 2>;

/// Software version as four digits tens, ones, tenths, hundredths: 12.34 is 1234 (0..9999).
using VersionCenti = std::uint16_t;

/// Software date DDMMYY (DCP 5.12.2.1).
struct SoftwareDate {
  std::uint8_t day = 1;    ///< 1..31 (checked against the month, 20YY for leap years)
  std::uint8_t month = 1;  ///< 1..12
  std::uint8_t year = 0;   ///< two digits 00..99
  bool operator==(const SoftwareDate&) const = default;
};

/// Civil date and time for I3 (DCP 5.12.5.1): year 2010..9999.
struct CivilTime {
  std::uint16_t year = 2010;
  std::uint8_t month = 1;
  std::uint8_t day = 1;
  std::uint8_t hour = 0;
  std::uint8_t minute = 0;
  std::uint8_t second = 0;
  bool operator==(const CivilTime&) const = default;
};

/// True if the fields form a real date/time within the I3 ranges.
bool valid_civil_time(const CivilTime& t) noexcept;

/// I2 switching function (DCP 5.12.4).
enum class SwitchFunction : std::uint8_t {
  None = '0',       ///< no function / cancel the recent function
  MaxTorque = '1',  ///< maximum torque for the next travel only
  Reset = 'R',      ///< trip / fault reset in 200..1000 ms
};

/// I6 power supply (DCP 5.12.6).
enum class PowerSupply : std::uint8_t {
  Mains = 'N',      ///< normal mains operation
  Emergency = 'U',  ///< emergency supply (UPS)
};

/// I6 energy saving mode (DCP 5.12.6): '0', '1', '2'.
enum class EnergySaving : std::uint8_t { Off = '0', Mode1 = '1', Mode2 = '2' };

/// I7 maximum speed (DCP 5.12.7.1).
enum class MaxSpeed : std::uint8_t {
  V3 = '1',  ///< intermediate speed 1
  V4 = '2',  ///< fast speed
};

/// I7 travel type in the reply (DCP 5.12.7.2). 'l' here really is a lower-case L.
enum class TravelKind : std::uint8_t {
  Short = 's',  ///< maximum speed not reached
  Long = 'l',   ///< maximum speed reached
};

/// DCP 5.12.9: a signed six-digit millimetre figure, or 'E' (invalid). nullopt means 'E'.
/// Range -999999..999999.
using SignedMm = std::optional<std::int32_t>;

// ---- messages from the lift controller (us) -------------------------------------------------

/// I0 from the lift controller (DCP 5.12.2.1).
struct InitRequest {
  Code2 maker{'L', 'I'};  ///< lift controller maker code
  VersionCenti version = 0;
  SoftwareDate date{};
  Code2 language{'E', 'N'};
  bool operator==(const InitRequest&) const = default;
};
/// I1 from the lift controller (DCP 5.12.3.1).
struct DataInfoRequest {
  bool extended_protocol = false;  ///< '1': I9 reply with the travel distance
  DataInfoType type = DataInfoType::Alternating;
  bool operator==(const DataInfoRequest&) const = default;
};
/// I2 from the lift controller (DCP 5.12.4.1). The reserve character is sent as '0'.
struct SwitchRequest {
  SwitchFunction function = SwitchFunction::None;
  std::uint8_t reserve = '0';  ///< don't care; any data character is accepted when decoding
  bool operator==(const SwitchRequest&) const = default;
};
/// I3 from the lift controller (DCP 5.12.5.1).
struct DateTimeRequest {
  CivilTime time{};
  bool operator==(const DateTimeRequest&) const = default;
};
/// I6 from the lift controller (DCP 5.12.6.1).
struct PowerRequest {
  PowerSupply supply = PowerSupply::Mains;
  EnergySaving saving = EnergySaving::Off;
  bool operator==(const PowerRequest&) const = default;
};
/// I7 from the lift controller (DCP 5.12.7.1).
struct StartParamsRequest {
  MaxSpeed max_speed = MaxSpeed::V4;
  std::uint32_t distance_cm = 0;  ///< 0..99999
  bool operator==(const StartParamsRequest&) const = default;
};
/// I8 from the lift controller (DCP 5.12.8.1).
struct LoadRequest {
  std::uint16_t load_percent = 0;  ///< 0..999 % of rated load
  bool operator==(const LoadRequest&) const = default;
};
/// I9 from the lift controller (DCP 5.12.9.1).
struct PositionRequest {
  SignedMm position_mm = 0;  ///< from the lowest floor level; nullopt = 'E' (invalid)
  bool operator==(const PositionRequest&) const = default;
};

/// Any expanded message the lift controller sends.
using MasterMessage = std::variant<InitRequest, DataInfoRequest, SwitchRequest, DateTimeRequest,
                                   PowerRequest, StartParamsRequest, LoadRequest, PositionRequest>;

// ---- messages from the drive ------------------------------------------------------------------

/// I0 reply from the drive (DCP 5.12.2.2).
struct InitReply {
  Code2 maker{'Z', 'A'};  ///< drive maker code (table 5.12.2.3)
  VersionCenti version = 0;
  SoftwareDate date{};
  Protocol dcp_type = Protocol::Dcp4;  ///< '0' ComChan, '3' DCP3, '4' DCP4
  Code2 language{'E', 'N'};
  /// Decoding only: fields that were not as DCP 5.12.2.2 defines them but were tolerated
  /// (init_anomaly bits). The DCP type alone must be readable.
  std::uint8_t anomalies = 0;
  bool operator==(const InitReply&) const = default;
};

/// Bits of InitReply::anomalies.
namespace init_anomaly {
inline constexpr std::uint8_t kMaker = 0x01;     ///< maker code not two capital letters
inline constexpr std::uint8_t kVersion = 0x02;   ///< version not four digits
inline constexpr std::uint8_t kDate = 0x04;      ///< software date not a DDMMYY date
inline constexpr std::uint8_t kLanguage = 0x08;  ///< language missing or not two capitals
inline constexpr std::uint8_t kLength = 0x10;    ///< reply shorter or longer than defined
}  // namespace init_anomaly
/// I1 reply (DCP 5.12.3.2): "I1" (base protocol) or "I11" (extended protocol supported).
struct DataInfoReply {
  bool extended_protocol = false;
  bool operator==(const DataInfoReply&) const = default;
};
/// I2 reply (DCP 5.12.4.2): the function now active ('R': reset follows within 1000 ms).
struct SwitchReply {
  SwitchFunction function = SwitchFunction::None;
  std::uint8_t reserve = '0';
  bool operator==(const SwitchReply&) const = default;
};
/// I3 reply (DCP 5.12.5.2): "I3".
struct DateTimeReply {
  bool operator==(const DateTimeReply&) const = default;
};
/// I6 reply (DCP 5.12.6.2): the mode the drive actually runs.
struct PowerReply {
  PowerSupply supply = PowerSupply::Mains;
  EnergySaving saving = EnergySaving::Off;
  bool operator==(const PowerReply&) const = default;
};
/// I7 reply (DCP 5.12.7.2).
struct StartParamsReply {
  TravelKind kind = TravelKind::Long;
  std::uint32_t total_cm = 0;  ///< Sg: minimum total distance, 0..99999
  std::uint32_t decel_cm = 0;  ///< Sv: deceleration distance, 0..99999
  bool operator==(const StartParamsReply&) const = default;
};
/// I8 reply (DCP 5.12.8.2): "I8".
struct LoadReply {
  bool operator==(const LoadReply&) const = default;
};
/// I9 reply (DCP 5.12.9.2): base "I9", or extended with the last travel's distance
/// (+ up, - down, 'E' invalid).
struct PositionReply {
  bool extended = false;
  SignedMm travel_mm = 0;  ///< only meaningful when extended
  bool operator==(const PositionReply&) const = default;
};

/// Any expanded message the drive sends.
using DriveMessage = std::variant<InitReply, DataInfoReply, SwitchReply, DateTimeReply, PowerReply,
                                  StartParamsReply, LoadReply, PositionReply>;

/// The I-message a master or drive message belongs to.
MessageId message_id(const MasterMessage& message) noexcept;
MessageId message_id(const DriveMessage& message) noexcept;

/// Encodes a message into an expanded payload ('I' id fields). Fails with ValueOutOfRange (or the
/// field's own error, e.g. BadMaker) when a field cannot be represented.
Decoded<Payload> encode(const MasterMessage& message) noexcept;
/// Encodes a drive reply (for the simulator and tests).
Decoded<Payload> encode(const DriveMessage& message) noexcept;

/// Decodes an expanded payload sent by the lift controller (what the drive receives).
Decoded<MasterMessage> decode_master_message(std::span<const std::uint8_t> payload) noexcept;
/// Decodes an expanded payload sent by the drive (what we receive).
Decoded<DriveMessage> decode_drive_message(std::span<const std::uint8_t> payload) noexcept;

// ---- drive maker codes --------------------------------------------------------------------

/// The company behind a drive maker code from table 5.12.2.3, or empty if not in the table.
/// (Unknown codes are still accepted by the decoder: makers joined after 1.0.0.13.)
std::string_view drive_maker_name(Code2 code) noexcept;
/// The company behind a lift controller maker code from table 5.12.2.3, or empty.
std::string_view controller_maker_name(Code2 code) noexcept;

// ---- remote keypad (DCP 5.8, 5.6.3) ------------------------------------------------------------

/// Keypad button bits; several may be set at once (DCP 5.6.3). 0x00 means no button.
namespace keypad_button {
inline constexpr std::uint8_t kNone = 0x00;
inline constexpr std::uint8_t k1 = 0x04;
inline constexpr std::uint8_t k2 = 0x08;
inline constexpr std::uint8_t k3 = 0x10;
inline constexpr std::uint8_t k4 = 0x20;
inline constexpr std::uint8_t k5 = 0x40;
inline constexpr std::uint8_t kAll = k1 | k2 | k3 | k4 | k5;
}  // namespace keypad_button

/// True if `buttons` only uses bits 0x04..0x40.
constexpr bool valid_keypad_buttons(std::uint8_t buttons) noexcept {
  return (buttons & static_cast<std::uint8_t>(~keypad_button::kAll)) == 0;
}
/// The payload of a keypad frame (STX 1F button ETX): the single button byte.
Decoded<Payload> encode_keypad(std::uint8_t buttons) noexcept;
/// Decodes a Remote-mode payload received by the drive as a keypad frame: exactly one byte with
/// valid button bits.
Decoded<std::uint8_t> decode_keypad(std::span<const std::uint8_t> payload) noexcept;

// ---- drive error messages (DCP 5.11)
// -------------------------------------------------------------

/// DCP 5.11: an error message carries 1..20 characters. Longer texts (up to the channel's frame
/// limit) are accepted too and kept whole: losing a drive's fault text is worse than a long one.
inline constexpr std::size_t kDriveErrorSpecChars = 20;

/// A drive error text (appendix A characters) in fixed storage.
struct DriveErrorText {
  std::array<std::uint8_t, kMaxChannelPayload> data{};
  std::size_t length = 0;
  std::span<const std::uint8_t> chars() const noexcept { return {data.data(), length}; }
};

/// Decodes a DriveError-mode payload: at least one character, data characters only.
Decoded<DriveErrorText> decode_drive_error(std::span<const std::uint8_t> payload) noexcept;

}  // namespace liftd::dcp
