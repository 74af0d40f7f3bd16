// The DCP master link engine (DCP chapters 5 to 7): one instance per drive link, driven once per
// 15 ms cycle by whoever owns the serial port. Sans-I/O: frames and time in, frames, state and
// events out. After construction no method allocates, locks, logs or throws.
//
// Per cycle the owner calls, in this order:
//   1. next_frame(now)  -> the 6 bytes to send (process data from set_process, two channel
//                          bytes, B7; B0..B2 forced off unless travel_allowed())
//   2. on_reply(bytes, now) when 6 reply bytes arrived in time, else on_no_reply(now)
//   3. drains pop_completion(), pop_event(), pop_drive_error() and reads the snapshots.
#pragma once

#include <array>
#include <chrono>
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>
#include <variant>

#include "common/defaults.hpp"
#include "common/fixed_queue.hpp"
#include "common/mono_time.hpp"
#include "dcp/channel.hpp"
#include "dcp/defaults.hpp"
#include "dcp/display.hpp"
#include "dcp/frame.hpp"
#include "dcp/messages.hpp"

namespace liftd::dcp {

/// Where the link stands.
enum class LinkState : std::uint8_t {
  Down,       ///< no good reply since start: channel idle, no travel
  Init,       ///< handshake STX ETX, I0, I1, I3 running: no travel
  Up,         ///< handshake done: travel allowed if the drive speaks DCP3 or DCP4
  Resetting,  ///< the drive accepted I2 'R': no travel, re-initialisation about 5 s later
  Fault,      ///< link fault (bad/missing replies or port lost): B0 off, waiting to recover
};

std::string_view to_string(LinkState state) noexcept;

/// Settings of one link. Checked once by config_error(); the constructor throws on a bad one.
struct MasterLinkConfig {
  /// I1 data-information-type (DCP 5.12.3); decides the width of our remaining distance.
  DataInfoType data_info_type = DataInfoType::Alternating;
  /// I1 protocol type '1': ask for the extended I9 reply with the measured travel distance.
  bool extended_position = defaults::kExtendedPosition;
  /// DCP 7.3: consecutive bad or missing replies that make a link fault.
  int fault_after_bad_frames = defaults::kLinkFaultFrames;
  /// DCP 7.3: consecutive good replies, drive stationary (S1 = 0), that end a link fault.
  int recover_after_good_frames = defaults::kLinkRecoverFrames;
  /// I0: our maker code (DCP 5.12.2.3). liftd has no registered code: set the installer's own.
  Code2 maker{'L', 'D'};
  /// I0: our software version, four digits (12.34 = 1234).
  VersionCenti version = 10;
  /// I0: our software date DDMMYY.
  SoftwareDate software_date{1, 1, 26};
  /// I0: display language, ISO 639 upper case.
  Code2 language{'E', 'N'};
  /// How long we wait for the drive's reply to an I-message, counted from our ETX.
  MonoTime request_timeout = std::chrono::milliseconds(defaults::kRequestTimeoutMs);
  /// DCP 5.12.4.2: after its 'R' reply the drive waits 200 ms, in which we may cancel.
  MonoTime reset_cancel_window = std::chrono::milliseconds(200);
  /// DCP 5.12.4.2: re-run I0/I1 about 5 s after a trip/fault reset.
  MonoTime reinit_after_reset = std::chrono::seconds(5);
};

/// Empty if the config is usable, else which setting is wrong and why.
std::string_view config_error(const MasterLinkConfig& config) noexcept;

/// I-message requests the caller may submit (the engine itself sends I0, I1 and I3).
struct KeypadPress {
  std::uint8_t buttons = keypad_button::kNone;  ///< DCP 5.6.3 bits; kNone = all released
  bool operator==(const KeypadPress&) const = default;
};
/// One request: I2, I6, I7, I8, I9 or a keypad frame.
using Request = std::variant<SwitchRequest, PowerRequest, StartParamsRequest, LoadRequest,
                             PositionRequest, KeypadPress>;
/// The caller's handle for a request, echoed in its completion.
using RequestTag = std::uint32_t;

/// Why submit() refused a request.
enum class SubmitResult : std::uint8_t {
  Accepted,
  QueueFull,  ///< the request queue is full; try again later
  LinkNotUp,  ///< requests are taken only while the link is Up (I2 '0' also while Resetting)
  Invalid,    ///< the request cannot be encoded (a field out of range)
  TooLate,    ///< I2 '0' cancel after the 200 ms window of DCP 5.12.4.2
};

std::string_view to_string(SubmitResult result) noexcept;

/// How a request ended.
enum class RequestResult : std::uint8_t {
  Ok,            ///< reply received (keypad: frame sent)
  Timeout,       ///< no matching reply within request_timeout
  AssumedMains,  ///< I6 without reply: DCP 5.12.6.2 says assume mains, no saving
  LinkLost,      ///< the link left Up (fault, channel timeout, re-init) before the reply
};

std::string_view to_string(RequestResult result) noexcept;

/// A finished request.
struct Completion {
  RequestTag tag = 0;
  MessageId id = MessageId::Init;  ///< which I-message; meaningless when `keypad` is true
  bool keypad = false;             ///< true for a keypad frame
  RequestResult result = RequestResult::Ok;
  /// The drive's reply for Ok, and the assumed PowerReply for AssumedMains.
  std::optional<DriveMessage> reply;
  MonoTime at{};
};

/// What happened on the link, for the journal and the API watch stream.
enum class LinkEventKind : std::uint8_t {
  StateChanged,      ///< `from` -> `state`; detail says why
  ChannelReset,      ///< the receive channel went back to its initial state; detail says why
  ChannelError,      ///< a malformed channel frame from the drive was dropped
  DecodeError,       ///< a drive payload (I-message, display, error text) did not decode
  RequestTimeout,    ///< an I-message got no reply; detail names it
  UnmatchedReply,    ///< a reply that answers nothing outstanding
  TimeSent,          ///< I3 date/time confirmed by the drive
  HandshakeProblem,  ///< the handshake did not complete; detail says what was wrong
  Tolerated,         ///< the drive's answer was odd but usable; detail says what was odd
};

std::string_view to_string(LinkEventKind kind) noexcept;

/// One link event. `detail` always points to a static string.
struct LinkEvent {
  MonoTime at{};
  LinkEventKind kind = LinkEventKind::StateChanged;
  LinkState from = LinkState::Down;
  LinkState state = LinkState::Down;
  std::string_view detail;
};

/// A drive error message (DCP 5.11) with the time its ETX arrived.
struct DriveErrorEvent {
  MonoTime at{};
  DriveErrorText text;
};

/// Link statistics since construction.
struct LinkCounters {
  std::uint64_t frames_sent = 0;
  std::uint64_t good_replies = 0;
  std::uint64_t bad_checksum = 0;      ///< replies ignored for a bad checksum (DCP 6.1 a)
  std::uint64_t bad_exchanges = 0;     ///< exchanges the line spoilt (an echo collision)
  std::uint64_t missing_replies = 0;   ///< replies missing, late or incomplete
  std::uint64_t s7_seen = 0;           ///< good replies with S7 (DCP 6.1 b)
  std::uint64_t b7_sent = 0;           ///< frames we sent with B7
  std::uint64_t repeats_skipped = 0;   ///< repeated replies whose channel bytes we had already
  std::uint64_t channel_resets = 0;    ///< STX ETX, 1 s timeouts and our own resets
  std::uint64_t channel_errors = 0;    ///< malformed channel frames dropped
  std::uint64_t decode_errors = 0;     ///< payloads that did not decode
  std::uint64_t data_word_errors = 0;  ///< drive data words not fitting the data-information-type
  std::uint64_t request_timeouts = 0;
  std::uint64_t unmatched_replies = 0;
  std::uint64_t link_faults = 0;
  std::uint64_t events_dropped = 0;      ///< events, completions, error texts lost to full queues
  std::uint64_t handshake_attempts = 0;  ///< handshakes started since the last success
  std::uint64_t deferred_resets = 0;     ///< channel faults during a travel: re-init at rest
  std::uint32_t error_run = 0;           ///< current run of consecutive bad/missing replies
  std::uint32_t longest_error_run = 0;
};

/// The latest drive process data.
struct DriveSnapshot {
  std::optional<std::uint8_t> status;  ///< last good status byte (S0..S7)
  MonoTime status_at{};
  /// Last deceleration distance (DCP 4.2.1.2/3); only while Up.
  std::optional<DriveData> deceleration;
  MonoTime deceleration_at{};
  /// Last extended status (DCP 4.2.1.1); only while Up.
  std::optional<ExtendedStatus> extended;
  MonoTime extended_at{};
};

/// Capacities of the fixed queues.
inline constexpr std::size_t kRequestQueueSize = 8;
inline constexpr std::size_t kCompletionQueueSize = 16;
inline constexpr std::size_t kEventQueueSize = 32;
inline constexpr std::size_t kDriveErrorQueueSize = 8;

/// The master side of one DCP link.
class MasterLink {
 public:
  /// Throws std::invalid_argument if config_error(config) is not empty.
  explicit MasterLink(const MasterLinkConfig& config);

