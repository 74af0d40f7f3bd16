// The USS master engine (spec chapter A 2, A 3, A 5; chapter C 4 for the PKW channel), sans-I/O:
// it decides which telegram goes out next and when, supervises the reply delay, takes the
// received characters apart with a uss::Receiver, keeps every slave's link state and runs one
// PKW request per slave. It owns no port and reads no clock: a runner (uss::UssRunner) or a test
// passes every time in. No allocation, lock or exception after construction.
//
// The order of calls for one exchange (runner side, one thread):
//   wait until send_at(); bytes = next_telegram(now); write them;
//   on_sent(time the last byte leaves the line);
//   while (awaiting_reply()) { feed on_char(c, t) for each received character, or call
//                              on_time(now) once now >= deadline() }
// The user side (set_pzd, submit_pkw, poll_*, ...) runs on the same thread between exchanges.
//
// Decisions (each with the spec sentence it rests on):
//  - Polling list (A 5.1): "Die Reihenfolge der angesprochenen Slaveteilnehmer kann z.B. durch
//    Eintrag der Teilnehmernummern (ADR) in einer Umlaufliste angegeben werden ... kann deren
//    Teilnehmernummer mehrmals in der Umlaufliste vorkommen." One pass = the list once.
//  - Start pause (A 5.1.2): "vor dem STX eine zeichenlose Startpause von mindestens 2
//    Zeichenlaufzeiten". send_at() is the end of the last character on the line (our request's
//    last byte, or the reply's) plus start_pause(baud). A received telegram of k characters
//    occupies the line for at least k character times from its STX, so its end is taken as
//    max(time of its last character, STX stamp - 1 character time + k character times): on a line
//    that delivers characters faster than the baud rate (a pty) the pause is still kept.
//  - Reply delay (A 5.2.1.1): "Das Zeitintervall zwischen dem letzten Zeichen des
//    Auftragstelegramms (BCC) und dem Beginn des Antworttelegramms (STX) ... beträgt 20 ms, darf
//    jedoch nicht kleiner als die Startpause sein." A received character is stamped when it is
//    complete, so the STX may be stamped up to reply_delay + 1 character time after on_sent();
//    deadline() is the first late instant (that + 1 ns), like Receiver::deadline().
//  - "Antwortet der Teilnehmer x nicht innerhalb der maximal zulässigen Antwortverzugszeit, wird
//    im Master die Fehlermeldung 'Teilnehmer x sendet nicht' hinterlegt ... erst nach einem
//    fehlerfreien Telegramm vom Teilnehmer x gelöscht. Der Teilnehmer x wird nicht aus der
//    Umlaufliste gelöscht." A timeout or an unusable reply (rejected by the receiver, wrong
//    address, a payload that does not fit the slave's PKW/PZD lengths, a mirror that differs)
//    sets responding = false at once; the next good reply sets it again. Characters that are
//    not an STX before the reply (line noise, A 5.2.3 counter 12) do not end the wait.
//  - Fixed cycle time (A 5.1.1): "Nach dem Datenaustausch mit dem letzten Teilnehmer muß er
//    warten, bis die definierte Zykluszeit abgelaufen ist und ein neuer Umlauf beginnt." The
//    first poll of a pass is not sent before the previous pass's start + cycle_time.
//  - PKW (C 4.2.1.1): "Der Auftraggeber darf immer nur einen Auftrag an eine Schnittstelle
//    stellen ... Solange auf die Antwortkennung gewartet wird, muß der Auftraggeber seinen
//    Auftrag wiederholen!" One request per slave, sent in every poll of that slave until
//    classify_reply() says Matches / Error / NoAuthority; Unrelated replies (the old request's
//    answers, "Übergangsphase zwischen Alt-Auftrag und Neu-Auftrag") are ignored and counted.
//    "Erhält der Auftraggeber ... keine zum Auftrag gehörende Antwortkennung, so ist im
//    Auftraggeber für eine entsprechende Reaktion zu sorgen": after pkw_repeat_limit polls
//    without the matching reply the request ends as Unanswered. Without a request the master
//    sends "kein Auftrag" (AK 0) and ignores the "keine Antwort" replies.
//  - Spontaneous reports (C 4.2.1.2): the slave changes PKE bit 11 with each new report and
//    repeats it "bis dieser [der Master] durch ändern des Toggle-Bits (Bit 11) den sicheren
//    Empfang der Spontanmeldung quittiert hat". The master sends its own toggle in bit 11 of
//    every request. A report (AK 9..12) whose bit 11 differs from it is new: it is surfaced
//    and the master takes the report's bit 11 as its own, which changes the bit in its next
//    request (the acknowledgement). A report whose bit equals it is a repeat of an acknowledged
//    one and is ignored. The figure (Bild 4.5) is missing from our copy; when a slave is heard
//    for the first time (or again after "does not send") the master adopts the toggle of its
//    first non-report reply, so a slave that restarted with bit 11 = 0 is not taken for one
//    that has all its reports acknowledged. A poll answered by a report does not count
//    against pkw_repeat_limit (the slave interrupted the answer, C 4.2.1.2).
//  - Mirror (A 5.3): "Dieses Telegramm unterscheidet sich vom normalen Telegramm nur dadurch,
//    daß das Bit Nr. 6 des Adreßbytes gesetzt ist. Der Slave sendet (spiegelt) dieses
//    Telegramm ohne irgendwelche Veränderungen". The mirror carries the slave's next normal
//    payload; the reply must equal the sent telegram byte for byte.
//  - Broadcast (A 3, appendix): ADR bit 5, the 4-word broadcast enable array in the PKW area,
//    "Auf ein Broadcast-Telegramm darf von den einzelnen Slaves kein Antworttelegramm gesendet
//    werden": no reply is awaited; the next telegram follows after the start pause.
//  - Special telegrams (A 5.4): ADR bit 7 (with bit 5: to every slave that handles them, no
//    reply), payload passed through unchanged; a reply is accepted with any length whose ADR
//    bits 0..4 name the slave.
//  - Broadcasts, special telegrams and mirrors asked for by the user go out between two polls,
//    at most one after each poll, so the polling never stops. Mirrors of mirror_at_start go out
//    once before the first poll.
#pragma once

