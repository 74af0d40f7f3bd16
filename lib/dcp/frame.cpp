#include "dcp/frame.hpp"

#include "drive/drive.hpp"

namespace liftd::dcp {
namespace {

constexpr std::uint16_t kModeBit = 0x8000;        // DCP 4.2.1: bit 15 marks extended status
constexpr std::uint16_t kMax15 = 0x7FFF;          // DCP 3.5.3.4 / 4.2.1.2: 15-bit saturation
constexpr std::uint16_t kMax16 = 0xFFFF;          // DCP 3.5.3.4 / 4.2.1.3: 16-bit saturation
constexpr std::uint16_t kSpeedBitsMask = 0x07FF;  // G0..G10

struct SpeedName {
  Speed speed;
  std::string_view name;
};
constexpr std::array<SpeedName, 11> kSpeedNames = {{{Speed::V0, "V0"},
                                                    {Speed::VN, "VN"},
                                                    {Speed::VF, "VF"},
                                                    {Speed::V1, "V1"},
                                                    {Speed::VI, "VI"},
                                                    {Speed::V2, "V2"},
                                                    {Speed::V3, "V3"},
                                                    {Speed::V4, "V4"},
                                                    {Speed::V5, "V5"},
                                                    {Speed::V6, "V6"},
                                                    {Speed::V7, "V7"}}};

constexpr Speed speed_named(std::string_view name) {
  for (const auto& entry : kSpeedNames) {
    if (entry.name == name) return entry.speed;
  }
  return Speed::V0;
}

// DCP 3.5.3.7: the travelling speeds by the installation's speed count, fastest first, in the
// one order every drive kind and the configuration share (drive::kTravelSpeedNames).
constexpr std::array<Speed, drive::kTravelSpeedNames.size()> kDcp3SpeedOrder = [] {
  std::array<Speed, drive::kTravelSpeedNames.size()> out{};
  for (std::size_t i = 0; i < out.size(); ++i) out[i] = speed_named(drive::kTravelSpeedNames[i]);
  return out;
}();
static_assert(kDcp3SpeedOrder[0] == Speed::V4 && kDcp3SpeedOrder[6] == Speed::V5);

// Low nibbles B3..B0 of the command byte (DCP 3.5.1 / 3.5.2 tables).
constexpr std::uint8_t kNibbleIdle = 0x0;
constexpr std::uint8_t kNibbleStop = 0x1;
constexpr std::uint8_t kNibbleRelevelling = 0x3;
constexpr std::uint8_t kNibbleDistanceOrDecel = 0x5;
constexpr std::uint8_t kNibbleTravel = 0x7;
constexpr std::uint8_t kNibbleSpeed = 0x9;
constexpr std::uint8_t kNibbleAfterFastStartDcp3 = 0xF;
constexpr std::uint8_t kNibbleAfterFastStartDcp4 = 0xD;

constexpr bool bit(std::uint8_t byte, std::uint8_t mask) {
  return (byte & mask) != 0;
}
constexpr std::uint8_t flag(bool on, std::uint8_t mask) {
  return on ? mask : std::uint8_t{0};
}

template <typename Frame>
FrameBytes encode_frame(std::uint8_t first, const Frame& f) noexcept {
  FrameBytes out{first, f.data1, f.data2, f.comm1, f.comm2, 0};
  out[5] = checksum(std::span<const std::uint8_t, 5>(out.data(), 5));
  return out;
}

bool checksum_ok(std::span<const std::uint8_t, kFrameSize> bytes) noexcept {
  return checksum(bytes.first<5>()) == bytes[5];
}

}  // namespace

std::string_view to_string(Speed speed) noexcept {
  for (const auto& entry : kSpeedNames) {
    if (entry.speed == speed) return entry.name;
  }
  return "?";
}

std::optional<Speed> speed_from_string(std::string_view name) noexcept {
  for (const auto& entry : kSpeedNames) {
    if (entry.name == name) return entry.speed;
  }
  return std::nullopt;
}

bool speed_allowed(Speed speed, Protocol protocol) noexcept {
  switch (protocol) {
    case Protocol::ComChan:
      return false;
    case Protocol::Dcp3:
      return true;
    case Protocol::Dcp4:
      // DCP 3.5.3.7: V7, V6, V5, V2 and V1 are not available under DCP4.
      return speed != Speed::V1 && speed != Speed::V2 && speed != Speed::V5 && speed != Speed::V6 &&
             speed != Speed::V7;
  }
  return false;
}

std::span<const Speed> dcp3_travel_speeds(int count) noexcept {
  if (count < 1 || count > static_cast<int>(kDcp3SpeedOrder.size())) return {};
  return std::span<const Speed>(kDcp3SpeedOrder.data(), static_cast<std::size_t>(count));
}

std::optional<Speed> speed_from_word(std::uint16_t word) noexcept {
  if ((word & ~kSpeedBitsMask) != 0) return std::nullopt;
  if (word == 0 || (word & (word - 1)) != 0) return std::nullopt;  // exactly one bit
  return static_cast<Speed>(word);
}

std::string_view to_string(MessageType type) noexcept {
  switch (type) {
    case MessageType::Idle:
      return "idle";
    case MessageType::Stop:
      return "stop";
    case MessageType::Relevelling:
      return "relevelling";
    case MessageType::DistanceOrDecel:
      return "distance/deceleration";
    case MessageType::Travel:
      return "travel";
    case MessageType::Speed:
      return "speed";
    case MessageType::SpeedAfterFastStart:
      return "speed-after-fast-start";
    case MessageType::Invalid:
      return "invalid";
  }
  return "invalid";
}

MessageType classify_command(std::uint8_t command, Protocol protocol) noexcept {
  if (bit(command, command_bit::kDesiredDistance)) return MessageType::Invalid;
  const std::uint8_t nibble = command & 0x0F;
  switch (nibble) {
    case kNibbleIdle:
      return MessageType::Idle;
    case kNibbleStop:
      return MessageType::Stop;
    case kNibbleRelevelling:
      return MessageType::Relevelling;
    case kNibbleDistanceOrDecel:
      return MessageType::DistanceOrDecel;
    case kNibbleTravel:
      return MessageType::Travel;
    case kNibbleSpeed:
      return MessageType::Speed;
    case kNibbleAfterFastStartDcp3:
      return protocol == Protocol::Dcp3 ? MessageType::SpeedAfterFastStart : MessageType::Invalid;
    case kNibbleAfterFastStartDcp4:
      return protocol == Protocol::Dcp4 ? MessageType::SpeedAfterFastStart : MessageType::Invalid;
    default:
      return MessageType::Invalid;
  }
}

std::uint8_t command_nibble(MessageType type, Protocol protocol) noexcept {
  switch (type) {
    case MessageType::Idle:
      return kNibbleIdle;
    case MessageType::Stop:
      return kNibbleStop;
    case MessageType::Relevelling:
      return kNibbleRelevelling;
    case MessageType::DistanceOrDecel:
      return kNibbleDistanceOrDecel;
    case MessageType::Travel:
      return kNibbleTravel;
    case MessageType::Speed:
      return kNibbleSpeed;
    case MessageType::SpeedAfterFastStart:
      return protocol == Protocol::Dcp4 ? kNibbleAfterFastStartDcp4 : kNibbleAfterFastStartDcp3;
    case MessageType::Invalid:
      return kNibbleIdle;
  }
  return kNibbleIdle;
}

void DistanceModeTracker::observe(MessageType type) noexcept {
  if (after_speed_) {
    if (type == MessageType::DistanceOrDecel) {
      meaning_ = Meaning::RemainingDistance;
    } else if (type == MessageType::Travel) {
      meaning_ = Meaning::Deceleration;
    }
  }
  if (type == MessageType::Speed || type == MessageType::SpeedAfterFastStart) {
    after_speed_ = true;
  } else if (type != MessageType::Invalid) {
    after_speed_ = false;
  }
}

std::uint16_t remaining_distance_word(std::int64_t distance_mm, DistanceWidth width) noexcept {
  const std::int64_t max = width == DistanceWidth::Bits15 ? kMax15 : kMax16;
  if (distance_mm <= 0) return 0;
  if (distance_mm >= max) return static_cast<std::uint16_t>(max);
  return static_cast<std::uint16_t>(distance_mm);
}

std::optional<DataInfoType> data_info_type_from_char(char c) noexcept {
  if (c < '0' || c > '4') return std::nullopt;
  return static_cast<DataInfoType>(c);
}

DistanceWidth remaining_distance_width(DataInfoType type) noexcept {
  // DCP 4.2.2.4 / 4.2.2.5: types '3' and '4' use 16-bit remaining distances.
  return (type == DataInfoType::Decel16 || type == DataInfoType::ExtendedDist16)
             ? DistanceWidth::Bits16
             : DistanceWidth::Bits15;
}

std::uint16_t ExtendedStatus::to_word() const noexcept {
  std::uint16_t word = kModeBit;
  if (below_unlocking_speed) word |= 1U << 0;
  if (below_border_speed) word |= 1U << 1;
  if (below_overspeed) word |= 1U << 2;
  word = static_cast<std::uint16_t>(word | ((weight_bits & 0x1FU) << 4));
  if (emergency_reduced_voltage) word |= 1U << 9;
  if (emergency_direction_down) word |= 1U << 10;
  if (motor_temperature_limit) word |= 1U << 11;
  if (drive_temperature_limit) word |= 1U << 12;
  return word;
}

std::optional<ExtendedStatus> ExtendedStatus::from_word(std::uint16_t word) noexcept {
  if ((word & kModeBit) == 0) return std::nullopt;
  ExtendedStatus s;
  s.below_unlocking_speed = (word & (1U << 0)) != 0;
  s.below_border_speed = (word & (1U << 1)) != 0;
  s.below_overspeed = (word & (1U << 2)) != 0;
  s.weight_bits = static_cast<std::uint8_t>((word >> 4) & 0x1FU);
  s.emergency_reduced_voltage = (word & (1U << 9)) != 0;
  s.emergency_direction_down = (word & (1U << 10)) != 0;
  s.motor_temperature_limit = (word & (1U << 11)) != 0;
  s.drive_temperature_limit = (word & (1U << 12)) != 0;
  return s;
}

std::optional<DriveData> decode_drive_data(std::uint16_t word, DataInfoType type,
                                           DriveDataError* error) noexcept {
  auto fail = [error](DriveDataError e) -> std::optional<DriveData> {
    if (error != nullptr) *error = e;
    return std::nullopt;
  };
  auto distance15 = [word]() {
    DriveData d;
    d.kind = DriveData::Kind::DecelerationDistance;
    d.deceleration_distance_mm = word & kMax15;
    d.saturated = (word & kMax15) == kMax15;
    return d;
  };
  auto extended = [word]() {
    DriveData d;
    d.kind = DriveData::Kind::ExtendedStatus;
    d.extended = *ExtendedStatus::from_word(word);
    return d;
  };
  const bool mode_bit = (word & kModeBit) != 0;
  switch (type) {
    case DataInfoType::Alternating:
      return mode_bit ? extended() : distance15();
    case DataInfoType::Decel15:
      if (mode_bit) return fail(DriveDataError::ExpectedDistance);
      return distance15();
    case DataInfoType::Extended:
    case DataInfoType::ExtendedDist16:
      if (!mode_bit) return fail(DriveDataError::ExpectedExtended);
      return extended();
    case DataInfoType::Decel16: {
      DriveData d;
      d.kind = DriveData::Kind::DecelerationDistance;
      d.deceleration_distance_mm = word;
      d.saturated = word == kMax16;
      return d;
    }
  }
  return fail(DriveDataError::ExpectedDistance);
}

std::uint16_t encode_deceleration_distance(std::uint32_t distance_mm,
                                           DistanceWidth width) noexcept {
  const std::uint32_t max = width == DistanceWidth::Bits15 ? kMax15 : kMax16;
  return static_cast<std::uint16_t>(distance_mm >= max ? max : distance_mm);
}

std::uint8_t checksum(std::span<const std::uint8_t, 5> bytes) noexcept {
  std::uint8_t x = 0;
  for (std::uint8_t b : bytes) x ^= b;
  return x;
}

FrameBytes encode(const MasterFrame& frame) noexcept {
  return encode_frame(frame.command, frame);
}
FrameBytes encode(const SlaveFrame& frame) noexcept {
  return encode_frame(frame.status, frame);
}

std::optional<MasterFrame> decode_master(std::span<const std::uint8_t, kFrameSize> bytes) noexcept {
  if (!checksum_ok(bytes)) return std::nullopt;
  return MasterFrame{bytes[0], bytes[1], bytes[2], bytes[3], bytes[4]};
}

std::optional<SlaveFrame> decode_slave(std::span<const std::uint8_t, kFrameSize> bytes) noexcept {
  if (!checksum_ok(bytes)) return std::nullopt;
  return SlaveFrame{bytes[0], bytes[1], bytes[2], bytes[3], bytes[4]};
}

Status Status::from_byte(std::uint8_t s) noexcept {
  using namespace status_bit;
  return Status{bit(s, kReady),        bit(s, kTravelActive),        bit(s, kAdvanceWarning),
                bit(s, kGeneralFault), bit(s, kBelowLevelling),      bit(s, kAccepted),
                bit(s, kBrakeOpen),    bit(s, kMessageChecksumError)};
}

std::uint8_t Status::to_byte() const noexcept {
  using namespace status_bit;
  return static_cast<std::uint8_t>(
      flag(ready, kReady) | flag(travel_active, kTravelActive) |
      flag(advance_warning, kAdvanceWarning) | flag(general_fault, kGeneralFault) |
      flag(below_levelling, kBelowLevelling) | flag(accepted, kAccepted) |
      flag(brake_open, kBrakeOpen) | flag(message_error, kMessageChecksumError));
}

Command Command::from_byte(std::uint8_t c) noexcept {
  using namespace command_bit;
  return Command{bit(c, kDriveEnable),     bit(c, kTravel),
                 bit(c, kStopSwitch),      bit(c, kSpeedData),
                 bit(c, kDirectionDown),   bit(c, kSpeedChange),
                 bit(c, kDesiredDistance), bit(c, kReplyChecksumError)};
}

std::uint8_t Command::to_byte() const noexcept {
  using namespace command_bit;
  return static_cast<std::uint8_t>(
      flag(drive_enable, kDriveEnable) | flag(travel, kTravel) | flag(stop_switch, kStopSwitch) |
      flag(speed_data, kSpeedData) | flag(direction_down, kDirectionDown) |
      flag(speed_change, kSpeedChange) | flag(desired_distance, kDesiredDistance) |
      flag(reply_error, kReplyChecksumError));
}

}  // namespace liftd::dcp
