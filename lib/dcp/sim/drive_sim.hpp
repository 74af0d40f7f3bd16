// A simulated DCP3/DCP4 lift drive and car (the slave side of DCP 1.0.0.13): answers the
// master's 6-byte frames, runs the travel sequences of chapters 9 to 13 on a jerk-limited car
// model, serves the communication channel (chapter 5) and injects faults on demand.
// Sans-I/O: time comes in as an argument, no clock, file descriptor, logging or allocation.
// Sources: drive_sim.cpp (time and car, the frames, faults), drive_sim_travel.cpp (the travel
// sequencing), drive_sim_channel.cpp (the communication channel and display).
#pragma once

#include <array>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>

#include "common/mono_time.hpp"
#include "dcp/channel.hpp"
#include "dcp/frame.hpp"
#include "dcp/messages.hpp"
#include "dcp/sim/profile.hpp"
#include "dcp/sim/slave_channel.hpp"

namespace liftd::dcp::sim {

/// Travel speeds of the simulated installation (m/s), by DCP speed name (DCP 3.5.3.7).
struct SpeedTable {
  double v4_mps = 1.6;   ///< fast
  double v3_mps = 1.0;   ///< intermediate 1
  double v2_mps = 0.8;   ///< intermediate 2 (DCP3 only)
  double v1_mps = 0.63;  ///< intermediate 3 (DCP3 only)
  double v7_mps = 0.5;   ///< intermediate 4 (DCP3 only)
  double v6_mps = 0.4;   ///< intermediate 5 (DCP3 only)
  double v5_mps = 0.3;   ///< intermediate 6 (DCP3 only)
  double vi_mps = 0.5;   ///< inspection / test control
  double vn_mps = 0.03;  ///< relevelling
  double v0_mps = 0.05;  ///< crawl
  /// Speed for a speed name; 0 for VF (fast start holds the car).
  double of(dcp::Speed speed) const noexcept;
};

/// Everything configurable about the simulated drive. The defaults reproduce the I7 examples
/// of DCP 11.1.2.1 / 5.12.7 from the car's own profile (300 cm at V4: short, Sg 300, Sv 143;
/// 1000 cm at V4: long, Sg 520, Sv 250).
struct DriveConfig {
  dcp::Protocol protocol = dcp::Protocol::Dcp4;  ///< answered in I0 ('3' or '4')
  dcp::Code2 maker = {'K', 'W'};                 ///< DCP 5.12.2.3 drive maker code
  dcp::VersionCenti version = 100;               ///< software version 01.00 in I0
  dcp::SoftwareDate date{22, 11, 26};            ///< software date DDMMYY in I0
  SpeedTable speeds{};
  RampLimits accel{0.54, 1.3};       ///< acceleration ramp (m/s^2, m/s^3)
  RampLimits decel{0.56, 2.1};       ///< normal deceleration ramp
  RampLimits fast_stop{1.2, 4.0};    ///< DCP 13: fast-stop ramp, also the emergency stop
  RampLimits brake_stop{2.0, 20.0};  ///< mechanical brake closing on a moving car (B0 dropped)
  /// DCP 10: fixed deceleration distance to crawl per DCP3 speed, indexed by speed bit G0..G10;
  /// 0 = derived (ramp to V0 plus 50 mm of crawl).
  std::array<std::uint32_t, 11> dcp3_decel_mm{};
  std::uint32_t magnetising_ms = 300;           ///< pre-flux time before S6 (DCP 9.1.7)
  std::uint32_t brake_release_ms = 50;          ///< brake lifting time after S6 before motion
  std::uint32_t hold_torque_ms = 100;           ///< DCP 9.1.7: torque held after S6 drops
  std::uint32_t fast_start_limit_ms = 10000;    ///< DCP 12.1.2: fast start time limit
  std::uint32_t crawl_limit_mm = 200;           ///< DCP 11.1.2: start distance < 20 cm -> crawl
  std::uint32_t distance_tolerance_mm = 10;     ///< remaining-distance jitter ignored
  std::uint32_t link_timeout_frames = 10;       ///< DCP 7.3: 10 bad or missing frames
  std::uint32_t reset_delay_ms = 400;           ///< DCP 5.12.4: trip reset 200..1000 ms after reply
  std::chrono::microseconds reply_delay{1000};  ///< after the master frame's last byte
  /// Late-reply injection: 11 ms after the master frame's last byte (1.5625 ms at 38400 baud)
  /// the reply starts 12.56 ms into the cycle and ends at 14.13 ms: past both DCP 7.2 limits
  /// ("Latest start of drive controller send: 11,5625 msec", driver off by 13,625 msec) yet
  /// still before the next master frame at 15 ms.
  std::chrono::microseconds late_reply_delay{11000};
  double border_speed_mps = 1.0;       ///< extended status bit 1 threshold
  double overspeed_mps = 1.8;          ///< extended status bit 2 threshold
  std::int64_t start_position_mm = 0;  ///< car position at power-on
  bool require_init = true;            ///< DCP 5.12.2: no travel before a valid I0
  /// An older drive: never answers I1 (DCP 5.12.3.1 "If no message ('I' '1') is transmitted
  /// ..., the data-information-type will be set to '0' on both controllers") and answers I0
  /// with version and date fields that are not digits / not a date.
  bool older_drive = false;
};

/// Phase of the drive, as the status bits show it.
enum class Phase : std::uint8_t {
  Idle,           ///< S1=0 S6=0: waiting for a travel (S0 when ready)
  Magnetising,    ///< S1=1 S6=0: pre-flux after the start command
  Moving,         ///< S1=1 S6=1: the car follows its plan
  FastStartHold,  ///< S1=1 S6=1: DCP 12 fast start, car held at standstill with open brake
  Holding,        ///< S1=1 S6=0: stopped, torque held while the brake closes
  Finished,       ///< S1=0: travel over, waiting for the master to withdraw B1/B2
};
/// "idle", "magnetising", ...
std::string_view to_string(Phase phase) noexcept;

/// Which travel sequence runs.
enum class TravelKind : std::uint8_t {
  None,
  Distance,    ///< DCP 11.1: V4', V3', VN' on remaining distance (DCP4)
  Speed,       ///< DCP 10: V4..V5 with B1, fixed deceleration distance to crawl
  Inspection,  ///< DCP 9.2.1: VI with B1+B2, crawl with B2
  Crawl,       ///< DCP 10.3: V0 (also B2 only)
  Relevel,     ///< DCP 9.2.3: VN with B1, no remaining distance
  FastStart,   ///< DCP 12: held, waiting for the speed-after-fast-start message
};
/// "distance", "speed", ...
std::string_view to_string(TravelKind kind) noexcept;

/// Reply-level faults that can be injected for a number of frames or at a rate.
enum class ReplyFault : std::uint8_t {
  BadChecksum,   ///< reply with a corrupted checksum
  MessageError,  ///< treat the master's frame as corrupt: ignore it, set S7
  Late,          ///< reply after late_reply_delay (outside the DCP 7.2 window)
  NoReply,       ///< stay silent
  Garbage,       ///< send 3 random bytes instead of a frame
};
inline constexpr std::size_t kReplyFaultCount = 5;

/// Something the simulator did, for the tool to print and tests to check.
struct SimEvent {
  /// Kind of event.
  enum class Kind : std::uint8_t {
    PhaseChanged,      ///< value = new Phase
    TravelStarted,     ///< value = TravelKind, detail = start distance mm (or 0)
    TravelEnded,       ///< value = measured distance mm
    TargetExtended,    ///< value = new remaining distance mm
    ExtensionRefused,  ///< value = requested remaining distance mm
    FastStop,          ///< DCP 13 fast stop began
    Fault,             ///< value = FaultCause
    FaultCleared,      ///< value = FaultCause
    ChannelMessage,    ///< value = I-message digit ('0'..'9') handled
    ChannelReset,      ///< STX ETX or 1 s timeout
    DriveReset,        ///< I2 'R' executed
    Violation,         ///< the master broke a spec rule; value = Violation
  };
  MonoTime at{};            ///< when
  Kind kind{};              ///< what
  std::int64_t value = 0;   ///< see Kind
  std::int64_t detail = 0;  ///< see Kind
};
/// "phase", "travel-started", ...
std::string_view to_string(SimEvent::Kind kind) noexcept;

/// Why the drive is in fault (S3).
enum class FaultCause : std::uint8_t {
  Injected,          ///< general fault switched on by the operator (not resettable)
  LinkTimeout,       ///< DCP 7.3: 10 bad/missing frames during travel
  Implausible,       ///< DCP 4.1 S5: remaining distance not plausible
  FastStartTimeout,  ///< DCP 12.1.2: fast start held too long
};
/// "injected", "link-timeout", ...
std::string_view to_string(FaultCause cause) noexcept;

/// A master behaviour the spec forbids, as the drive sees it.
enum class Violation : std::uint8_t {
  /// DCP 3.5.3.2: stop mode 0001 is used only "During deceleration"; DCP 11.1.1 d: "Stop switch
  /// bit B2 remains activated until the lift car comes to the level". A stop message while the
  /// car still runs at speed is answered with an emergency stop.
  StopAtSpeed,
  /// DCP 5.12.9: "The actual position of the lift car will be send after each stopping": a new
  /// travel started although the last stop was not followed by an I9.
  NoPositionAfterStop,
};
inline constexpr std::size_t kViolationCount = 2;
/// "stop-at-speed", ...
std::string_view to_string(Violation violation) noexcept;

/// Faults of the communication channel alone (DCP 5), independent of the real-time bytes.
enum class ChannelFault : std::uint8_t {
  Partial,  ///< STX and part of a message, never the ETX (DCP 5.4: the master resets after 1 s)
  Garbage,  ///< a malformed message: unknown mode byte and stray control characters
  Silence,  ///< channel bytes 00 and the master's channel ignored for the given time (DCP 5.4)
};

/// What to send back for one master frame.
struct Reply {
  std::array<std::uint8_t, 8> bytes{};  ///< the bytes to send
  std::uint8_t size = 0;                ///< 0 = no reply
  /// Delay from the master frame's last byte to the start of the reply.
  std::chrono::microseconds delay{0};
  /// The bytes as a span.
  std::span<const std::uint8_t> view() const noexcept { return {bytes.data(), size}; }
};

/// Link and channel counters.
struct SimCounters {
  std::uint64_t frames = 0;              ///< master frames received
  std::uint64_t bad_frames = 0;          ///< with a bad checksum (or injected as such)
  std::uint64_t replies = 0;             ///< replies returned (any kind)
  std::uint64_t repeats = 0;             ///< replies repeated because of B7
  std::uint64_t travels = 0;             ///< travels completed
  std::uint64_t extensions = 0;          ///< target extensions accepted
  std::uint64_t refused_extensions = 0;  ///< target extensions refused
  std::uint64_t i_messages = 0;          ///< I-messages answered
  std::uint64_t violations = 0;          ///< spec violations of the master (see Violation)
  std::uint64_t implausible = 0;         ///< target changes refused with S5 = 0 (DCP 4.1)
  std::uint64_t shortened = 0;           ///< target changes to a nearer level accepted
};

/// The car's motion as the drive has planned it from one moment on: where the car is at any
/// later time, until the drive changes its plan (on a frame, a timer or an injected fault).
/// Trivially copyable, so another thread can read the car's position at the time it asks,
/// the way a real absolute encoder is read, without calling into the drive.
struct Trajectory {
  MotionPlan plan{};       ///< the distance along the travel direction over time
  MonoTime epoch{};        ///< time 0 of the plan
  double origin_mm = 0.0;  ///< car position at plan distance 0
  bool down = false;       ///< true: the plan's distance counts downwards
  /// Car position in mm at `t` (the plan's start position before it starts).
  double position_mm(MonoTime t) const noexcept;
  /// Car speed in m/s at `t`, signed (+ up).
  double velocity_mps(MonoTime t) const noexcept;
};

/// The simulated drive. Not thread-safe: one owner calls it.
class DriveSim {
 public:
  /// A drive at rest at config.start_position_mm, powered on at `now`.
  explicit DriveSim(const DriveConfig& config = {}, MonoTime now = MonoTime{}) noexcept;

