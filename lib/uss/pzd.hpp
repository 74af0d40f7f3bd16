// The PZD (process data) area of the USS payload (spec chapter C 5): control word STW and
// status word ZSW bits 0..10 (identical with the PROFIBUS drive profile, C 5.2.1), setpoint
// normalisation, and the broadcast enable array (C 5.2.3 and appendix).
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <string_view>

#include "uss/pkw.hpp"

namespace liftd::uss {

/// Control word STW, PZD1 master -> slave (C 5.2.1 Tabellen 5.2-5.4). Bits 11..15 are
/// device-specific.
namespace stw {
inline constexpr std::uint16_t kOn = 1U << 0;      ///< 1 = ON, 0 = OFF1 (ramp down)
inline constexpr std::uint16_t kNoOff2 = 1U << 1;  ///< 1 = operating condition, 0 = OFF2 (coast)
inline constexpr std::uint16_t kNoOff3 = 1U
                                         << 2;  ///< 1 = operating condition, 0 = OFF3 (quick stop)
inline constexpr std::uint16_t kEnableOperation = 1U << 3;      ///< enable / inhibit operation
inline constexpr std::uint16_t kRampGeneratorEnable = 1U << 4;  ///< 0 = ramp output set to 0
inline constexpr std::uint16_t kRampStart = 1U << 5;            ///< 1 = ramp runs, 0 = ramp frozen
inline constexpr std::uint16_t kSetpointEnable = 1U << 6;       ///< 0 = ramp input set to 0
inline constexpr std::uint16_t kFaultAcknowledge = 1U << 7;     ///< acknowledge on the rising edge
inline constexpr std::uint16_t kJog1 = 1U << 8;                 ///< jog 1 on (optional)
inline constexpr std::uint16_t kJog2 = 1U << 9;                 ///< jog 2 on (optional)
/// 1 = control by the automation system: process data valid; 0 = the slave keeps the old
/// process data.
inline constexpr std::uint16_t kControlByPlc = 1U << 10;
}  // namespace stw

/// Status word ZSW, PZD1 slave -> master (C 5.2.1 Tabellen 5.5, 5.6). Bits 11..15 are
/// device-specific.
namespace zsw {
inline constexpr std::uint16_t kReadyToSwitchOn = 1U << 0;   ///< ready to switch on
inline constexpr std::uint16_t kReady = 1U << 1;             ///< ready (for operation)
inline constexpr std::uint16_t kOperationEnabled = 1U << 2;  ///< operation enabled
inline constexpr std::uint16_t kFault = 1U << 3;             ///< fault (drive out of operation)
inline constexpr std::uint16_t kNoOff2 = 1U << 4;            ///< 0 = an OFF2 command is present
inline constexpr std::uint16_t kNoOff3 = 1U << 5;            ///< 0 = an OFF3 command is present
inline constexpr std::uint16_t kSwitchOnInhibit = 1U << 6;   ///< switch-on inhibited
inline constexpr std::uint16_t kWarning = 1U << 7;           ///< warning, drive keeps running
/// Setpoint/actual monitoring within the tolerance band.
inline constexpr std::uint16_t kSetpointReached = 1U << 8;
/// The automation system is asked to take control (0 = local operation only).
inline constexpr std::uint16_t kPlcControlRequested = 1U << 9;
/// Actual value >= the comparison value set by a parameter (f or n reached).
inline constexpr std::uint16_t kFrequencyReached = 1U << 10;
}  // namespace zsw

/// Snake-case names of STW bits 0..10 (API and log names), index = bit number.
inline constexpr std::array<std::string_view, 11> kControlWordBitNames = {"on",
                                                                          "no_off2",
                                                                          "no_off3",
                                                                          "enable_operation",
                                                                          "ramp_generator_enable",
                                                                          "ramp_start",
                                                                          "setpoint_enable",
                                                                          "fault_acknowledge",
                                                                          "jog1",
                                                                          "jog2",
                                                                          "control_by_plc"};
/// Snake-case names of ZSW bits 0..10, index = bit number.
inline constexpr std::array<std::string_view, 11> kStatusWordBitNames = {"ready_to_switch_on",
                                                                         "ready",
                                                                         "operation_enabled",
                                                                         "fault",
                                                                         "no_off2",
                                                                         "no_off3",
                                                                         "switch_on_inhibit",
                                                                         "warning",
                                                                         "setpoint_reached",
                                                                         "plc_control_requested",
                                                                         "frequency_reached"};

/// Setpoint / actual value normalisation (C 5.2.2: "Die Normierung ist von der Bedeutung des
/// Wertes und dem jeweiligen Gerätetyp abhängig"). Default: the drive-profile convention
/// 4000 hex = 100 %. Values are rounded to the nearest raw step and clamped to int16.
struct Normalisation {
  std::int32_t raw_full_scale = 0x4000;  ///< raw value that means full_scale
  double full_scale = 100.0;             ///< engineering value at raw_full_scale
  std::int16_t to_raw(double value) const noexcept;
  double from_raw(std::int16_t raw) const noexcept;
};

/// The 4-word broadcast enable array sent in the PKW area of a broadcast telegram (C 5.2.3,
/// appendix "The Optional Broadcast Mechanism"). Word a: bit 0 = broadcast flag, bits 1..15 =
/// PZD words 1..15 enabled; words b, c, d: bit masks for PZD 1, 4 and 5 (a bit of those words is
/// taken over only if the word is enabled in a AND the bit is set in its mask). PZD 16 is never
/// taken over.
struct BroadcastEnable {
  bool enable = false;          ///< word a bit 0: the broadcast flag; without it nothing is taken
  std::uint16_t mask_pzd1 = 0;  ///< word b
  std::uint16_t mask_pzd4 = 0;  ///< word c
  std::uint16_t mask_pzd5 = 0;  ///< word d
  /// Word a bits 1..15: bit k enables PZD word k (use pzd_word_bit(k)); bit 0 is ignored here.
  std::uint16_t pzd_words = 0;
  /// Word a as sent.
  std::uint16_t word_a() const noexcept {
    return static_cast<std::uint16_t>((pzd_words & 0xFFFE) | (enable ? 1U : 0U));
  }
  bool operator==(const BroadcastEnable&) const = default;
};
/// Word a bit for PZD word k (1..15); 0 for any other k (PZD 16 is not broadcast-capable).
constexpr std::uint16_t pzd_word_bit(unsigned k) noexcept {
  return (k >= 1 && k <= 15) ? static_cast<std::uint16_t>(1U << k) : std::uint16_t{0};
}
/// Fills the 4 PKW words a, b, c, d (in the places of PKE, IND, PWE1, PWE2): encode the result
/// with PkwLength::Four.
void encode_broadcast_enable(const BroadcastEnable& be, Pkw& pkw) noexcept;
/// The inverse (slave side): reads a, b, c, d from a 4-word PKW area.
BroadcastEnable decode_broadcast_enable(const Pkw& pkw) noexcept;
/// Slave side of the appendix rules: takes the enabled words and bits of `received` into
/// `current` (index 0 = PZD1). Nothing changes without the broadcast flag; PZD 16 never.
void apply_broadcast(const BroadcastEnable& be, std::span<const std::uint16_t> received,
                     std::span<std::uint16_t> current) noexcept;

}  // namespace liftd::uss
