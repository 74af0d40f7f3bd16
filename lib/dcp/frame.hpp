// DCP process frames: the 6-byte master and slave messages (DCP 1.0.0.13 chapters 2 to 4).
// Pure code: no I/O, no clock, no logging, no allocation.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>

namespace liftd::dcp {

/// DCP 2: every message in both directions is exactly 6 bytes.
inline constexpr std::size_t kFrameSize = 6;
/// One frame on the wire.
using FrameBytes = std::array<std::uint8_t, kFrameSize>;

/// Which DCP dialect the drive speaks; decided by the drive's I0 reply (DCP 5.12.2.2).
enum class Protocol : std::uint8_t {
  ComChan,  ///< '0': communication channel only, no process data
  Dcp3,     ///< '3': speed-controlled travels, no absolute position
  Dcp4,     ///< '4': travels on remaining distance
};

/// Command byte bits B0..B7 (DCP 3.1).
namespace command_bit {
inline constexpr std::uint8_t kDriveEnable = 0x01;  ///< B0: drive controller enable
/// B1: travel command (DCP3) / desired-distance travel (DCP4)
inline constexpr std::uint8_t kTravel = 0x02;
inline constexpr std::uint8_t kStopSwitch = 0x04;          ///< B2: stop switch (V0 switch-off)
inline constexpr std::uint8_t kSpeedData = 0x08;           ///< B3: data bytes carry a speed
inline constexpr std::uint8_t kDirectionDown = 0x10;       ///< B4: 0 = up, 1 = down
inline constexpr std::uint8_t kSpeedChange = 0x20;         ///< B5: speed change
inline constexpr std::uint8_t kDesiredDistance = 0x40;     ///< B6: 0 actual, 1 desired distance
inline constexpr std::uint8_t kReplyChecksumError = 0x80;  ///< B7: your last reply was corrupt
}  // namespace command_bit

/// Status byte bits S0..S7 (DCP 4.1).
namespace status_bit {
inline constexpr std::uint8_t kReady = 0x01;                 ///< S0: drive controller ready
inline constexpr std::uint8_t kTravelActive = 0x02;          ///< S1: travel active
inline constexpr std::uint8_t kAdvanceWarning = 0x04;        ///< S2: advance warning active
inline constexpr std::uint8_t kGeneralFault = 0x08;          ///< S3: general fault active
inline constexpr std::uint8_t kBelowLevelling = 0x10;        ///< S4: v < 0.3 m/s
inline constexpr std::uint8_t kAccepted = 0x20;              ///< S5: distance / speed accepted
inline constexpr std::uint8_t kBrakeOpen = 0x40;             ///< S6: 1 = mechanical brake open
inline constexpr std::uint8_t kMessageChecksumError = 0x80;  ///< S7: your last message was corrupt
}  // namespace status_bit

/// Speed bits G0..G10 carried in the data bytes of a speed message (DCP 3.5.3.7).
enum class Speed : std::uint16_t {
  V0 = 1U << 0,   ///< G0: crawl
  VN = 1U << 1,   ///< G1: relevelling
  VF = 1U << 2,   ///< G2: fast start (and fast stop, DCP 13)
  V1 = 1U << 3,   ///< G3: intermediate 3
  VI = 1U << 4,   ///< G4: inspection
  V2 = 1U << 5,   ///< G5: intermediate 2
  V3 = 1U << 6,   ///< G6: intermediate 1
  V4 = 1U << 7,   ///< G7: fast
  V5 = 1U << 8,   ///< G8: intermediate 6
  V6 = 1U << 9,   ///< G9: intermediate 5
  V7 = 1U << 10,  ///< G10: intermediate 4
};

/// All eleven speeds in bit order G0..G10.
inline constexpr std::array<Speed, 11> kAllSpeeds = {Speed::V0, Speed::VN, Speed::VF, Speed::V1,
                                                     Speed::VI, Speed::V2, Speed::V3, Speed::V4,
                                                     Speed::V5, Speed::V6, Speed::V7};

/// "V4", "VN", ...
std::string_view to_string(Speed speed) noexcept;
/// Inverse of to_string; nullopt for anything else.
std::optional<Speed> speed_from_string(std::string_view name) noexcept;
/// Whether the speed may be used in the given dialect (V1, V2, V5, V6, V7 are DCP3 only).
bool speed_allowed(Speed speed, Protocol protocol) noexcept;
/// DCP 3.5.3.7 table: the speeds a DCP3 installation with `count` (1..7) travelling speeds uses,
/// fastest first; an empty span for a count outside 1..7.
std::span<const Speed> dcp3_travel_speeds(int count) noexcept;

/// The data word of a speed message (data1 = high byte, data2 = low byte).
constexpr std::uint16_t speed_word(Speed speed) noexcept {
  return static_cast<std::uint16_t>(speed);
}
/// Decodes a speed data word: exactly one of G0..G10 set, bits 11..15 clear; else nullopt.
std::optional<Speed> speed_from_word(std::uint16_t word) noexcept;

/// Message types by the command byte's low nibble B3..B0 (DCP 3.5.1 and 3.5.2).
enum class MessageType : std::uint8_t {
  Idle,             ///< 0000: idle mode
  Stop,             ///< 0001: stop mode (waiting for the drive to stop)
  Relevelling,      ///< 0011: relevelling without remaining distance
  DistanceOrDecel,  ///< 0101: remaining distance (DCP4) or deceleration; see DistanceModeTracker
  Travel,           ///< 0111: travel mode
  Speed,            ///< 1001: speed message, data bytes carry a speed
  SpeedAfterFastStart,  ///< DCP3 1111, DCP4 1101: speed after a fast start (and fast stop)
  Invalid,              ///< any other nibble, or B6 set (every valid type has B6 = 0)
};

std::string_view to_string(MessageType type) noexcept;

/// Classifies a command byte. B4, B5 and B7 do not matter; B6 must be 0 (DCP 3.5 tables).
MessageType classify_command(std::uint8_t command, Protocol protocol) noexcept;

/// The command byte's low nibble for a message type (B3..B0), for building frames. Invalid and
/// DistanceOrDecel map to their own nibbles (DistanceOrDecel: 0101).
std::uint8_t command_nibble(MessageType type, Protocol protocol) noexcept;

/// DCP 3.5.1 note: after a speed message, the next message decides whether 0101 messages mean
/// "remaining distance" (0101 follows directly) or "deceleration" (travel 0111 follows).
/// Feed it every classified message; it answers what a 0101 means right now.
class DistanceModeTracker {
 public:
  enum class Meaning : std::uint8_t { Undecided, RemainingDistance, Deceleration };
  /// Feeds the next message's type.
  void observe(MessageType type) noexcept;
  /// What 0101 messages mean after the messages seen so far.
  Meaning meaning() const noexcept { return meaning_; }