  /// Handles one master frame received completely at `now` and returns the reply.
  Reply on_master_frame(std::span<const std::uint8_t, dcp::kFrameSize> bytes,
                        MonoTime now) noexcept;
  /// Advances the car and the timers to `now` (call between frames, e.g. every few ms).
  void advance(MonoTime now) noexcept;
  /// The reply delay the drive wants right now (config.reply_delay).
  std::chrono::microseconds reply_delay() const noexcept { return config_.reply_delay; }

  // --- the car ---
  /// Car position in mm from the lowest level (the simulated absolute encoder).
  double position_mm() const noexcept;
  /// Car speed in m/s, signed (+ up).
  double velocity_mps() const noexcept;
  /// The car's planned motion from now on (valid until the next call that changes the plan).
  Trajectory trajectory() const noexcept;
  /// True while the car does not move.
  bool stationary() const noexcept;
  /// Moves the car (only while idle), e.g. to start a test at a floor.
  void set_position_mm(double position_mm) noexcept;

  // --- state ---
  /// Current phase.
  Phase phase() const noexcept { return phase_; }
  /// Travel sequence running (None when idle).
  TravelKind travel_kind() const noexcept { return kind_; }
  /// The status byte as the next reply would carry it (without S7).
  std::uint8_t status_byte() const noexcept;
  /// Data-information-type set by I1 ('0' by default).
  dcp::DataInfoType data_info_type() const noexcept { return data_info_type_; }
  /// True after a valid I0 exchange.
  bool initialised() const noexcept { return initialised_; }
  /// Distance measured over the last completed travel (mm, + up).
  std::int64_t last_travel_mm() const noexcept { return last_travel_mm_; }
  /// Counters.
  const SimCounters& counters() const noexcept { return counters_; }
  /// Last I8 load (% of rated load).
  std::uint32_t load_percent() const noexcept { return load_percent_; }
  /// Last I9 position the lift controller sent (mm).
  std::int64_t controller_position_mm() const noexcept { return controller_position_mm_; }
  /// True while I2 '1' (maximum torque for the next travel) is armed.
  bool max_torque_armed() const noexcept { return max_torque_; }
  /// Supply and energy-saving mode set with I6.
  dcp::PowerSupply power_supply() const noexcept { return power_supply_; }
  /// Energy-saving mode set with I6.
  dcp::EnergySaving energy_saving() const noexcept { return energy_mode_; }
  /// Date and time last received with I3.
  const dcp::CivilTime& date_time() const noexcept { return date_time_; }
  /// The configuration in use.
  const DriveConfig& config() const noexcept { return config_; }
  /// The 4x20 remote display as the drive renders it (DCP 5.7).
  const std::array<std::array<char, 20>, 4>& display() const noexcept { return display_; }
  /// I7 figures for a desired distance: ftyp 's'/'l', Sg and Sv in cm (DCP 5.12.7.2).
  struct StartParameters {
    char travel_type = 's';      ///< 's' short, 'l' long (maximum speed reached)
    std::uint32_t total_cm = 0;  ///< Sg
    std::uint32_t decel_cm = 0;  ///< Sv
  };
  /// What the drive answers to I7 for `distance_cm` at V3 (`fast` false) or V4.
  StartParameters start_parameters(std::uint32_t distance_cm, bool fast) const noexcept;

