// Simulated USS slaves (drives) on one bus, written from the USS specification (chapters A and C
// and the broadcast appendix), not from our master: the receive side of A 5.2, the reply after a
// reply delay, mirror (A 5.3), broadcast (A 3, never answered), special telegrams (A 5.4), the PKW
// parameter channel of C 4 with a small parameter table, spontaneous reports (C 4.2.1.2), the
// drive-profile state machine seen from the drive (C 5.2.1), a motor and lift-car model, fault
// injection, and a record of what the spec forbids the master. Sans-I/O: characters and time come
// in, reply bytes with the time to send them go out. No clock, no I/O, no allocation after the
// constructor.
//
// Structure: one UssSlaveSim per slave address (each with its own receiver, as every station on
// the bus runs A 5.2 itself), and UssBusSim that feeds every received character to all of them and
// hands out the replies. A single slave can also be driven alone through the same calls.
// Sources: uss_slave_sim.cpp (the line and telegram handling, UssBusSim), uss_slave_drive.cpp (the
// drive profile and the car), uss_slave_parameters.cpp (the PKW parameter store).
//
// How to drive it (one thread owns the object; nothing here is thread-safe):
//   - every character read from the line: on_char(c, t) with t = the time it was received
//     (a parity/framing error from the port's PARMRK marks goes in c.error);
//   - when nothing arrives: on_time(now) at least every few ms and by deadline() (residual-time
//     supervision of A 5.2.1.2), which also moves the car;
//   - next_reply_at() says when a reply is due; take_reply(now, out) hands it over once now has
//     reached it: send out.bytes[0..size) then (out.parity_error_at >= 0: that byte with a parity
//     error; a transport that cannot make one corrupts the byte instead);
//   - reply_sent(t) with the time the reply's last byte left (the start pause of the master's
//     next telegram is measured from it, A 5.1.2); without the call the simulator assumes the
//     reply went out at send time at the line's baud rate.
// Car and encoder for another thread: after each call copy position_mm()/velocity_mps() into
// whatever the other thread reads (e.g. an atomic), as the daemon does for the other simulators.
//
// Device-specific choices (the spec leaves them to the device's manual):
//   - Special telegrams (A 5.4): a slave configured with UssSpecialMode::Echo answers a special
//     telegram addressed to it with the same address byte and the same payload (a loopback that
//     lets a master test its pass-through); special broadcasts are taken and never answered.
//     With Ignore it is a plain drive-profile slave: "Das Telegramm wird von allen Slaves, für
//     die keine Sondertelegramme definiert sind, verworfen" (A 4.3).
//   - Array places: IND = y addresses "die y-te Stelle" (C 4.2.1.1, counted from 1) unless
//     zero_based_index is set.
//   - Error numbers above 100 are device-specific (C 4.2.1.1 Tabelle 4.3): see kError* below.
//   - Parameter description (PBE, C 6 Bild 6.1 is missing from our copy of the spec): elements
//     1 identifier (bits 0..7 data type 3 = I2, 6 = O2, 7 = O4 as in the drive profile; bit 9
//     read-only, bit 10 text available, bit 11 active parameter (sends spontaneous reports),
//     bit 14 array), 2 number of array elements, 3 standardisation factor (float 1.0), 4 variable
//     attribute (1 word), 5 reserved (2 words), 6 name (16 characters, 8 words), 7 lower and
//     8 upper limit (the parameter's width), 9 reserved (1 word), 10 identifier extension.
//   - Text elements are 16 characters (C 8 example 7: "Nach /1/ immer 16 Zeichen groß"), the
//     first character in the high byte of the first word (C 6: characters go in storage order).
//
// The parameter table (values after power-on):
//   P1    firmware version        O2  read-only           0x0100
//   P2    actual speed            I2  read-only           = HIW (0x4000 = nominal speed)
//   P4    speed table             O4  array [4], active   (C 8 example 5: dword to place 2)
//   P7    baud rate               O2  1..10, active       8; text per value, y = value + 1
//                                                          (C 8 example 7)
//   P18   ramp time               O2                      (C 8 example 6: word 0x7000)
//   P20   travel counter          O4  active              0
//   P41   comparison speed        O2  0..0x7FFF           0x4000 (ZSW bit 10 threshold)
//   P52   reference speed         O2                      0x4000 (C 8 example 2)
//   P60   fault number            O2  read-only           0 none, 1 injected, 2 telegram failure
//   P683  bus address             O2  array [3], 0..30    texts per place "SST 1", "SCB",
//                                                          "SST 2" (C 3.2 P683)
#pragma once

