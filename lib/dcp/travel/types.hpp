// The sequencers' sans-I/O boundary: what they read once per 15 ms cycle, what they put into the
// next master frame, the channel messages they need and the events they report.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>

#include "common/defaults.hpp"
#include "common/mono_time.hpp"
#include "dcp/frame.hpp"
#include "lift/cause.hpp"
#include "lift/floors.hpp"
#include "lift/inputs.hpp"

namespace liftd::travel {

using lift::Direction;

/// Kind of travel (one state machine family per kind).
enum class TravelKind : std::uint8_t {
  None,          ///< no travel
  Dcp4Distance,  ///< DCP 11.1.2/11.1.3: V4'/V3' travel on remaining distance
  Dcp4Relevel,   ///< DCP 11.1.4: VN' relevelling on remaining distance
  Dcp3Speed,     ///< DCP 10.1/10.2: speed travel with fixed deceleration distance SVx
  Dcp3Crawl,     ///< DCP 10.3: crawl travel with V0
  Inspection,    ///< DCP 9.2.1: inspection travel (VI, V0 from an end zone)
  Recall,        ///< DCP 9.2.2: test control travel, same as inspection
  Relevel,       ///< DCP 9.2.3: relevelling without remaining distance
};

/// Fixed-capacity ASCII text of an I-message body (between 0x1C and ETX).
struct ChannelText {
  std::array<char, 16> chars{};
  std::size_t size = 0;
};

/// A communication-channel request a travel needs (DCP 5.12.7 .. 5.12.9).
struct ChannelRequest {
  enum class Kind : std::uint8_t { StartParameters, Load, Position };
  Kind kind = Kind::StartParameters;
  dcp::Speed vmax = dcp::Speed::V4;         ///< I7: V3 ('1') or V4 ('2')
  std::uint32_t desired_distance_cm = 0;    ///< I7: Ss, 5 BCD digits
  std::uint8_t load_percent = 0;            ///< I8: load in % of rated load, 3 BCD digits
  std::optional<std::int64_t> position_mm;  ///< I9: mm from the lowest level; nullopt sends 'E'
  /// The message body, e.g. "I7200300" for I7 V4 300 cm (DCP 11.1.2.1 example 1).
  ChannelText body() const noexcept;
  bool operator==(const ChannelRequest&) const = default;
};

/// A reply to one of the requests above, as the channel decoded it.
struct ChannelReply {
  ChannelRequest::Kind kind = ChannelRequest::Kind::StartParameters;
  bool short_travel = false;            ///< I7 ftyp: 's' short, 'l' long
  std::uint32_t min_distance_cm = 0;    ///< I7 Sg
  std::uint32_t decel_distance_cm = 0;  ///< I7 Sv: the target may be extended while remaining > Sv
};

/// Everything a sequencer may look at, once per 15 ms cycle.
struct CycleInput {
  MonoTime now{};
  bool link_up = false;         ///< link supervision good (no 10-lost-frames fault)
  bool handshake_done = false;  ///< valid I0 exchange done
  dcp::Protocol protocol = dcp::Protocol::Dcp4;
  dcp::Status status{};  ///< last good status byte
  /// The previous frame got a good reply without S7 that is no repetition (DCP 6): `status`
  /// shows how the drive took that frame (S5 for a new speed or target, DCP 4.1).
  bool reply_fresh = false;
  std::optional<std::uint32_t> decel_distance_mm;  ///< from the data bytes, if known (not 7FFF)
  std::optional<dcp::ExtendedStatus> extended;     ///< from the data bytes, if any
  std::optional<std::int64_t> position_mm;         ///< absolute car position if valid
  lift::Inputs inputs{};
  std::optional<ChannelReply> channel_reply;  ///< a reply that arrived in this cycle
};

/// What goes into the next master frame, plus the outputs that follow the drive.
struct CycleOutput {
  std::uint8_t command = 0;     ///< B0..B6 (B7 belongs to the link)
  std::uint16_t data_word = 0;  ///< speed bits or remaining distance
  bool brake_open = false;      ///< mechanical brake output: follows S6 (DCP 9.1.7)
  /// Motor contactors: on with our B0, and while the drive reports S1 (DCP 9.1.4, 10.1.1 step 5).
  bool contactors_on = false;
  std::optional<ChannelRequest> channel_request;  ///< a request to queue on the channel
};

/// What happened, for the API and the journal (drained by the caller, outside the cycle).
struct Event {
  enum class Type : std::uint8_t {
    Started,            ///< drive reported travel active (S1) for a travel
    Finished,           ///< travel ended normally (S1 = 0 after the stop)
    Aborted,            ///< travel ended early; see cause
    TargetExtended,     ///< the drive confirmed a new target with S5 (DCP 4.1)
    TargetRefused,      ///< the drive refused a new target: S5 cleared, emergency stop
    FastStartArmed,     ///< fast start holding the car, waiting for the doors
    DriveFault,         ///< the drive raised S3 (DCP 9.1.6)
    DriveFaultCleared,  ///< the drive cleared S3
  };
  Type type = Type::Started;
  TravelKind kind = TravelKind::None;
  lift::Cause cause = lift::Cause::None;
  MonoTime at{};
  std::int64_t target_mm = 0;               ///< destination level, where it applies
  std::optional<std::int64_t> position_mm;  ///< position at the event
  /// target_mm applies: a run with a destination (not inspection or recall, not a drive fault
  /// while standing).
  bool has_target() const noexcept {
    return kind != TravelKind::None && kind != TravelKind::Inspection && kind != TravelKind::Recall;
  }
  bool operator==(const Event&) const = default;
};

/// A travel order from the dispatcher / API.
struct TravelRequest {
  TravelKind kind = TravelKind::Dcp4Distance;
  /// Speed limit: V4/V3 for Dcp4Distance; the DCP3 speed for Dcp3Speed; ignored otherwise.
  dcp::Speed speed = dcp::Speed::V4;
  /// Destination level (mm from the lowest level). Used by distance travels and, where the
  /// position is known, by DCP3 and relevelling travels.
  std::int64_t target_mm = 0;
  /// DCP3 and relevelling travels without position: the direction to go.
  Direction direction = Direction::None;
  /// DCP 12: start with the fast start function (doors still closing).
  bool fast_start = false;
  /// DCP 5.12.8: load in percent, sent with I8 if known (never with fast start).
  std::optional<std::uint8_t> load_percent;
  /// DCP3 and crawl travels: end by position against `target_mm` whatever
  /// TravelConfig::dcp3_reference says (the learning travel, which finds the shaft's signals).
  bool by_position = false;
  /// Crawl travels: the longest crawl in ms; 0 takes TravelConfig::crawl_timeout_ms.
  std::uint32_t crawl_timeout_ms = 0;
};

/// Where a DCP3 travel learns its deceleration point and level.
enum class Dcp3Reference : std::uint8_t {
  ShaftSignals,  ///< Inputs::decel_point() of the travel's speed and Inputs::level_zone
  Position,      ///< absolute position against the target and the configured SVx
};

/// Tunables of the travel sequencers. Times in ms, distances in mm.
struct TravelConfig {
  dcp::DataInfoType data_info_type = dcp::DataInfoType::Alternating;  ///< set with I1
  /// Cycles the speed message stays on the wire before the travel command (two, so one corrupt
  /// frame does not lose it).
  std::uint32_t speed_message_cycles = 2;
  bool use_i7 = defaults::kUseStartParameters;  ///< DCP 11.1.2.1: exchange start parameters
  std::uint32_t i7_timeout_ms = 600;            ///< then go without Sv
  std::uint32_t i8_timeout_ms = 300;       ///< DCP 5.12.8: travel starts even without the reply
  std::uint32_t start_timeout_ms = 3000;   ///< S6 and S1 must come within this after enabling
  std::uint32_t stop_timeout_ms = 5000;    ///< S1 must clear within this after the stop
  std::uint32_t extension_margin_mm = 20;  ///< added to the deceleration distance for extensions
  /// DCP 12.1.2: fast start time limit.
  std::uint32_t fast_start_timeout_ms = defaults::kFastStartTimeoutMs;
  /// Level reached (relevelling, DCP3 by position).
  std::uint32_t level_tolerance_mm = defaults::kLevelToleranceMm;
  /// DCP4: a travel that ends farther than this from its target is reported as StoppedOffLevel.
  std::uint32_t arrival_tolerance_mm = 20;
  /// Longest crawl (DCP3 B2 positioning, relevelling without distance) before a controlled stop.
  std::uint32_t crawl_timeout_ms = 30000;
  bool auto_relevel = true;  ///< DCP4: VN' when the car drifts off the level
  std::uint32_t relevel_threshold_mm = defaults::kRelevelThresholdMm;  ///< starts auto relevelling
  std::uint32_t relevel_zone_mm = lift::kRelevelZoneMm;                ///< beyond this drift, none
  bool relevel_electric_stop = defaults::kRelevelElectricStop;         ///< DCP 9.2.3.2 / 9.2.3.1
  /// Relevel with the doors open over the bridged door zone (travel.relevel_with_doors "open" or
  /// "both"); false: only with the doors locked ("closed").
  bool relevel_doors_open = true;
  Dcp3Reference dcp3_reference = Dcp3Reference::Position;
  /// DCP 3.5.3.7: number of travelling speeds of a DCP3 installation (1..7).
  int dcp3_speed_count = defaults::kDcp3SpeedCount;
  /// DCP 8.1: fixed deceleration distance SVx per DCP3 speed, indexed by the speed's bit
  /// number G0..G10 (used with Dcp3Reference::Position): SV3 (G6) and SV4 (G7) by default.
  std::array<std::uint32_t, 11> dcp3_decel_distance_mm{
      0, 0, 0, 0, 0, 0, defaults::kDcp3DecelV3Mm, defaults::kDcp3DecelV4Mm, 0, 0, 0};
  /// DCP 10.3 step 3: once B2 is withdrawn the drive stops from crawl on its own ramp. With
  /// Dcp3Reference::Position, withdraw B2 this much before the level so the car stops on it
  /// (the role a stop flag placed ahead of the level plays in the shaft). 0: at the level.
  std::uint32_t dcp3_stop_lead_mm = defaults::kDcp3StopLeadMm;
};

/// The name of the first out-of-range TravelConfig field, or nullopt when the config is usable.
std::optional<std::string_view> validate(const TravelConfig& config) noexcept;

/// Bit number (0..10) of a speed, the index into TravelConfig::dcp3_decel_distance_mm.
std::size_t speed_index(dcp::Speed speed) noexcept;

/// n for the travel speeds V1..V7 (the shaft's deceleration point of Vn, lift::Inputs), 0 for
/// V0, VN, VF and VI, which have no deceleration point of their own.
int speed_number(dcp::Speed speed) noexcept;

/// Why a target extension was refused.
enum class ExtendResult : std::uint8_t {
  Accepted,          ///< new target taken over before the car moves (goes out with the start)
  Pending,           ///< new target sent; the drive's S5 confirms or refuses it (DCP 4.1, 7.2)
  Busy,              ///< an earlier target change still waits for the drive's S5
  NoDistanceTravel,  ///< no DCP4 distance travel running
  NotFurther,        ///< not beyond the current target in the travel direction
  AdvanceWarning,    ///< S2 set: DCP 9.1.5 forbids extending
  DecelUnknown,      ///< neither data bytes nor I7 gave a deceleration distance
  TooLate,           ///< could not reach the drive 30 ms before the deceleration point
};

/// Why a travel request was refused.
enum class StartResult : std::uint8_t {
  Accepted,        ///< takes effect in the next cycle
  Busy,            ///< a travel is running or the drive still reports S1
  WrongProtocol,   ///< travel kind not available in the drive's dialect
  BadSpeed,        ///< speed not allowed for this travel / installation
  NoPosition,      ///< distance travel without a valid position
  AlreadyThere,    ///< target within the level tolerance
  NoDirection,     ///< direction unknown
  InspectionMode,  ///< inspection / recall switched on: only button travels
  ShuttingDown,    ///< the service is stopping: no new travel
};

/// snake_case names for the API and the journal.
std::string_view to_string(TravelKind kind) noexcept;
std::string_view to_string(Event::Type type) noexcept;
std::string_view to_string(StartResult result) noexcept;
std::string_view to_string(ExtendResult result) noexcept;

}  // namespace liftd::travel