 private:
  bool after_speed_ = false;
  Meaning meaning_ = Meaning::Undecided;
};

/// Width of distances in the data bytes, from the data-information-type (DCP 4.2.2, 5.12.3).
enum class DistanceWidth : std::uint8_t { Bits15, Bits16 };

/// DCP 3.5.3.4: remaining distance in mm, clamped to 0 below (level passed) and to 0x7FFF or
/// 0xFFFF above.
std::uint16_t remaining_distance_word(std::int64_t distance_mm, DistanceWidth width) noexcept;

/// Data-information-type set with I1 (DCP 4.2.2, 5.12.3); default '0'.
enum class DataInfoType : std::uint8_t {
  Alternating = '0',     ///< 15-bit deceleration distance and extended status alternate
  Decel15 = '1',         ///< 15-bit deceleration distance only
  Extended = '2',        ///< extended status only
  Decel16 = '3',         ///< 16-bit deceleration distance only (16-bit remaining distance)
  ExtendedDist16 = '4',  ///< extended status only, 16-bit remaining distance from us
};

/// Parses '0'..'4'.
std::optional<DataInfoType> data_info_type_from_char(char c) noexcept;
/// Which remaining-distance width the master sends for a data-information-type.
DistanceWidth remaining_distance_width(DataInfoType type) noexcept;

/// Extended status (DCP 4.2.1.1), one field per defined bit.
struct ExtendedStatus {
  bool below_unlocking_speed = false;      ///< bit 0: v < 0.8 m/s (unlocking zone)
  bool below_border_speed = false;         ///< bit 1: v < adjustable border speed
  bool below_overspeed = false;            ///< bit 2: v < adjustable overspeed
  std::uint8_t weight_bits = 0;            ///< bits 4..8: reserved for weight detection (raw)
  bool emergency_reduced_voltage = false;  ///< bit 9: emergency power, reduced DC-link voltage
  bool emergency_direction_down = false;   ///< bit 10: recommended direction (0 up, 1 down)
  bool motor_temperature_limit = false;    ///< bit 11
  bool drive_temperature_limit = false;    ///< bit 12

