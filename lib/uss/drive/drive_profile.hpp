// The master's side of the PROFIBUS drive-profile state machine that USS carries in the first
// PZD word (USS C 5.2.1: "Steuer- und Zustandswort sind identisch mit der Festlegung aus dem
// PROFIBUS-Profil Drehzahlveränderbare Antriebe"): the state the drive is in, read from its
// status word ZSW, and the control word STW that moves it towards what the lift wants (run,
// normal stop OFF1, coast OFF2, quick stop OFF3), the fault acknowledge as a rising edge of
// STW bit 7, and the supervision of how long the drive takes. Sans-I/O: the caller passes the
// time and the drive's replies; no allocation, lock or system call.
//
// The state graph as the master walks it (C 5.2.1, tables 5.2 to 5.6):
//
//   fault (ZSW 3) --rising edge STW 7, cause gone--> switch-on inhibit (ZSW 6)
//   switch-on inhibit --STW 0 = 0 (OFF1) with STW 1, 2 = 1--> ready to switch on (ZSW 0)
//     ("Wiedereinschalten nur durch AUS 1 und anschließendem EIN", ZSW bit 6)
//   ready to switch on --STW 0 = 1 (ON)--> ready (ZSW 1, "Betriebsbereit")
//   ready --STW 3 = 1 (enable operation)--> operation enabled (ZSW 2)
//   operation enabled --STW 0 = 0 (OFF1)--> ramp down on the ramp generator, at n/f = 0 and
//     I = 0 switched off: ready to switch on
//   any --STW 1 = 0 (OFF2)--> pulses off, motor coasts, switch-on inhibit
//   any --STW 2 = 0 (OFF3)--> quickest stop (current limit), then switch-on inhibit
#pragma once

#include <cstdint>
#include <string_view>

#include "common/defaults.hpp"
#include "common/mono_time.hpp"
#include "uss/defaults.hpp"
#include "uss/pzd.hpp"