  /// Takes the oldest unread event; false when none.
  bool pop_event(SimEvent& out) noexcept;

  // --- fault injection (switchable at run time) ---
  /// DCP 4.1 S3: general fault on/off (the car stops on the emergency ramp).
  void set_general_fault(bool on, MonoTime now) noexcept;
  /// DCP 4.1 S2: advance warning on/off.
  void set_advance_warning(bool on) noexcept { advance_warning_ = on; }
  /// DCP 4.1 S0 forced off.
  void set_not_ready(bool on) noexcept { not_ready_ = on; }
  /// The drive finds the next change of the remaining distance implausible (DCP 4.1 note):
  /// S5 cleared and an emergency stop, whatever the change.
  void refuse_next_target() noexcept { refuse_next_target_ = true; }
  /// Extended status flags (emergency power and temperature bits) to report.
  void set_extended_flags(const dcp::ExtendedStatus& flags) noexcept { ext_flags_ = flags; }
  /// Applies `fault` to the next `frames` replies.
  void inject(ReplyFault fault, std::uint32_t frames) noexcept;
  /// Applies `fault` to each reply with `probability` (0..1, deterministic generator).
  void set_fault_rate(ReplyFault fault, double probability) noexcept;
  /// Clears every reply fault and rate.
  void clear_reply_faults() noexcept;
  /// Injects a communication-channel fault; `duration` applies to Silence.
  void inject_channel(ChannelFault fault, MonoTime now,
                      MonoTime duration = std::chrono::milliseconds(1500)) noexcept;
  /// Violations seen so far, by kind.
  std::uint64_t violations(Violation kind) const noexcept {
    return violations_[static_cast<std::size_t>(kind)];
  }