#include <array>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "common/defaults.hpp"
#include "common/fixed_queue.hpp"
#include "common/mono_time.hpp"
#include "uss/defaults.hpp"
#include "uss/line.hpp"
#include "uss/pkw.hpp"
#include "uss/pzd.hpp"
#include "uss/receiver.hpp"
#include "uss/telegram.hpp"
#include "uss/timing.hpp"

namespace liftd::uss {

/// One slave on the bus.
struct SlaveConfig {
  std::uint8_t address = 0;         ///< 0..31 (A 4.3)
  PkwLength pkw = PkwLength::Four;  ///< PKW_ANZ of the slave (C 3.1): 0, 3, 4 or 127
  std::uint8_t pzd_words = 2;       ///< PZD_ANZ of the slave (C 3.1): 0..16
};

/// The bus as the master sees it.
struct MasterConfig {
  std::uint32_t baud = defaults::kUssBaud;  ///< A 5.1.2 Tabelle 5.1: 9600, 19200, 38400, 187500
  std::vector<SlaveConfig> slaves;
  /// Umlaufliste (A 5.1): addresses of configured slaves in any order, repeats allowed.
  std::vector<std::uint8_t> polling_list;
  /// How long to wait for the reply's STX after our BCC (A 5.2.1.1): at most 20 ms, at least
  /// the start pause.
  std::chrono::nanoseconds reply_delay = std::chrono::milliseconds(defaults::kUssReplyDelayMs);
  /// Fixed cycle time (A 5.1.1): a pass does not start before the previous one's start + this.
  std::optional<std::chrono::nanoseconds> cycle_time;
  /// Polls of a slave with a PKW request and no matching reply before it ends as Unanswered.
  std::uint32_t pkw_repeat_limit = defaults::kUssPkwRepeatLimit;
  /// Send a mirror telegram (A 5.3) to every configured slave once before the first poll.
  bool mirror_at_start = true;
  /// The slaves' usual reply delay (their processing time, A 5.1.1 Bild 5.2), used only for
  /// expected_cycle_time(); unset = reply_delay (the longest wait, A 5.2.1.1).
  std::optional<std::chrono::nanoseconds> expected_reply_delay;
};

/// Tag of the mirror results that mirror_at_start produces.
inline constexpr std::uint32_t kStartMirrorTag = 0xFFFFFFFFU;

/// The link and process data of one slave.
struct SlaveState {
  bool configured = false;  ///< the address is in MasterConfig::slaves
  bool heard = false;       ///< a good reply came at least once
  /// A good reply came and no failure since; false = "Teilnehmer x sendet nicht" (A 5.2.1.1)
  /// or not heard yet.
  bool responding = false;
  std::uint32_t consecutive_failures = 0;  ///< timeouts / unusable replies since the last good
  std::uint64_t good = 0;                  ///< good replies
  std::uint64_t failures = 0;              ///< timeouts and unusable replies
  std::array<std::uint16_t, kMaxPzdWords> pzd_in{};  ///< PZD of the last good reply (C 5)
  std::uint8_t pzd_in_count = 0;                     ///< words in pzd_in
  MonoTime last_good{};                              ///< when the last good reply completed
  bool pkw_busy = false;  ///< a PKW request runs, or its result waits for poll_pkw_result()
};

/// The end of one PKW request.
struct PkwResult {
  std::uint32_t tag = 0;     ///< as given to submit_pkw()
  std::uint8_t address = 0;  ///< slave
  enum class Outcome : std::uint8_t {
    Done,         ///< the matching positive reply (C 4.2.1.1 Tabelle 4.3)
    Error,        ///< AK 7 "Auftrag nicht ausführbar": error_number says why
    NoAuthority,  ///< AK 8 "keine PKW-Bedienhoheit"
    Unanswered,   ///< pkw_repeat_limit polls without the matching reply
  } outcome = Outcome::Done;
  Pkw reply;                       ///< the reply (Done, Error, NoAuthority)
  std::uint16_t error_number = 0;  ///< Error: uss::error_number() of the reply
};

/// A spontaneous report (C 4.2.1.2), surfaced once (repeats before our acknowledgement are not).
struct SpontaneousReport {
  std::uint8_t address = 0;
  Pkw report;  ///< AK 9..12, PNU, IND, the changed value
  MonoTime at{};
};

/// The outcome of one mirror telegram (A 5.3).
struct MirrorResult {
  std::uint32_t tag = 0;  ///< as given to request_mirror(), kStartMirrorTag for the start test
  std::uint8_t address = 0;
  bool ok = false;  ///< the reply came in time and equals the sent telegram byte for byte
  /// From the start of sending the mirror to its returned last character (0 if none came).
  std::chrono::nanoseconds round_trip{0};
};

/// The outcome of one special telegram with a reply (A 5.4).
struct SpecialResult {
  std::uint32_t tag = 0;  ///< as given to send_special()
  std::uint8_t address = 0;
  bool answered = false;  ///< a valid telegram from this address came in time
  std::uint8_t adr = 0;   ///< the reply's address byte
  std::uint8_t size = 0;  ///< payload bytes in `payload`
  std::array<std::uint8_t, kMaxPayloadBytes> payload{};
  std::span<const std::uint8_t> data() const noexcept { return {payload.data(), size}; }
};

/// A slave's "sendet nicht" flag changed (A 5.2.1.1).
struct LinkChange {
  std::uint8_t address = 0;
  bool responding = false;  ///< true: a good reply; false: flagged "does not send"
  MonoTime at{};
};

/// How the last exchange ended (for the runner's statistics and flight recorder).
enum class ExchangeOutcome : std::uint8_t {
  None,             ///< nothing sent yet
  Reply,            ///< a good reply
  BadReply,         ///< a reply that was rejected or did not fit
  Timeout,          ///< no reply by the deadline (A 5.2.1.1)
  NoReplyExpected,  ///< broadcast (A 3) or special broadcast (A 5.4)
  Abandoned,        ///< the port went away (reset_link)
};

/// What a telegram was.
enum class TelegramKind : std::uint8_t { Poll, Mirror, Broadcast, Special, SpecialBroadcast };

/// The master's own counters (the receive-side ones are rx_counters()).
struct MasterCounters {
  std::uint64_t polls = 0;                 ///< normal telegrams sent (A 5)
  std::uint64_t mirrors = 0;               ///< mirror telegrams sent (A 5.3)
  std::uint64_t broadcasts = 0;            ///< broadcast telegrams sent (A 3)
  std::uint64_t specials = 0;              ///< special telegrams sent (A 5.4), broadcast or not
  std::uint64_t good_replies = 0;          ///< replies that passed every check
  std::uint64_t bad_replies = 0;           ///< replies rejected by the receiver or below
  std::uint64_t wrong_address = 0;         ///< of those: valid telegram, wrong ADR (A 5.2)
  std::uint64_t bad_payload = 0;           ///< of those: length does not fit the PKW/PZD setting
  std::uint64_t mirror_mismatches = 0;     ///< of those: a mirror that came back changed
  std::uint64_t reply_timeouts = 0;        ///< no reply by the deadline (A 5.2.1.1)
  std::uint64_t pkw_stale_replies = 0;     ///< replies not belonging to the running request
  std::uint64_t pkw_unanswered = 0;        ///< requests ended as Unanswered
  std::uint64_t spontaneous = 0;           ///< new spontaneous reports (C 4.2.1.2)
  std::uint64_t spontaneous_repeats = 0;   ///< reports seen again before our acknowledgement
  std::uint64_t dropped_reports = 0;       ///< spontaneous reports lost: queue full
  std::uint64_t dropped_link_changes = 0;  ///< link changes lost: queue full
  std::uint64_t dropped_results = 0;       ///< mirror / special results lost: queue full
  std::uint64_t stray_chars = 0;           ///< characters while no reply was awaited
  std::uint64_t abandoned = 0;             ///< exchanges cut by reset_link()
};

/// The master engine. Everything is allocated in the constructor.
class Master {
 public:
  /// Checks the configuration and throws std::invalid_argument with a text naming the
  /// offending entry and the spec rule: baud 0; a slave address above 31 or twice; PZD words
  /// above 16; a PKW length other than 0, 3, 4, 127; an empty polling list or one naming an
  /// unconfigured address; reply_delay above 20 ms or below the start pause (A 5.2.1.1); a
  /// cycle_time of 0 or less; pkw_repeat_limit 0.
  explicit Master(MasterConfig config);
  Master(const Master&) = delete;
  Master& operator=(const Master&) = delete;