  // ---- the cycle ----
  /// The frame to send now. Runs timers first (request timeouts, channel timeouts, reset
  /// window, day change). If the previous frame got neither on_reply nor on_no_reply, it counts
  /// as missing.
  FrameBytes next_frame(MonoTime now) noexcept;
  /// The drive's 6 reply bytes to the last frame.
  void on_reply(std::span<const std::uint8_t, kFrameSize> bytes, MonoTime now) noexcept;
  /// No complete reply to the last frame by the deadline (DCP 7.2: 13.625 ms).
  void on_no_reply(MonoTime now) noexcept;
  /// The exchange is unusable though bytes came: our frame came back changed on an echoing
  /// line (a collision), so the drive did not read it intact. Handled as an S7 reply (DCP
  /// 6.1 b: our channel bytes are repeated; DCP 7.3 counts it as a message received
  /// incorrectly), nothing of the reply is consumed.
  void on_bad_reply(MonoTime now) noexcept;
  /// The serial device is gone: link fault at once.
  void on_port_lost(MonoTime now) noexcept;

  // ---- inputs ----
  /// Process data for the next frames: command byte B0..B6 (B7 is ours and ignored) and the
  /// data word (speed bits or remaining distance).
  void set_process(std::uint8_t command, std::uint16_t data_word) noexcept {
    command_ = static_cast<std::uint8_t>(command & ~command_bit::kReplyChecksumError);
    data_word_ = data_word;
  }
  /// Wall-clock date and time for I3 (after the handshake and at each day change). Call it
  /// regularly (e.g. every second); an invalid time is ignored.
  void set_civil_time(const CivilTime& time) noexcept;
  /// Queues a request. I2 '0' is also taken while Resetting, inside the cancel window.
  SubmitResult submit(const Request& request, RequestTag tag) noexcept;