  /// Encodes with bit 15 set (mode identification).
  std::uint16_t to_word() const noexcept;
  /// Decodes a word whose bit 15 is set; nullopt if bit 15 is clear.
  static std::optional<ExtendedStatus> from_word(std::uint16_t word) noexcept;
  bool operator==(const ExtendedStatus&) const = default;
};

/// What the drive's data bytes carried in one reply.
struct DriveData {
  enum class Kind : std::uint8_t { DecelerationDistance, ExtendedStatus };
  Kind kind = Kind::DecelerationDistance;
  /// Deceleration distance in mm. `saturated` means 0x7FFF / 0xFFFF: stationary or starting
  /// (DCP 4.2.1.2/3), i.e. no usable figure.
  std::uint32_t deceleration_distance_mm = 0;
  bool saturated = false;
  ExtendedStatus extended{};
  bool operator==(const DriveData&) const = default;
};

/// Why a drive data word does not fit the configured data-information-type.
enum class DriveDataError : std::uint8_t {
  ExpectedDistance,  ///< type '1': bit 15 must be 0
  ExpectedExtended,  ///< types '2' and '4': bit 15 must be 1
};

/// Decodes the drive's data word (data1 high byte) for a data-information-type (DCP 4.2.2).
/// Returns the error through `error` and nullopt where the word does not fit.
std::optional<DriveData> decode_drive_data(std::uint16_t word, DataInfoType type,
                                           DriveDataError* error = nullptr) noexcept;
/// Encodes drive data for a data-information-type (used by the simulator): distances clamp to the
/// width's saturation value; extended status sets bit 15.
std::uint16_t encode_deceleration_distance(std::uint32_t distance_mm, DistanceWidth width) noexcept;

/// The master's frame before its checksum (DCP 3).
struct MasterFrame {
  std::uint8_t command = 0;
  std::uint8_t data1 = 0;  ///< high byte of the data word
  std::uint8_t data2 = 0;  ///< low byte of the data word
  std::uint8_t comm1 = 0;  ///< communication channel byte 1 (DCP 5)
  std::uint8_t comm2 = 0;  ///< communication channel byte 2
  std::uint16_t data_word() const noexcept {
    return static_cast<std::uint16_t>((data1 << 8) | data2);
  }
  void set_data_word(std::uint16_t word) noexcept {
    data1 = static_cast<std::uint8_t>(word >> 8);
    data2 = static_cast<std::uint8_t>(word & 0xFF);
  }
  bool operator==(const MasterFrame&) const = default;
};

/// The drive's frame before its checksum (DCP 4).
struct SlaveFrame {
  std::uint8_t status = 0;
  std::uint8_t data1 = 0;
  std::uint8_t data2 = 0;
  std::uint8_t comm1 = 0;
  std::uint8_t comm2 = 0;
  std::uint16_t data_word() const noexcept {
    return static_cast<std::uint16_t>((data1 << 8) | data2);
  }
  void set_data_word(std::uint16_t word) noexcept {
    data1 = static_cast<std::uint8_t>(word >> 8);
    data2 = static_cast<std::uint8_t>(word & 0xFF);
  }
  bool operator==(const SlaveFrame&) const = default;
};

/// DCP 3.4 / 4.4: XOR of bytes 1..5.
std::uint8_t checksum(std::span<const std::uint8_t, 5> bytes) noexcept;

FrameBytes encode(const MasterFrame& frame) noexcept;
FrameBytes encode(const SlaveFrame& frame) noexcept;
/// nullopt when the checksum does not match (the only way a 6-byte frame can be malformed).
std::optional<MasterFrame> decode_master(std::span<const std::uint8_t, kFrameSize> bytes) noexcept;
std::optional<SlaveFrame> decode_slave(std::span<const std::uint8_t, kFrameSize> bytes) noexcept;

/// Status byte by name (DCP 4.1).
struct Status {
  bool ready = false;            ///< S0
  bool travel_active = false;    ///< S1
  bool advance_warning = false;  ///< S2
  bool general_fault = false;    ///< S3
  bool below_levelling = false;  ///< S4
  bool accepted = false;         ///< S5
  bool brake_open = false;       ///< S6
  bool message_error = false;    ///< S7
  static Status from_byte(std::uint8_t status) noexcept;
  std::uint8_t to_byte() const noexcept;
  bool operator==(const Status&) const = default;
};

/// Command byte by name (DCP 3.1).
struct Command {
  bool drive_enable = false;      ///< B0
  bool travel = false;            ///< B1
  bool stop_switch = false;       ///< B2
  bool speed_data = false;        ///< B3
  bool direction_down = false;    ///< B4
  bool speed_change = false;      ///< B5
  bool desired_distance = false;  ///< B6
  bool reply_error = false;       ///< B7
  static Command from_byte(std::uint8_t command) noexcept;
  std::uint8_t to_byte() const noexcept;
  bool operator==(const Command&) const = default;
};

}  // namespace liftd::dcp