  // ---- runner side ----

  /// The telegram to send now (an empty span while a reply is awaited). The bytes stay valid
  /// until the next call. `now` is when sending starts (it starts a pass's cycle time).
  std::span<const std::uint8_t> next_telegram(MonoTime now) noexcept;
  /// The earliest time the next telegram may start: the end of the last character on the line
  /// plus the start pause (A 5.1.2), and for the first poll of a pass with a fixed cycle time
  /// not before the previous pass's start + cycle_time (A 5.1.1).
  MonoTime send_at() const noexcept;
  /// The telegram from next_telegram() has left the line at `end_of_last_byte` (the runner
  /// adds transmission_time() to the write time). Starts the reply supervision.
  void on_sent(MonoTime end_of_last_byte) noexcept;
  /// A reply is awaited: feed characters or call on_time() by deadline().
  bool awaiting_reply() const noexcept { return phase_ == Phase::Awaiting; }
  /// One received character, stamped when it was received.
  void on_char(const RxChar& c, MonoTime at) noexcept;
  /// While awaiting a reply: the first instant at which the wait is over without further
  /// characters (the reply delay before the STX, the residual time after it). MonoTime::max()
  /// otherwise.
  MonoTime deadline() const noexcept;
  /// Time supervision: ends the exchange once now >= deadline().
  void on_time(MonoTime now) noexcept;
  /// While awaiting a reply: the runner read our telegram back changed on an echoing line (a
  /// collision), so the slave did not receive it intact and must not answer it (A 5.2.2). The
  /// exchange ends as a bad one (counted in bad_replies, a failure of the slave as a rejected
  /// reply is, A 5.2.1.1); the line counts as busy until `at`.
  void on_collision(MonoTime at) noexcept;
  /// The port (re)opened or went away: an exchange in progress is dropped (its PKW poll is not
  /// counted, a mirror or special waiting for its reply fails), the line counts as quiet from
  /// `now`, so the next telegram keeps a full start pause, and every slave's process data from
  /// before is void (not responding, no PZD) until it answers again.
  void reset_link(MonoTime now) noexcept;
  /// How the last exchange ended.
  ExchangeOutcome last_outcome() const noexcept { return last_outcome_; }
  /// What the last telegram from next_telegram() was, and to whom (0 for broadcasts).
  TelegramKind last_kind() const noexcept { return current_.kind; }
  std::uint8_t last_address() const noexcept { return current_.address; }