  // ---- outputs ----
  LinkState state() const noexcept { return state_; }
  /// The drive's DCP type from its last I0 reply.
  std::optional<Protocol> protocol() const noexcept { return protocol_; }
  /// True while Up with a DCP3 or DCP4 drive, and while a travel that was running goes on through
  /// a channel re-initialisation (DCP 5.1: the channel is subordinate to the real-time
  /// channel). B0..B2 are cleared in every other case.
  bool travel_allowed() const noexcept;
  /// The real-time channel is healthy (replies arrive: not Down, not Fault, DCP 7.3).
  bool realtime_up() const noexcept {
    return state_ != LinkState::Down && state_ != LinkState::Fault;
  }
  /// The last frame got a good reply without S7: its status reflects our last frame.
  bool last_exchange_good() const noexcept { return last_exchange_good_; }
  /// What kept the last handshake from completing (empty when it completed).
  std::string_view handshake_problem() const noexcept { return handshake_problem_; }
  /// The drive's last I0 reply (maker, version, date, DCP type, language).
  const std::optional<InitReply>& drive_info() const noexcept { return drive_info_; }
  /// The data-information-type both sides use now ('0' until the drive confirmed I1).
  DataInfoType active_data_info_type() const noexcept { return active_type_; }
  /// True if the drive confirmed the extended I9 reply.
  bool extended_position_active() const noexcept { return extended_active_; }
  /// The power mode the drive reported with I6 (mains, no saving until told otherwise).
  PowerReply power_mode() const noexcept { return power_mode_; }
  /// The latest process data from the drive.
  const DriveSnapshot& drive() const noexcept { return drive_; }
  /// The drive's remote display; display().version() changes with every content change.
  const DisplayModel& display() const noexcept { return display_; }
  LinkCounters counters() const noexcept;