#include <array>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

#include "common/mono_time.hpp"
#include "uss/line.hpp"
#include "uss/pkw.hpp"
#include "uss/receiver.hpp"
#include "uss/telegram.hpp"

namespace liftd::uss::sim {

/// Device-specific error numbers (C 4.2.1.1 Tabelle 4.3: "Fehlerkennung größer 100 können
/// gerätespezifisch belegt werden").
/// 101: the reply does not fit the configured PKW length ("Mit fester Telegrammlänge nicht
/// möglich", C 8 example 3; C 7: "Wird vom Master ein Auftrag erstellt, der eine Antwort zur
/// Folge hätte, die über die eingestellte Größe des PKW-Bereiches hinausgeht ...").
inline constexpr std::uint16_t kErrorPkwTooShort = 101;
/// 102: a reserved request id (C 4.2.1.1 Tabelle 4.3: "1010 Reserve -> Auftrag nicht ausführbar").
inline constexpr std::uint16_t kErrorReservedRequest = 102;

/// What a special telegram (ADR bit 7, A 5.4) makes the simulated slave do.
enum class UssSpecialMode : std::uint8_t {
  Echo,    ///< answer with the same address byte and payload (device-specific loopback)
  Ignore,  ///< drop it like every drive-profile slave (A 4.3)
};

/// The motor and the lift car behind the drive.
struct UssCarConfig {
  double nominal_mps = 1.0;        ///< car speed at HSW = 0x4000 (100 %, C 5.2.2)
  double accel_mps2 = 0.5;         ///< the ramp generator: acceleration and deceleration (OFF1)
  double quick_stop_mps2 = 1.2;    ///< OFF3, and STW bit 4 = 0 ("an der Stromgrenze")
  double brake_mps2 = 0.0;         ///< the brake on a moving car without pulses; 0 = at once
  double tolerance_percent = 1.0;  ///< ZSW bit 8: |actual - setpoint| band, % of nominal
  double start_mm = 0.0;           ///< where the car stands at power-on
  double bottom_mm = -200.0;       ///< the pit buffer: the car cannot go lower
  double top_mm = 30000.0;         ///< the top of the shaft: the car cannot go higher
  std::vector<double> floors_mm;   ///< floor levels, for floor_at()
};

/// One simulated slave.
struct UssSlaveConfig {
  std::uint8_t address = 0;                   ///< 0..31 (A 4.3)
  uss::PkwLength pkw = uss::PkwLength::Four;  ///< PKW_ANZ (C 3.1)
  std::uint8_t pzd_words = 2;                 ///< PZD_ANZ 0..16 (C 3.1)
  /// Time from the request's BCC to the reply's STX (A 5.2.1.1: at most 20 ms; raised to the
  /// start pause if shorter: "darf jedoch nicht kleiner als die Startpause sein").
  std::chrono::nanoseconds reply_delay = std::chrono::milliseconds(2);
  /// The injected late reply: beyond the master's 20 ms.
  std::chrono::nanoseconds late_reply_delay = std::chrono::milliseconds(25);
  /// C 3.1 "Telegrammausfallzeit" (factory setting 1 s; 0 = no monitoring): with no good
  /// telegram for this long after the first one the drive trips (fault number 2).
  std::chrono::nanoseconds telegram_timeout = std::chrono::seconds(1);
  /// C 5.2.1 STW bit 0 t_wart: "Ready" without enable for this long falls back to switch-on
  /// inhibit; 0 = forever ("20 min wird wie unendlich interpretiert").
  std::chrono::nanoseconds ready_timeout{0};
  UssSpecialMode special = UssSpecialMode::Echo;
  bool zero_based_index = false;  ///< array place IND = 0 is the first element
  /// How many undelivered repeats of a request a master may give up after (C 4.2.1.1 "Erhält
  /// der Auftraggeber ... keine zum Auftrag gehörende Antwortkennung, so ist im Auftraggeber
  /// für eine entsprechende Reaktion zu sorgen"); an earlier change is recorded as a violation.
  std::uint32_t pkw_give_up_repeats = 10;
  UssCarConfig car;
};

/// The drive's state in the drive profile (C 5.2.1; PROFIBUS profile states).
enum class UssDriveState : std::uint8_t {
  SwitchOnInhibit,   ///< ZSW bit 6: after power-on, OFF2, OFF3 and a fault acknowledge
  ReadyToSwitchOn,   ///< ZSW bit 0: OFF1 with OFF2 and OFF3 lifted
  Ready,             ///< ZSW bits 0, 1: ON
  OperationEnabled,  ///< ZSW bits 0..2: pulses enabled, the car follows the ramp
  RampStop,          ///< OFF1 in operation: down the ramp, then ready to switch on
  QuickStop,         ///< OFF3 in operation: quick stop, then switch-on inhibit
  Fault,             ///< ZSW bit 3: left only on a rising edge of STW bit 7, cause removed
};
/// "switch_on_inhibit", "ready_to_switch_on", ...
std::string_view to_string(UssDriveState state) noexcept;

/// Faults injected into the next replies (a count each).
enum class UssReplyFault : std::uint8_t {
  Silent,  ///< no reply (the telegram is still executed)
  BadBcc,  ///< BCC inverted in bit 0
  BadLge,  ///< LGE one higher (BCC computed over the wrong LGE, so only the length is wrong)
  Parity,  ///< the reply's address byte is to be sent with a parity error
  Late,    ///< sent after late_reply_delay instead of reply_delay
  Stale,   ///< the PKW area answers the previous request once (C 4.2.1.1 transition phase)
};
inline constexpr std::size_t kUssReplyFaultCount = 6;
/// "silent", "badbcc", "badlge", "parity", "late", "stale".
std::string_view to_string(UssReplyFault fault) noexcept;
/// Parses those names.
std::optional<UssReplyFault> parse_uss_reply_fault(std::string_view name) noexcept;

/// A reply ready for the line.
struct UssReply {
  std::array<std::uint8_t, uss::kMaxTelegramBytes> bytes{};
  std::size_t size = 0;
  MonoTime send_at{};  ///< earliest time to start sending the STX
  /// Until when a master certainly waits for this reply: the end of the bus's last reply before
  /// the request (the earliest the master can have sent it), the start pause and the longest
  /// reply delay (A 5.1.2, A 5.2.1.1: 20 ms). A telegram that arrives before then broke a rule
  /// for certain; one that arrives later may come from a master that rightly gave up on a reply
  /// the machine delayed (see UssSlaveStats::unjudged).
  MonoTime awaited_until{};
  int parity_error_at = -1;  ///< index of the byte to send with a parity error; -1 = none
  std::uint8_t address = 0;  ///< the slave that answers
  std::span<const std::uint8_t> view() const noexcept { return {bytes.data(), size}; }
};

/// Something the master did that the spec forbids.
struct UssViolation {
  MonoTime at{};
  std::uint8_t address = 0;
  std::string_view rule;  ///< the spec's rule, quoted by chapter (static text)
};

/// Counts of what the slave did.
struct UssSlaveStats {
  std::uint64_t telegrams = 0;     ///< good telegrams addressed to this slave (normal)
  std::uint64_t replies = 0;       ///< replies handed out (all kinds)
  std::uint64_t mirrors = 0;       ///< mirror telegrams answered
  std::uint64_t broadcasts = 0;    ///< broadcasts taken (never answered)
  std::uint64_t specials = 0;      ///< special telegrams received for this slave
  std::uint64_t undefined = 0;     ///< telegrams with an undefined ADR type (no reaction)
  std::uint64_t pkw_requests = 0;  ///< new PKW requests (a change of the request, C 4.2.1.1)
  std::uint64_t pkw_errors = 0;    ///< replies "Auftrag nicht ausführbar" to new requests
  std::uint64_t eeprom_writes = 0;
  std::uint64_t spontaneous = 0;  ///< spontaneous reports started
  std::uint64_t spontaneous_acknowledged = 0;
  std::uint64_t faulted_replies = 0;  ///< replies changed or withheld by injected faults
  std::uint64_t telegram_timeouts = 0;
  std::uint64_t violations = 0;
  /// Timing rules (A 5, A 5.1.2) seen broken by a telegram that came after the master may have
  /// given up on our reply (UssReply::awaited_until): on a pseudo-terminal characters arrive
  /// only when the machine delivers them, so the slave cannot tell a late delivery from a master
  /// at fault and counts the case here instead of as a violation.
  std::uint64_t unjudged = 0;
};

/// The drive and car as the slave sees them.
struct UssDriveView {
  UssDriveState state = UssDriveState::SwitchOnInhibit;
  std::uint16_t stw = 0;           ///< the control word in effect
  std::int16_t hsw = 0;            ///< the main setpoint in effect
  std::uint16_t zsw = 0;           ///< the status word as sent now
  std::int16_t hiw = 0;            ///< the main actual value as sent now
  double position_mm = 0.0;        ///< the car
  double velocity_mps = 0.0;       ///< + up
  bool brake_open = false;         ///< the car can move (operation enabled)
  std::uint16_t fault_number = 0;  ///< P60
  bool fault_cause = false;        ///< the cause of the fault is still there
};

class UssSlaveSim {
 public:
  /// Throws std::invalid_argument for an address above 31 or more than 16 PZD words.
  UssSlaveSim(const UssSlaveConfig& config, std::uint32_t baud, MonoTime now);