  // ---- user side (same thread as the runner side, between exchanges) ----

  /// The PZD words (C 5) sent to a slave from its next poll on; words beyond its PZD count are
  /// ignored, missing ones keep their value. No-op for an unconfigured address.
  void set_pzd(std::uint8_t address, std::span<const std::uint16_t> words) noexcept;
  /// A slave's state; an unconfigured address gives a state with configured = false.
  const SlaveState& slave(std::uint8_t address) const noexcept;
  /// Starts a PKW request (C 4.2.1.1). false if the address is not configured, has no PKW
  /// area, already has a request running or a result not yet polled, or the request does not
  /// fit the slave's PKW length (e.g. a double word with 3 words). The toggle bit of `request`
  /// is ignored (the master owns bit 11).
  bool submit_pkw(std::uint8_t address, const Pkw& request, std::uint32_t tag) noexcept;
  /// Takes one finished PKW request; false if none.
  bool poll_pkw_result(PkwResult& out) noexcept;
  /// Takes one spontaneous report; false if none.
  bool poll_spontaneous(SpontaneousReport& out) noexcept;
  /// Sends a mirror telegram to a configured slave between two polls. false if the address is
  /// not configured or a mirror for it is still pending.
  bool request_mirror(std::uint8_t address, std::uint32_t tag) noexcept;
  /// Takes one mirror result; false if none.
  bool poll_mirror(MirrorResult& out) noexcept;
  /// Queues a broadcast telegram (A 3, appendix): the broadcast enable array in a 4-word PKW
  /// area, then `pzd` (0..16 words). false if the queue is full or pzd is too long.
  bool send_broadcast(const BroadcastEnable& enable, std::span<const std::uint16_t> pzd) noexcept;
  /// Queues a special telegram (A 5.4, ADR bit 7) with a device-specific payload (0..252
  /// bytes) to `address` (0..31, need not be configured); `broadcast`: to every slave that
  /// handles special telegrams, no reply. false if the queue is full or the arguments are out
  /// of range.
  bool send_special(std::uint8_t address, bool broadcast, std::span<const std::uint8_t> payload,
                    std::uint32_t tag) noexcept;
  /// Takes one special-telegram result (not for special broadcasts); false if none.
  bool poll_special(SpecialResult& out) noexcept;
  /// Takes one change of a slave's "sendet nicht" flag; false if none.
  bool poll_link_change(LinkChange& out) noexcept;