namespace liftd::uss {

/// The drive-profile state, as the master reads it from ZSW (USS C 5.2.1, table 5.5).
enum class ProfileState : std::uint8_t {
  NotReadyToSwitchOn,  ///< ZSW bit 0 = 0 without fault or inhibit ("Nicht einschaltbereit")
  SwitchOnInhibit,     ///< ZSW bit 6 = 1 ("Einschaltsperre")
  ReadyToSwitchOn,     ///< ZSW bit 0 = 1, bit 1 = 0 ("Einschaltbereit")
  Ready,               ///< ZSW bits 0, 1 = 1, bit 2 = 0 ("Betriebsbereit": switched on)
  OperationEnabled,    ///< ZSW bits 0, 1, 2 = 1 ("Betrieb freigegeben")
  Off1Active,          ///< operation enabled while our STW says OFF1: ramping down (table 5.2)
  Off2Active,          ///< ZSW bit 4 = 0: "AUS 2 Befehl steht an", not yet in inhibit
  Off3Active,          ///< ZSW bit 5 = 0: "AUS 3 Befehl steht an": quick stop running
  Fault,               ///< ZSW bit 3 = 1 ("Störung")
};
/// "not_ready_to_switch_on", "switch_on_inhibit", "ready_to_switch_on", "ready",
/// "operation_enabled", "off1_active", "off2_active", "off3_active", "fault".
std::string_view to_string(ProfileState state) noexcept;

/// The state ZSW describes. `off1_sent`: the STW last sent had bit 0 = 0, so a drive still in
/// operation is ramping down (Off1Active). Priority: fault, inhibit, OFF2, OFF3, then bits 2..0.
ProfileState decode_status(std::uint16_t zsw, bool off1_sent = false) noexcept;

/// True when ZSW says the drive's pulses are on (bit 2, "Betrieb freigegeben"): the motor is fed.
constexpr bool operation_enabled(std::uint16_t zsw) noexcept {
  return (zsw & zsw::kOperationEnabled) != 0;
}

/// What the lift wants of the drive.
enum class ProfileWish : std::uint8_t {
  Stop,       ///< OFF1: normal stop on the ramp, then switched off (idle word)
  Run,        ///< to operation enabled with ramp generator and setpoint enabled
  Coast,      ///< OFF2: pulses off at once, the motor coasts (safety chain, safety faults)
  QuickStop,  ///< OFF3: quickest stop at the current limit, then off
};
/// "stop", "run", "coast", "quick_stop".
std::string_view to_string(ProfileWish wish) noexcept;

/// The control words (USS C 5.2.1, tables 5.2 to 5.4). Bit 10 "Führung vom AG" is set in every
/// word: with it at 0 the drive ignores the process data ("Prozeßdaten ungültig").
namespace control {
/// Run: ON (bit 0), no OFF2 (1), no OFF3 (2), enable operation (3), ramp generator enable (4),
/// ramp start (5, 0 would freeze the ramp output), setpoint enable (6), control by PLC (10).
inline constexpr std::uint16_t kRun = stw::kOn | stw::kNoOff2 | stw::kNoOff3 |
                                      stw::kEnableOperation | stw::kRampGeneratorEnable |
                                      stw::kRampStart | stw::kSetpointEnable | stw::kControlByPlc;
/// OFF1 (bit 0 = 0): "Herunterfahren an der Hochlauframpe", then switched off. Bits 3..6 stay
/// set so the ramp generator brings the drive down (bit 4 = 0 would stop at the current limit,
/// bit 5 = 0 would freeze the ramp). Also the word that takes an inhibited drive to "ready to
/// switch on" (ZSW bit 6: "Wiedereinschalten nur durch AUS 1 und anschließendem EIN").
inline constexpr std::uint16_t kStop = kRun & ~stw::kOn;
/// OFF2 (bit 1 = 0): "Impulse sperren ... Motor trudelt aus", with ON and every enable off so
/// nothing restarts when OFF2 is lifted; no OFF3 (bit 2 = 1): OFF2 alone decides.
inline constexpr std::uint16_t kCoast = stw::kNoOff3 | stw::kControlByPlc;
/// OFF3 (bit 2 = 0): "Schnellhalt ... schnellstmögliches Herunterfahren"; ON off so the drive
/// ends in switch-on inhibit, operation stays enabled (bit 3) so the drive can brake, the
/// setpoint and ramp generator are off (the quick stop has its own ramp).
inline constexpr std::uint16_t kQuickStop =
    stw::kNoOff2 | stw::kEnableOperation | stw::kControlByPlc;
}  // namespace control

/// The word for `wish` given the drive's `state`, without the acknowledge bit. Run from
/// switch-on inhibit, not ready, fault or a running OFF2/OFF3 sends OFF1 first (the drive must
/// see bit 0 = 0 before it takes ON again, C 5.2.1 ZSW bit 6); from every other state kRun.
std::uint16_t control_word(ProfileWish wish, ProfileState state) noexcept;

/// Timing supervision of the drive-profile machine (a state not reached in time).
enum class Supervision : std::uint8_t {
  None,
  NotSwitchedOn,  ///< run wished, no "operation enabled" within switch_on_timeout_ms
  NotStopped,     ///< OFF1/OFF2/OFF3 wished, ZSW bit 2 still 1 after stop_timeout_ms
};
/// "none", "drive_did_not_start", "drive_did_not_stop".
std::string_view to_string(Supervision supervision) noexcept;

/// Tunables of the state machine (config `uss.drive.*`).
struct ProfileConfig {
  /// Run wished: "operation enabled" must follow within this (the drive's own t_wart, C 5.2.1
  /// bit 0, may be up to 20 min; a lift waits much less).
  std::uint32_t switch_on_timeout_ms = defaults::kUssProfileTimeoutMs;
  /// OFF1/OFF2/OFF3 wished: ZSW bit 2 must drop within this (OFF1 ramps down first).
  std::uint32_t stop_timeout_ms = 5000;
  /// Longest time STW bit 7 is held at 1 waiting for ZSW bit 3 to clear.
  std::uint32_t acknowledge_hold_ms = 1000;
  /// ZSW bit 9 "Führung gefordert" must be 1: at 0 "Führung nur am Gerät möglich" (the drive is
  /// in local control) and no travel may start.
  bool require_plc_control = true;
};

/// What one step sees of the drive.
struct ProfileInput {
  MonoTime now{};
  std::uint16_t zsw = 0;      ///< the drive's last status word
  std::uint64_t replies = 0;  ///< good replies from the drive so far (grows by one per reply)
  bool link_ok = false;       ///< the replies are current; no supervision without them
};

/// The master side of the drive profile: STW from the wish, the acknowledge edge, supervision.
class DriveProfile {
 public:
  explicit DriveProfile(const ProfileConfig& config = {}) noexcept : config_(config) {}

  /// One step: returns the STW for the next telegram to the drive.
  std::uint16_t step(ProfileWish wish, const ProfileInput& in) noexcept;

  /// Arms one fault acknowledge: STW bit 7 goes out at 0 until the drive has answered a
  /// telegram that carried the 0, then at 1 until ZSW bit 3 clears or acknowledge_hold_ms
  /// pass (C 5.2.1 table 5.3: "Sammelmeldung wird bei positiver Flanke quittiert"). Also clears
  /// a latched supervision.
  void acknowledge() noexcept;

  /// The state decoded in the last step.
  ProfileState state() const noexcept { return state_; }
  /// The STW returned by the last step.
  std::uint16_t control() const noexcept { return stw_; }
  /// The wish of the last step.
  ProfileWish wish() const noexcept { return wish_; }
  /// A state the drive did not reach in time; latched until acknowledge().
  Supervision supervision() const noexcept { return supervision_; }
  /// An acknowledge edge is under way.
  bool acknowledging() const noexcept { return ack_ != Ack::Idle; }
  /// ZSW bit 9 allows control (or the check is off).
  bool plc_control(std::uint16_t zsw) const noexcept {
    return !config_.require_plc_control || (zsw & zsw::kPlcControlRequested) != 0;
  }
  const ProfileConfig& config() const noexcept { return config_; }

 private:
  enum class Ack : std::uint8_t { Idle, Armed, Low, High };

  ProfileConfig config_;
  ProfileState state_ = ProfileState::NotReadyToSwitchOn;
  ProfileWish wish_ = ProfileWish::Stop;
  std::uint16_t stw_ = control::kStop;
  Supervision supervision_ = Supervision::None;
  MonoTime wish_since_{};
  bool wish_started_ = false;
  Ack ack_ = Ack::Idle;
  std::uint64_t ack_replies_ = 0;
  MonoTime ack_since_{};
};

}  // namespace liftd::uss