 private:
  /// Keeps how late recent frames arrived (for the remaining-distance plausibility check).
  void note_transport_delay(MonoTime now) noexcept;
  /// One master frame (DCP 3): the channel bytes, then the command byte by phase.
  void process(const dcp::MasterFrame& frame, MonoTime now) noexcept;
  /// The master frame's command byte and speed word, decoded once.
  struct FrameView {
    const dcp::MasterFrame& frame;
    std::uint8_t command = 0;
    dcp::MessageType type = dcp::MessageType::Invalid;
    bool b0 = false;    ///< drive enable
    bool b1 = false;    ///< travel command
    bool b2 = false;    ///< stop switch
    bool down = false;  ///< B4: direction down
    bool has_speed = false;
    dcp::Speed speed = dcp::Speed::V0;
    bool speed_ok = false;  ///< a speed this dialect has (DCP 3.5.3.7)
  };
  FrameView view(const dcp::MasterFrame& frame) const noexcept;
  /// B0 withdrawn (DCP 9.1.1, 12.2.1).
  void on_enable_off(const FrameView& f, MonoTime now) noexcept;
  /// At rest: speed messages and the commands that start each travel (DCP 9 to 12).
  void on_frame_at_rest(const FrameView& f, MonoTime now) noexcept;
  /// DCP4 remaining-distance travel start (DCP 11.1), or inspection at crawl (DCP 9.2.1.2).
  void start_distance_travel(const FrameView& f, MonoTime now) noexcept;
  /// A travel is running: fast stop (DCP 13), direction change, then by travel kind.
  void on_frame_in_travel(const FrameView& f, MonoTime now) noexcept;
  /// Fast start hold and go (DCP 12).
  void on_frame_in_fast_start(const FrameView& f, MonoTime now) noexcept;
  /// DCP4 distance travel: remaining distance, B2 withdrawn (DCP 11.1).
  void on_frame_in_distance_travel(const FrameView& f, MonoTime now) noexcept;
  /// DCP3 speed travel: speed change, B1 off at SVx, B2 off at the level (DCP 10.1).
  void on_frame_in_speed_travel(const FrameView& f, MonoTime now) noexcept;
  /// Crawl and relevelling: the command withdrawn stops the car (DCP 9.2.3, 10.3).
  void stop_from_crawl(MonoTime now) noexcept;
  void process_channel(std::uint8_t byte, MonoTime now) noexcept;
  void handle_i_message(std::span<const std::uint8_t> payload, MonoTime now) noexcept;
  void handle_keypad(std::uint8_t buttons, MonoTime now) noexcept;
  void render_display() noexcept;
  void flush_display(bool all) noexcept;
  void send_error_message(std::string_view text) noexcept;
  void update_motion(MonoTime now) noexcept;
  void update_timers(MonoTime now) noexcept;
  bool can_start() const noexcept;
  void start_travel(TravelKind kind, dcp::Speed speed, bool down, MonoTime now,
                    std::int64_t distance_mm) noexcept;
  void begin_motion(MonoTime now) noexcept;
  void on_remaining_distance(std::uint16_t word, MonoTime now) noexcept;
  void plan_stop(const RampLimits& ramp, MonoTime now) noexcept;
  void plan_to_speed(double speed_mps, MonoTime now) noexcept;
  void plan_to_target(MonoTime now) noexcept;
  /// The top speed of a distance travel: the selected speed, crawl when crawl-limited.
  double target_vmax_mps() const noexcept;
  void abort_travel(MonoTime now) noexcept;
  void controlled_abort(MonoTime now) noexcept;
  void raise_fault(FaultCause cause, MonoTime now) noexcept;
  void report_violation(Violation kind, MonoTime now) noexcept;
  bool decelerating(MonoTime now) const noexcept;
  void refuse_target(std::uint16_t word, MonoTime now) noexcept;
  void clear_fault(FaultCause cause, MonoTime now) noexcept;
  void set_phase(Phase phase, MonoTime now) noexcept;
  void emit(SimEvent::Kind kind, MonoTime now, std::int64_t value,
            std::int64_t detail = 0) noexcept;
  std::uint16_t data_word() noexcept;
  std::uint32_t reported_decel_mm() const noexcept;
  bool take_fault(ReplyFault fault) noexcept;
  double dcp3_decel_m(dcp::Speed speed) const noexcept;
  double seconds(MonoTime t) const noexcept;
  MotionState state_at(MonoTime now) const noexcept;