  /// Receive diagnostics of A 5.2.3 (all replies; reply timeouts in counter 16).
  const RxCounters& rx_counters() const noexcept { return rx_.counters(); }
  /// The master's own counters.
  const MasterCounters& counters() const noexcept { return counters_; }
  /// Completed passes of the polling list (a pass completes when the next one starts).
  std::uint64_t cycles() const noexcept { return cycles_; }
  /// The cycle time from the spec's rules for the polling list (uss::expected_cycle_time():
  /// start pause, request, reply delay and reply of each entry, A 5.1.1), or the fixed
  /// cycle_time if that is longer. Idle PKW (AK 0) lengths; expected_reply_delay.
  std::chrono::nanoseconds expected_cycle_time() const noexcept { return expected_cycle_; }
  /// Start of the last completed pass to the start of the next one (0 before the first).
  std::chrono::nanoseconds last_cycle_time() const noexcept { return last_cycle_; }
  /// The configuration in use.
  const MasterConfig& config() const noexcept { return config_; }
  /// A 5.1.2: the start pause in use (2 character times).
  std::chrono::nanoseconds start_pause() const noexcept { return start_pause_; }

 private:
  static constexpr std::size_t kSlots = kMaxSlaveAddress + 1;
  static constexpr std::size_t kReportSlots = 32;
  static constexpr std::size_t kLinkSlots = 64;
  static constexpr std::size_t kResultSlots = 16;
  static constexpr std::size_t kExtraSlots = 8;

  enum class Phase : std::uint8_t { Idle, Sent, Awaiting };