  // ---- the line ----
  /// One received character (A 5.2).
  void on_char(const uss::RxChar& c, MonoTime at) noexcept;
  /// Residual-time supervision and the car model up to now.
  void on_time(MonoTime now) noexcept;
  /// When on_time must be called at the latest (residual time of a telegram in progress).
  std::optional<MonoTime> deadline() const noexcept { return receiver_.deadline(); }
  /// When the next reply is due; nullopt when none is queued.
  std::optional<MonoTime> next_reply_at() const noexcept;
  /// The next reply if it is due at `now` (send_at <= now); false otherwise.
  bool take_reply(MonoTime now, UssReply& out) noexcept;
  /// The bus carried a reply (ours or another slave's) until `end`: the master's next STX must
  /// follow a start pause after it (A 5.1.2).
  void reply_sent(MonoTime end) noexcept { bus_quiet_from_ = end; }
  /// The same, with the time until which the master certainly waited for that reply.
  void reply_sent(MonoTime end, MonoTime awaited_until) noexcept {
    bus_quiet_from_ = end;
    last_reply_awaited_until_ = awaited_until;
  }
  /// Moves the car up to `now` (also done by every other call).
  void advance(MonoTime now) noexcept;

  // ---- injection ----
  /// The next `count` replies get `fault` (0 clears it).
  void inject(UssReplyFault fault, std::uint32_t count) noexcept;
  void clear_faults() noexcept;
  /// A drive fault (ZSW bit 3) while `on`; switching it off removes the cause, the drive stays
  /// in Fault until the master acknowledges (rising edge of STW bit 7).
  void set_drive_fault(bool on) noexcept;
  void set_warning(bool on) noexcept { warning_ = on; }
  /// Local operation: ZSW bit 9 = 0 and the process data are not taken.
  void set_local(bool on) noexcept { local_ = on; }
  /// "keine PKW-Bedienhoheit": change and EEPROM requests answered with reply id 8.
  void set_pkw_authority(bool on) noexcept { authority_ = on; }
  /// A parameter changed from elsewhere (the panel, another interface): active parameters are
  /// reported spontaneously (C 4.2.1.2). `place` = array place as the master numbers it (ignored
  /// for simple parameters). False for an unknown parameter, place or a value out of range.
  bool change_parameter(std::uint16_t pnu, std::uint8_t place, std::uint32_t value) noexcept;
  /// Moves a stationary car (drift); ignored while it moves.
  void move_car(double mm) noexcept;