  DriveConfig config_;
  MonoTime epoch_{};
  MonoTime now_{};
  double motion_start_s_ = 0.0;  // plan time at which the brake has lifted
  bool travel_measured_ = false;
  bool rd_saturated_ = false;   // the last remaining distance was 0x7FFF / 0xFFFF
  bool crawl_limited_ = false;  // DCP 11.1.2: start distance below 20 cm

  // Link layer (DCP 6, 7.3).
  dcp::FrameBytes last_reply_{};
  bool have_last_reply_ = false;
  MonoTime last_good_{};
  std::uint32_t bad_streak_ = 0;
  std::uint32_t good_streak_ = 0;
  /// How much later than its 15 ms slot the latest-arriving of the recent good frames came,
  /// and how many good frames ago that was (see on_master_frame).
  MonoTime transport_delay_{};
  std::uint32_t frames_since_delay_ = 0;
  std::uint64_t frame_index_ = 0;
  dcp::DistanceModeTracker tracker_{};

  // Travel state.
  Phase phase_ = Phase::Idle;
  TravelKind kind_ = TravelKind::None;
  MonoTime phase_since_{};
  dcp::Speed selected_ = dcp::Speed::V0;
  bool speed_selected_ = false;
  bool accepted_ = false;  // S5
  bool down_ = false;      // direction of the running travel
  bool stopping_ = false;  // the plan ends in standstill
  bool to_crawl_ = false;  // DCP3: decelerating/crawling after B1 dropped
  bool fast_stop_latched_ = false;
  bool go_pending_ = false;  // DCP4 fast start: go received, waiting for the distance
  bool max_torque_ = false;  // I2 '1' for the next travel
  dcp::Speed run_speed_ = dcp::Speed::V0;
  double origin_mm_ = 0.0;   // plan origin (position at s = 0)
  double target_s_m_ = 0.0;  // Distance travels: stop point along the direction
  // The car's speed when target_s_m_ was read from a remaining distance (0 at rest): the
  // reading's error is the master's measuring lag times this speed.
  double target_read_at_mps_ = 0.0;
  double travel_start_mm_ = 0.0;
  double decel_report_m_ = 0.0;  // deceleration distance reported in the data bytes
  MotionPlan plan_{};
  bool b1_ = false;
  bool b2_ = false;
  std::int64_t last_travel_mm_ = 0;