  struct Slot {
    bool configured = false;
    SlaveConfig config;
    std::uint8_t reply_lge = 0;  // fixed reply LGE, 0 = variable (PKW 127)
    SlaveState state;
    std::array<std::uint16_t, kMaxPzdWords> pzd_out{};
    bool pkw_active = false;  // a request runs
    bool result_ready = false;
    Pkw request;
    std::uint32_t pkw_tag = 0;
    std::uint32_t pkw_polls = 0;  // polls with the request and no matching reply
    PkwResult result;
    bool toggle = false;        // our PKE bit 11 (C 4.2.1.2)
    bool toggle_known = false;  // adopted from the slave since it was last heard
    bool down_announced = false;
    bool mirror_pending = false;
    std::uint32_t mirror_tag = 0;
  };

  // A queued broadcast or special telegram, encoded when queued.
  struct Extra {
    TelegramKind kind = TelegramKind::Broadcast;
    std::uint8_t address = 0;
    std::uint32_t tag = 0;
    std::uint16_t size = 0;  // telegram bytes
    std::array<std::uint8_t, kMaxTelegramBytes> bytes{};
  };

  // The telegram in flight.
  struct Current {
    TelegramKind kind = TelegramKind::Poll;
    std::uint8_t address = 0;
    std::uint32_t tag = 0;
    bool carried_pkw = false;  // a poll that carried the running PKW request
    bool expects_reply = false;
    bool pass_start = false;
    MonoTime started{};
  };

  struct Choice {
    enum class What : std::uint8_t { Mirror, Extra, Poll } what = What::Poll;
    std::uint8_t address = 0;
  };

  Choice choose() const noexcept;
  std::size_t build_poll(Slot& s, std::uint8_t adr) noexcept;
  void end_exchange(ExchangeOutcome outcome) noexcept;
  void finish_reply(MonoTime at) noexcept;
  void finish_poll_reply(Slot& s, const Telegram& t, MonoTime at) noexcept;
  void fail_exchange(ExchangeOutcome outcome, MonoTime at) noexcept;
  void handle_pkw_reply(Slot& s, const Pkw& reply, MonoTime at) noexcept;
  void finish_pkw(Slot& s, PkwResult::Outcome outcome, const Pkw* reply) noexcept;
  void note_good(Slot& s, MonoTime at) noexcept;
  void note_failure(Slot& s, MonoTime at) noexcept;
  void push_mirror_result(bool ok, std::chrono::nanoseconds round_trip) noexcept;
  void push_special_result(bool answered) noexcept;
  MonoTime reply_deadline() const noexcept;

  MasterConfig config_;
  std::chrono::nanoseconds char_time_;
  std::chrono::nanoseconds start_pause_;
  std::chrono::nanoseconds expected_cycle_{0};
  std::array<Slot, kSlots> slots_{};
  std::vector<std::uint8_t> polling_;  // copy of the list, fixed after construction

  Receiver rx_;
  Phase phase_ = Phase::Idle;
  Current current_;
  ExchangeOutcome last_outcome_ = ExchangeOutcome::None;
  std::size_t poll_index_ = 0;     // next entry of polling_
  bool startup_ = true;            // mirror_at_start mirrors still go first
  bool extra_allowed_ = false;     // a poll went out since the last extra telegram
  std::size_t mirror_cursor_ = 0;  // round robin over pending mirrors
  MonoTime line_free_{};           // end of the last character on the line
  MonoTime sent_end_{};            // end of our last telegram
  bool reply_started_ = false;     // the receiver accepted an STX in this exchange
  MonoTime stx_at_{};
  bool pass_started_ = false;
  MonoTime pass_start_{};
  std::uint64_t cycles_ = 0;
  std::chrono::nanoseconds last_cycle_{0};

  std::array<std::uint8_t, kMaxTelegramBytes> tx_{};
  std::size_t tx_size_ = 0;
  std::array<std::uint8_t, kMaxPayloadBytes> payload_{};
  Pkw reply_pkw_;  // scratch for decoding
  std::array<std::uint16_t, kMaxPzdWords> pzd_scratch_{};

  FixedQueue<Extra, kExtraSlots> extras_;
  FixedQueue<SpontaneousReport, kReportSlots> reports_;
  FixedQueue<LinkChange, kLinkSlots> link_changes_;
  FixedQueue<MirrorResult, kResultSlots> mirror_results_;
  FixedQueue<SpecialResult, kResultSlots> special_results_;
  std::size_t result_cursor_ = 0;  // round robin over slots with a PKW result
  MasterCounters counters_;
};

}  // namespace liftd::uss