  /// Next finished request, oldest first.
  std::optional<Completion> pop_completion() noexcept { return completions_.pop(); }
  /// Next link event, oldest first.
  std::optional<LinkEvent> pop_event() noexcept { return events_.pop(); }
  /// Next drive error message, oldest first.
  std::optional<DriveErrorEvent> pop_drive_error() noexcept { return drive_errors_.pop(); }

 private:
  enum class Step : std::uint8_t { ChannelReset, I0, I1, I3, Done };
  struct Pending {
    Request request;
    RequestTag tag = 0;
  };
  struct Outstanding {
    bool active = false;
    bool internal = false;      ///< I0/I1/I3 of the engine itself
    bool expects_reply = true;  ///< false for keypad frames and STX ETX
    bool sent = false;          ///< our ETX has left
    MonoTime sent_at{};
    MessageId id = MessageId::Init;
    bool keypad = false;
    SwitchFunction switch_function = SwitchFunction::None;
    RequestTag tag = 0;
  };

  void run_timers(MonoTime now) noexcept;
  void schedule_channel(MonoTime now) noexcept;
  bool send_message(const MasterMessage& message, bool internal, RequestTag tag) noexcept;
  void consume_channel(std::uint8_t byte, MonoTime now) noexcept;
  void handle_parse(ParseStatus status, MonoTime now) noexcept;
  void handle_frame(const ChannelFrame& frame, MonoTime now) noexcept;
  void handle_reply(const DriveMessage& reply, MonoTime now) noexcept;
  void handle_timeout(MonoTime now) noexcept;
  void handle_drive_data(const SlaveFrame& frame, MonoTime now) noexcept;
  void count_error(MonoTime now) noexcept;
  void count_good(std::uint8_t status, MonoTime now) noexcept;
  void enter(LinkState next, std::string_view why, MonoTime now) noexcept;
  void enter_init(std::string_view why, MonoTime now) noexcept;
  void channel_fault(std::string_view why, MonoTime now) noexcept;
  void handshake_failed(std::string_view problem, MonoTime now) noexcept;
  void handshake_done(MonoTime now) noexcept;
  bool at_rest() const noexcept;
  void reset_channel(MonoTime now) noexcept;
  void fail_requests(RequestResult result, MonoTime now) noexcept;
  void complete(const Outstanding& o, RequestResult result, std::optional<DriveMessage> reply,
                MonoTime now) noexcept;
  void event(LinkEventKind kind, std::string_view detail, MonoTime now) noexcept;

  MasterLinkConfig config_;
  LinkState state_ = LinkState::Down;
  Step step_ = Step::ChannelReset;

  // process data
  std::uint8_t command_ = 0;
  std::uint16_t data_word_ = 0;

  // link-layer error handling (DCP 6)
  bool awaiting_reply_ = false;
  bool b7_next_ = false;  ///< set B7 in the next frame
  bool b7_in_last_frame_ = false;
  bool repeat_next_ = false;  ///< S7 seen: repeat our last channel pair
  bool last_reply_consumed_ = false;
  bool last_exchange_good_ = false;
  bool motion_on_ = false;           ///< the last frame sent carried B0, B1 or B2
  std::string_view reinit_pending_;  ///< channel fault during a travel: re-init at rest
  std::string_view handshake_problem_;
  int good_run_ = 0;  ///< good stationary replies while in Fault

  // channel
  ChannelParser parser_;
  ChannelTransmitter transmitter_;
  Outstanding outstanding_;
  liftd::FixedQueue<Pending, kRequestQueueSize> requests_;
  DisplayModel display_;

  // handshake results
  std::optional<Protocol> protocol_;
  std::optional<InitReply> drive_info_;
  DataInfoType active_type_ = DataInfoType::Alternating;
  bool extended_active_ = false;
  PowerReply power_mode_{};

  // I3 and I2 reset timing
  std::optional<CivilTime> civil_time_;
  std::optional<CivilTime> last_time_sent_;  ///< date of the last confirmed/attempted I3
  MonoTime reset_reply_at_{};
  MonoTime last_now_{};  ///< time of the latest cycle call, for submit()

  DriveSnapshot drive_;
  LinkCounters counters_;
  liftd::FixedQueue<Completion, kCompletionQueueSize> completions_;
  liftd::FixedQueue<LinkEvent, kEventQueueSize> events_;
  liftd::FixedQueue<DriveErrorEvent, kDriveErrorQueueSize> drive_errors_;
};

}  // namespace liftd::dcp