  // Faults.
  std::array<bool, 4> faults_{};
  std::array<std::uint64_t, kViolationCount> violations_{};
  bool stop_without_i9_ = false;
  MonoTime stop_at_{};               // when the stop that owes an I9 was
  bool refuse_next_target_ = false;  // a travel stopped; no I9 since (DCP 5.12.9)
  double i7_decel_m_ = -1.0;         // Sv of the last I7 answer, for the next travel (-1: none)
  double travel_i7_decel_m_ = -1.0;  // Sv that applies to the running travel
  MonoTime channel_silent_until_{};
  bool advance_warning_ = false;
  bool not_ready_ = false;
  dcp::ExtendedStatus ext_flags_{};
  std::array<std::uint32_t, kReplyFaultCount> fault_frames_{};
  std::array<double, kReplyFaultCount> fault_rate_{};
  std::uint64_t rng_ = 0x9E3779B97F4A7C15ULL;

  // Channel (DCP 5).
  dcp::ChannelParser parser_{};
  ChannelOutput out_{};
  bool initialised_ = false;
  dcp::DataInfoType data_info_type_ = dcp::DataInfoType::Alternating;
  bool extended_i9_ = false;
  dcp::Code2 language_ = {'E', 'N'};
  bool reset_pending_ = false;
  MonoTime reset_at_{};
  dcp::PowerSupply power_supply_ = dcp::PowerSupply::Mains;
  dcp::EnergySaving energy_mode_ = dcp::EnergySaving::Off;
  dcp::CivilTime date_time_{};
  std::uint32_t load_percent_ = 0;
  std::int64_t controller_position_mm_ = 0;
  bool display_active_ = false;
  int menu_page_ = 0;
  MonoTime display_refresh_{};
  std::array<std::array<char, 20>, 4> display_{};
  std::array<std::array<char, 20>, 4> shown_{};

  // Events.
  static constexpr std::size_t kEventCapacity = 64;
  std::array<SimEvent, kEventCapacity> events_{};
  std::size_t event_head_ = 0;
  std::size_t event_count_ = 0;

  SimCounters counters_{};
};

}  // namespace liftd::dcp::sim