  // ---- reading ----
  std::uint8_t address() const noexcept { return config_.address; }
  const UssSlaveConfig& config() const noexcept { return config_; }
  UssDriveView drive() const noexcept;
  UssDriveState state() const noexcept { return state_; }
  double position_mm() const noexcept { return position_mm_; }
  double velocity_mps() const noexcept { return speed_mps_; }
  /// The floor (index into car.floors_mm) the car stands within `tolerance_mm` of, or -1.
  int floor_at(double tolerance_mm = 5.0) const noexcept;
  /// A parameter value (place as the master numbers it); nullopt if unknown.
  std::optional<std::uint32_t> parameter(std::uint16_t pnu, std::uint8_t place = 0) const noexcept;
  /// Spontaneous reports waiting (the one on the wire included).
  std::size_t reports_pending() const noexcept;
  const UssSlaveStats& stats() const noexcept { return stats_; }
  const uss::RxCounters& rx_counters() const noexcept { return receiver_.counters(); }
  /// Moves up to out.size() recorded violations (oldest first) into out; returns how many.
  std::size_t take_violations(std::span<UssViolation> out) noexcept;

 private:
  struct Param {
    std::uint16_t pnu = 0;
    std::string_view name;      // description element 6 (up to 16 characters)
    std::uint8_t type = 6;      // drive-profile data type: 3 = I2, 6 = O2, 7 = O4
    std::uint8_t elements = 0;  // 0 = simple parameter, n = array of n
    bool read_only = false;
    bool active = false;  // changes are reported spontaneously (C 4.2.1.2)
    std::uint32_t min = 0;
    std::uint32_t max = 0xFFFF;
    std::size_t value_at = 0;        // first slot in values_
    std::size_t place_texts_at = 0;  // texts per array place (y = place, counted from 1)
    std::size_t place_texts = 0;
    std::size_t value_texts_at = 0;  // texts per value (y = value + 1)
    std::size_t value_texts = 0;
    bool dword() const noexcept { return type == 7; }
  };
  struct Report {
    std::uint16_t pnu = 0;
    std::uint8_t place = 0;  // wire IND low byte
  };
  struct Request {  // a PKW request without the toggle bit (C 4.2.1.1 "jede Änderung")
    uss::Pkw pkw;
    bool valid = false;
  };

  void on_complete(MonoTime at) noexcept;
  void on_normal(uss::Telegram t, MonoTime at) noexcept;
  void on_broadcast(uss::Telegram t, MonoTime at) noexcept;
  void queue_echo(std::span<const std::uint8_t> bytes, MonoTime at) noexcept;
  void queue(UssReply& reply, MonoTime at, bool carries_answer) noexcept;
  void apply_pzd(std::span<const std::uint16_t> pzd, MonoTime at) noexcept;
  void apply_stw(std::uint16_t stw, MonoTime at) noexcept;
  void enter(UssDriveState s, MonoTime at) noexcept;
  void good_telegram(MonoTime at) noexcept;
  std::uint16_t make_zsw() const noexcept;
  std::int16_t make_hiw() const noexcept;
  void refresh_live() noexcept;

  uss::Pkw pkw_reply(const uss::Pkw& request, MonoTime at) noexcept;
  uss::Pkw execute(const uss::Pkw& request, bool repeat, MonoTime at) noexcept;
  uss::Pkw error(const uss::Pkw& request, std::uint16_t number) const noexcept;
  uss::Pkw report_pkw() const noexcept;
  bool value_reply(const Param& p, std::size_t slot, std::uint8_t id_word, std::uint8_t id_dword,
                   std::uint16_t ind, uss::Pkw& out) const noexcept;
  void push_report(std::uint16_t pnu, std::uint8_t place) noexcept;
  const Param* find(std::uint16_t pnu) const noexcept;
  std::optional<std::size_t> slot_of(const Param& p, std::uint8_t place) const noexcept;
  std::uint8_t wire_place(std::size_t element) const noexcept;
  std::size_t pkw_capacity() const noexcept;  // PWE words the reply may carry
  void violation(MonoTime at, std::string_view rule) noexcept;
  /// A timing rule broken by a telegram that arrived at `at`: a violation if a master waiting
  /// as the spec says still waited for our reply then (`awaited_until`), unjudged otherwise.
  void timing_rule(MonoTime at, MonoTime awaited_until, std::string_view rule) noexcept;

  UssSlaveConfig config_;
  std::uint32_t baud_;
  uss::Receiver receiver_;
  std::chrono::nanoseconds reply_delay_;
  std::chrono::nanoseconds start_pause_;

  // line
  bool was_receiving_ = false;
  MonoTime stx_at_{};
  std::optional<MonoTime> bus_quiet_from_;
  MonoTime last_reply_awaited_until_{};  // of the reply that set bus_quiet_from_
  std::array<UssReply, 4> replies_{};    // ordered by send_at
  std::array<bool, 4> reply_late_{};     // the reply is an injected late one
  std::size_t reply_count_ = 0;
  std::array<std::uint32_t, kUssReplyFaultCount> faults_{};

  // parameters
  std::vector<Param> params_;
  std::vector<std::uint32_t> values_;
  std::vector<std::array<char, 16>> texts_;
  bool authority_ = true;
  Request request_;               // the request in work
  uss::Pkw answer_{};             // its answer
  uss::Pkw previous_answer_{};    // the answer to the request before (stale fault)
  bool answer_delivered_ = true;  // the answer went out in an undamaged reply
  std::uint32_t undelivered_repeats_ = 0;
  bool toggle_ = false;              // the slave's toggle bit (C 4.2.1.2)
  bool toggle_seen_ = false;         // the master's toggle is known
  bool master_toggle_ = false;       // the master's toggle in its last request
  std::array<Report, 8> reports_{};  // reports_[0] is on the wire while report_active_
  std::size_t report_count_ = 0;
  bool report_active_ = false;

  // drive
  UssDriveState state_ = UssDriveState::SwitchOnInhibit;
  std::array<std::uint16_t, uss::kMaxPzdWords> pzd_in_{};  // process data in effect
  std::uint16_t stw_ = 0;
  bool fault_injected_ = false;
  bool telegram_failed_ = false;
  std::uint16_t fault_number_ = 0;
  bool warning_ = false;
  bool local_ = false;
  MonoTime ready_since_{};
  bool have_good_ = false;
  MonoTime last_good_{};
  MonoTime last_advance_;
  double speed_mps_ = 0.0;
  double position_mm_ = 0.0;

  UssSlaveStats stats_{};
  std::array<UssViolation, 64> violations_{};
  std::size_t violation_first_ = 0;
  std::size_t violation_count_ = 0;
};

/// Several slaves on one bus line.
class UssBusSim {
 public:
  /// Throws std::invalid_argument for an empty list, a bad slave config or a repeated address
  /// (A 5.4: "Eine Adresse (Bit 0 bis 4) darf nur einmal am Bus vorkommen").
  UssBusSim(std::span<const UssSlaveConfig> slaves, std::uint32_t baud, MonoTime now);

  /// One character from the line, to every slave.
  void on_char(const uss::RxChar& c, MonoTime at) noexcept;
  void on_time(MonoTime now) noexcept;
  std::optional<MonoTime> deadline() const noexcept;
  std::optional<MonoTime> next_reply_at() const noexcept;
  /// The earliest due reply of any slave; tells every slave the bus is busy until it ends.
  bool take_reply(MonoTime now, UssReply& out) noexcept;
  /// The reply's last byte left at `end` (overrides the assumed end).
  void reply_sent(MonoTime end) noexcept;
  void advance(MonoTime now) noexcept;

  std::uint32_t baud() const noexcept { return baud_; }
  /// The slave with this address, or nullptr.
  UssSlaveSim* slave(std::uint8_t address) noexcept;
  const UssSlaveSim* slave(std::uint8_t address) const noexcept;
  std::span<UssSlaveSim> slaves() noexcept { return slaves_; }
  std::span<const UssSlaveSim> slaves() const noexcept { return slaves_; }
  /// Violations of all slaves (oldest first per slave).
  std::size_t take_violations(std::span<UssViolation> out) noexcept;

 private:
  std::uint32_t baud_;
  std::vector<UssSlaveSim> slaves_;
};

}  // namespace liftd::uss::sim
