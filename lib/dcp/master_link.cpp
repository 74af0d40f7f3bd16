#include "dcp/master_link.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace liftd::dcp {
namespace {

// B0..B2: drive enable, travel command, stop switch (DCP 3.1). Never sent while the link is not
// fit for travel (DCP 7.3 note: the master supervises the link and acts like the drive does).
constexpr std::uint8_t kTravelBits =
    command_bit::kDriveEnable | command_bit::kTravel | command_bit::kStopSwitch;

constexpr int kMaxFrameCount = 1000;  // sanity bound for the DCP 7.3 counts in the config

bool same_day(const CivilTime& a, const CivilTime& b) noexcept {
  return a.year == b.year && a.month == b.month && a.day == b.day;
}

bool upper_code(Code2 code) noexcept {
  return code[0] >= 'A' && code[0] <= 'Z' && code[1] >= 'A' && code[1] <= 'Z';
}

// The I-message behind a request, or nullopt for a keypad frame.
std::optional<MasterMessage> as_master(const Request& request) noexcept {
  return std::visit(
      [](const auto& r) -> std::optional<MasterMessage> {
        if constexpr (std::is_same_v<std::decay_t<decltype(r)>, KeypadPress>) {
          return std::nullopt;
        } else {
          return MasterMessage{r};
        }
      },
      request);
}

}  // namespace

std::string_view to_string(LinkState state) noexcept {
  switch (state) {
    case LinkState::Down:
      return "down";
    case LinkState::Init:
      return "init";
    case LinkState::Up:
      return "up";
    case LinkState::Resetting:
      return "resetting";
    case LinkState::Fault:
      return "fault";
  }
  return "unknown";
}

std::string_view to_string(SubmitResult result) noexcept {
  switch (result) {
    case SubmitResult::Accepted:
      return "accepted";
    case SubmitResult::QueueFull:
      return "request queue full";
    case SubmitResult::LinkNotUp:
      return "link not up";
    case SubmitResult::Invalid:
      return "request cannot be encoded";
    case SubmitResult::TooLate:
      return "reset cancel window (200 ms) has passed";
  }
  return "unknown";
}

std::string_view to_string(RequestResult result) noexcept {
  switch (result) {
    case RequestResult::Ok:
      return "ok";
    case RequestResult::Timeout:
      return "no reply from the drive";
    case RequestResult::AssumedMains:
      return "no reply: mains operation without energy saving assumed";
    case RequestResult::LinkLost:
      return "link lost before the reply";
  }
  return "unknown";
}

std::string_view to_string(LinkEventKind kind) noexcept {
  switch (kind) {
    case LinkEventKind::StateChanged:
      return "state changed";
    case LinkEventKind::ChannelReset:
      return "channel reset";
    case LinkEventKind::ChannelError:
      return "channel error";
    case LinkEventKind::DecodeError:
      return "decode error";
    case LinkEventKind::RequestTimeout:
      return "request timeout";
    case LinkEventKind::UnmatchedReply:
      return "unmatched reply";
    case LinkEventKind::TimeSent:
      return "date/time sent";
    case LinkEventKind::HandshakeProblem:
      return "handshake problem";
    case LinkEventKind::Tolerated:
      return "tolerated";
  }
  return "unknown";
}

std::string_view config_error(const MasterLinkConfig& c) noexcept {
  if (c.fault_after_bad_frames < 1 || c.fault_after_bad_frames > kMaxFrameCount) {
    return "fault_after_bad_frames must be 1..1000";
  }
  if (c.recover_after_good_frames < 1 || c.recover_after_good_frames > kMaxFrameCount) {
    return "recover_after_good_frames must be 1..1000";
  }
  if (!data_info_type_from_char(static_cast<char>(c.data_info_type))) {
    return "data_info_type must be '0'..'4'";
  }
  if (!upper_code(c.maker)) return "maker must be two upper-case letters";
  if (!upper_code(c.language)) return "language must be two upper-case letters (ISO 639)";
  if (c.version > 9999) return "version must be 0..9999 (four digits)";
  if (!encode(MasterMessage{InitRequest{c.maker, c.version, c.software_date, c.language}}).ok()) {
    return "software_date is not a valid DDMMYY date";
  }
  if (c.request_timeout <= MonoTime::zero()) return "request_timeout must be positive";
  if (c.reset_cancel_window <= MonoTime::zero()) return "reset_cancel_window must be positive";
  if (c.reinit_after_reset <= c.reset_cancel_window) {
    return "reinit_after_reset must be longer than reset_cancel_window";
  }
  return {};
}

MasterLink::MasterLink(const MasterLinkConfig& config) : config_(config) {
  if (const auto error = config_error(config); !error.empty()) {
    throw std::invalid_argument("dcp master link: " + std::string(error));
  }
}

bool MasterLink::travel_allowed() const noexcept {
  if (!protocol_ || (*protocol_ != Protocol::Dcp3 && *protocol_ != Protocol::Dcp4)) return false;
  if (state_ == LinkState::Up) return true;
  // DCP 5.1: "The communication data channel is subordinate to the real time channel": a
  // travel already running goes on while the channel re-initialises; no new one starts.
  return motion_on_ && (state_ == LinkState::Init || state_ == LinkState::Resetting);
}

bool MasterLink::at_rest() const noexcept {
  const bool travel_active = drive_.status && (*drive_.status & status_bit::kTravelActive) != 0;
  return !motion_on_ && !travel_active;
}

void MasterLink::set_civil_time(const CivilTime& time) noexcept {
  if (valid_civil_time(time)) civil_time_ = time;
}

LinkCounters MasterLink::counters() const noexcept {
  LinkCounters c = counters_;
  c.events_dropped = completions_.dropped() + events_.dropped() + drive_errors_.dropped();
  return c;
}

// ---- the cycle ------------------------------------------------------------------------------

FrameBytes MasterLink::next_frame(MonoTime now) noexcept {
  if (awaiting_reply_) on_no_reply(now);
  last_now_ = now;
  run_timers(now);
  schedule_channel(now);

  ChannelPair pair{};
  if (repeat_next_) {
    pair = transmitter_.repeat_pair();  // DCP 6.1 b: S7 seen, the drive missed these bytes
    repeat_next_ = false;
  } else {
    pair = transmitter_.next_pair();
  }
  if (outstanding_.active && !outstanding_.sent && transmitter_.idle()) {
    outstanding_.sent = true;  // our ETX is on its way: the reply timeout starts now
    outstanding_.sent_at = now;
    if (!outstanding_.expects_reply) {
      const Outstanding done = outstanding_;
      outstanding_ = Outstanding{};
      if (done.internal) {
        if (state_ == LinkState::Init && step_ == Step::ChannelReset) step_ = Step::I0;
      } else {
        complete(done, RequestResult::Ok, std::nullopt, now);
      }
    }
  }

  std::uint8_t command = command_;
  if (!travel_allowed()) command = static_cast<std::uint8_t>(command & ~kTravelBits);
  motion_on_ = (command & kTravelBits) != 0;
  b7_in_last_frame_ = b7_next_;
  if (b7_next_) {
    command |= command_bit::kReplyChecksumError;  // DCP 6.1 a
    ++counters_.b7_sent;
    b7_next_ = false;
  }
  MasterFrame frame{command, 0, 0, pair[0], pair[1]};
  frame.set_data_word(data_word_);
  awaiting_reply_ = true;
  ++counters_.frames_sent;
  return encode(frame);
}

void MasterLink::on_reply(std::span<const std::uint8_t, kFrameSize> bytes, MonoTime now) noexcept {
  if (!awaiting_reply_) return;  // a reply to nothing we sent: not part of the cycle
  awaiting_reply_ = false;
  last_now_ = now;
  const auto frame = decode_slave(bytes);
  last_exchange_good_ = false;
  if (!frame) {
    // DCP 6.1 a: ignore the reply (its S7 too, DCP 6 note), set B7 in the next frame, keep the
    // message type. The drive then repeats this reply, which we have not consumed.
    ++counters_.bad_checksum;
    b7_next_ = true;
    last_reply_consumed_ = false;
    count_error(now);
    return;
  }
  ++counters_.good_replies;
  drive_.status = frame->status;
  drive_.status_at = now;

  bool consumed = false;
  if ((frame->status & status_bit::kMessageChecksumError) != 0) {
    // DCP 6.1 b: the drive ignored our frame; repeat our channel bytes. Its own channel bytes
    // are 00 in such a reply (DCP 6.2 a), so there is nothing to consume.
    ++counters_.s7_seen;
    repeat_next_ = true;
    // The frame that carried B7 did not reach the drive either: say it again.
    if (b7_in_last_frame_) b7_next_ = true;
  } else if (b7_in_last_frame_ && last_reply_consumed_) {
    // DCP 6.2 b: this is a repetition of a reply whose channel bytes we already have.
    ++counters_.repeats_skipped;
  } else {
    consume_channel(frame->comm1, now);
    consume_channel(frame->comm2, now);
    consumed = true;
  }
  last_reply_consumed_ = consumed;
  const bool s7 = (frame->status & status_bit::kMessageChecksumError) != 0;
  // A reply to a B7 frame repeats an older one (DCP 6.2 b; DCP3 repeats its status too).
  last_exchange_good_ = !s7 && !b7_in_last_frame_;
  if (s7) {
    // DCP 7.3: "10 successive messages are received incorrectly or were completely lost": an
    // S7 reply says the drive received ours incorrectly, so it counts like a lost one.
    count_error(now);
  } else {
    count_good(frame->status, now);
  }
  if (state_ == LinkState::Up) handle_drive_data(*frame, now);
}

void MasterLink::on_bad_reply(MonoTime now) noexcept {
  if (!awaiting_reply_) return;
  awaiting_reply_ = false;
  last_now_ = now;
  last_exchange_good_ = false;
  // Our frame was changed on the line, so the drive did not read it intact: it ignored it and
  // answered with S7 and channel bytes 00 (DCP 6.2 a), if at all. As for an S7 reply (DCP
  // 6.1 b): repeat our channel bytes. No B7: that reply carried nothing to consume, and asking
  // for it again would only bring its S7 back.
  ++counters_.bad_exchanges;
  repeat_next_ = true;
  last_reply_consumed_ = false;
  count_error(now);
}

void MasterLink::on_no_reply(MonoTime now) noexcept {
  if (!awaiting_reply_) return;
  awaiting_reply_ = false;
  last_now_ = now;
  last_exchange_good_ = false;
  // No B7 here: the drive may never have seen our frame, and would then repeat a reply whose
  // channel bytes we consumed already.
  ++counters_.missing_replies;
  last_reply_consumed_ = false;
  count_error(now);
}

void MasterLink::on_port_lost(MonoTime now) noexcept {
  awaiting_reply_ = false;
  last_now_ = now;
  good_run_ = 0;
  if (state_ == LinkState::Fault) return;
  ++counters_.link_faults;
  fail_requests(RequestResult::LinkLost, now);
  reset_channel(now);
  enter(LinkState::Fault, "serial port lost", now);
}

// ---- supervision (DCP 7.3) ----------------------------------------------------------------

void MasterLink::count_error(MonoTime now) noexcept {
  ++counters_.error_run;
  counters_.longest_error_run = std::max(counters_.longest_error_run, counters_.error_run);
  good_run_ = 0;
  if ((state_ == LinkState::Init || state_ == LinkState::Up) &&
      counters_.error_run >= static_cast<std::uint32_t>(config_.fault_after_bad_frames)) {
    ++counters_.link_faults;
    fail_requests(RequestResult::LinkLost, now);
    reset_channel(now);
    enter(LinkState::Fault, "too many consecutive bad or missing replies (DCP 7.3)", now);
  }
}

void MasterLink::count_good(std::uint8_t status, MonoTime now) noexcept {
  counters_.error_run = 0;
  switch (state_) {
    case LinkState::Down:
      enter_init("drive answered", now);
      break;
    case LinkState::Fault:
      // DCP 7.3: resume only after consecutive good replies while the drive is stationary.
      if ((status & status_bit::kTravelActive) != 0) {
        good_run_ = 0;
      } else if (++good_run_ >= config_.recover_after_good_frames) {
        good_run_ = 0;
        enter_init("link recovered (DCP 7.3)", now);
      }
      break;
    case LinkState::Init:
    case LinkState::Up:
    case LinkState::Resetting:
      break;
  }
}

// ---- state changes ----------------------------------------------------------------------------

void MasterLink::enter(LinkState next, std::string_view why, MonoTime now) noexcept {
  if (next == state_) return;
  const LinkEvent e{now, LinkEventKind::StateChanged, state_, next, why};
  state_ = next;
  events_.push(e);
}

void MasterLink::enter_init(std::string_view why, MonoTime now) noexcept {
  ++counters_.handshake_attempts;
  reinit_pending_ = {};
  fail_requests(RequestResult::LinkLost, now);
  reset_channel(now);
  step_ = Step::ChannelReset;
  // DCP 5.12.3.1: without a confirmed I1 both sides use data-information-type '0'.
  active_type_ = DataInfoType::Alternating;
  extended_active_ = false;
  const LinkEvent e{now, LinkEventKind::StateChanged, state_, LinkState::Init, why};
  state_ = LinkState::Init;
  events_.push(e);  // also Init -> Init: a restarted handshake is worth a line in the journal
}

void MasterLink::channel_fault(std::string_view why, MonoTime now) noexcept {
  if (state_ != LinkState::Init && state_ != LinkState::Up) return;
  if (at_rest()) {
    enter_init(why, now);
    return;
  }
  // DCP 5.1: the channel is subordinate to the real-time channel, and DCP 5.4 resets "the
  // communication devices": reset the channel now, never the travel; the handshake (I0, I1,
  // I3) runs again once the car is at rest.
  fail_requests(RequestResult::LinkLost, now);
  reset_channel(now);
  ++counters_.deferred_resets;
  reinit_pending_ = why;
}

void MasterLink::handshake_done(MonoTime /*now*/) noexcept {
  handshake_problem_ = {};
  counters_.handshake_attempts = 0;
}

void MasterLink::handshake_failed(std::string_view problem, MonoTime now) noexcept {
  const bool news = problem != handshake_problem_;
  handshake_problem_ = problem;
  // Said in the journal the first time, whenever the cause changes, and then every 60th try
  // (about once a minute with the 1 s reply timeout), never silently and never every second.
  if (news || counters_.handshake_attempts % 60 == 1) {
    event(LinkEventKind::HandshakeProblem, problem, now);
  }
}

void MasterLink::reset_channel(MonoTime now) noexcept {
  parser_.reset(now);
  transmitter_.clear();
  outstanding_ = Outstanding{};
  repeat_next_ = false;
  display_.clear();  // DCP 5.10: the initial state has a cleared display
  ++counters_.channel_resets;
}

void MasterLink::fail_requests(RequestResult result, MonoTime now) noexcept {
  if (outstanding_.active && !outstanding_.internal)
    complete(outstanding_, result, std::nullopt, now);
  outstanding_ = Outstanding{};
  while (auto pending = requests_.pop()) {
    Outstanding o;
    o.tag = pending->tag;
    if (const auto message = as_master(pending->request)) {
      o.id = message_id(*message);
    } else {
      o.keypad = true;
    }
    complete(o, result, std::nullopt, now);
  }
}

void MasterLink::complete(const Outstanding& o, RequestResult result,
                          std::optional<DriveMessage> reply, MonoTime now) noexcept {
  Completion c;
  c.tag = o.tag;
  c.id = o.id;
  c.keypad = o.keypad;
  c.result = result;
  c.reply = std::move(reply);
  c.at = now;
  completions_.push(c);
}

void MasterLink::event(LinkEventKind kind, std::string_view detail, MonoTime now) noexcept {
  events_.push(LinkEvent{now, kind, state_, state_, detail});
}

// ---- timers and the outgoing channel -------------------------------------------------------

void MasterLink::run_timers(MonoTime now) noexcept {
  handle_parse(parser_.poll(now), now);
  if (outstanding_.active && outstanding_.sent && outstanding_.expects_reply &&
      now - outstanding_.sent_at >= config_.request_timeout) {
    handle_timeout(now);
  }
  if (!reinit_pending_.empty() && at_rest()) enter_init(reinit_pending_, now);
  if (state_ == LinkState::Resetting && now - reset_reply_at_ >= config_.reinit_after_reset) {
    enter_init("re-initialising after the drive's trip/fault reset (DCP 5.12.4.2)", now);
  }
}

void MasterLink::handle_timeout(MonoTime now) noexcept {
  const Outstanding o = outstanding_;
  outstanding_ = Outstanding{};
  ++counters_.request_timeouts;
  event(LinkEventKind::RequestTimeout, to_string(o.id), now);
  if (o.internal) {
    if (o.id == MessageId::Init) {
      // DCP 5.12.2: without a valid I0 exchange no travel; start the handshake again.
      if (state_ == LinkState::Init) {
        if (handshake_problem_.empty() || handshake_problem_ == "no reply to I0") {
          handshake_failed("no reply to I0", now);
        }
        enter_init("no valid reply to I0: restarting the handshake", now);
      }
    } else if (o.id == MessageId::DataInfo && state_ == LinkState::Init && step_ == Step::I1) {
      // DCP 5.12.3.1: "If no message ('I' '1') is transmitted ..., the data-information-type will
      // be set to '0' on both controllers": an older drive that ignores I1 runs with type '0'.
      step_ = Step::I3;
      event(LinkEventKind::Tolerated,
            "no reply to I1: data-information-type '0' on both sides (DCP 5.12.3.1)", now);
    } else if (o.id == MessageId::DateTime && state_ == LinkState::Init && step_ == Step::I3) {
      step_ = Step::Done;  // I3 is not needed for travel (DCP 5.12.5.1)
      handshake_done(now);
      enter(LinkState::Up, "handshake complete (I3 unanswered)", now);
    }
    return;
  }
  if (o.id == MessageId::Power) {
    power_mode_ = PowerReply{};  // DCP 5.12.6.2: no reply means mains, no saving
    complete(o, RequestResult::AssumedMains, DriveMessage{PowerReply{}}, now);
    return;
  }
  complete(o, RequestResult::Timeout, std::nullopt, now);
}

bool MasterLink::send_message(const MasterMessage& message, bool internal,
                              RequestTag tag) noexcept {
  const auto payload = encode(message);
  if (!payload.ok() || !transmitter_.start(ChannelMode::Expanded, payload.value.bytes())) {
    return false;
  }
  Outstanding o;
  o.active = true;
  o.internal = internal;
  o.expects_reply = true;
  o.id = message_id(message);
  o.tag = tag;
  if (const auto* s = std::get_if<SwitchRequest>(&message)) o.switch_function = s->function;
  outstanding_ = o;
  return true;
}

void MasterLink::schedule_channel(MonoTime now) noexcept {
  if (outstanding_.active || transmitter_.busy()) return;
  switch (state_) {
    case LinkState::Down:
    case LinkState::Fault:
      return;  // channel idle
    case LinkState::Init:
      if (!at_rest()) return;  // the handshake waits until the travel has ended
      switch (step_) {
        case Step::ChannelReset:
          // DCP 5.10: STX ETX puts the drive's channel into its initial state first.
          if (transmitter_.start_reset()) {
            outstanding_ = Outstanding{};
            outstanding_.active = true;
            outstanding_.internal = true;
            outstanding_.expects_reply = false;
          }
          return;
        case Step::I0:
          send_message(
              InitRequest{config_.maker, config_.version, config_.software_date, config_.language},
              true, 0);
          return;
        case Step::I1:
          send_message(DataInfoRequest{config_.extended_position, config_.data_info_type}, true, 0);
          return;
        case Step::I3:
          if (civil_time_) {
            last_time_sent_ = civil_time_;
            send_message(DateTimeRequest{*civil_time_}, true, 0);
          } else {
            step_ = Step::Done;  // no wall clock given yet: I3 follows once it is
            handshake_done(now);
            enter(LinkState::Up, "handshake complete (no date/time to send yet)", now);
          }
          return;
        case Step::Done:
          return;
      }
      return;
    case LinkState::Up:
      // DCP 5.12.5.1: I3 once a day, preferably at the day change.
      if (civil_time_ && (!last_time_sent_ || !same_day(*last_time_sent_, *civil_time_))) {
        last_time_sent_ = civil_time_;
        send_message(DateTimeRequest{*civil_time_}, true, 0);
        return;
      }
      [[fallthrough]];
    case LinkState::Resetting: {
      const Pending* pending = requests_.front();
      if (pending == nullptr) return;
      if (const auto* keypad = std::get_if<KeypadPress>(&pending->request)) {
        const auto payload = encode_keypad(keypad->buttons);
        if (payload.ok() && transmitter_.start(ChannelMode::Remote, payload.value.bytes())) {
          outstanding_ = Outstanding{};
          outstanding_.active = true;
          outstanding_.expects_reply = false;
          outstanding_.keypad = true;
          outstanding_.tag = pending->tag;
        }
      } else if (const auto message = as_master(pending->request)) {
        send_message(*message, false, pending->tag);
      }
      requests_.drop_front();
      return;
    }
  }
}

SubmitResult MasterLink::submit(const Request& request, RequestTag tag) noexcept {
  const auto* sw = std::get_if<SwitchRequest>(&request);
  const bool cancel = sw != nullptr && sw->function == SwitchFunction::None;
  if (state_ != LinkState::Up) {
    if (state_ != LinkState::Resetting || !cancel) return SubmitResult::LinkNotUp;
    // DCP 5.12.4.2: a cancel must reach the drive within 200 ms of its 'R' reply.
    if (last_now_ - reset_reply_at_ > config_.reset_cancel_window) return SubmitResult::TooLate;
  }
  if (const auto* keypad = std::get_if<KeypadPress>(&request)) {
    if (!valid_keypad_buttons(keypad->buttons)) return SubmitResult::Invalid;
  } else if (const auto message = as_master(request); !message || !encode(*message).ok()) {
    return SubmitResult::Invalid;
  }
  if (requests_.full()) return SubmitResult::QueueFull;
  requests_.push(Pending{request, tag});
  return SubmitResult::Accepted;
}

// ---- the incoming channel -----------------------------------------------------------------

void MasterLink::consume_channel(std::uint8_t byte, MonoTime now) noexcept {
  handle_parse(parser_.feed(byte, now), now);
}

void MasterLink::handle_parse(ParseStatus status, MonoTime now) noexcept {
  switch (status) {
    case ParseStatus::NeedMore:
      return;
    case ParseStatus::Complete:
      handle_frame(parser_.frame(), now);
      return;
    case ParseStatus::Bad:
      ++counters_.channel_errors;
      // DCP 5.7: a new STX inside a display stream clears the display.
      if (parser_.error() == ChannelError::StxInFrame &&
          parser_.dropped_mode() == ChannelMode::Remote) {
        display_.clear();
      }
      event(LinkEventKind::ChannelError, to_string(parser_.error()), now);
      return;
    case ParseStatus::Reset: {
      const ChannelReset reason = parser_.reset_reason();
      ++counters_.channel_resets;
      display_.clear();
      event(LinkEventKind::ChannelReset, to_string(reason), now);
      if (reason == ChannelReset::IdleTimeout || reason == ChannelReset::FrameTimeout) {
        channel_fault("channel timeout (DCP 5.4): re-initialising", now);
      }
      return;
    }
  }
}

void MasterLink::handle_frame(const ChannelFrame& frame, MonoTime now) noexcept {
  switch (frame.mode) {
    case ChannelMode::Expanded: {
      const auto decoded = decode_drive_message(frame.payload());
      if (!decoded.ok()) {
        ++counters_.decode_errors;
        event(LinkEventKind::DecodeError, to_string(decoded.error), now);
        if (state_ == LinkState::Init && outstanding_.active && outstanding_.internal &&
            outstanding_.id == MessageId::Init && frame.payload().size() >= 2 &&
            frame.payload()[1] == static_cast<std::uint8_t>(MessageId::Init)) {
          handshake_failed(decoded.error == MessageError::BadDcpType
                               ? "the drive's I0 reply names no known DCP type (DCP 5.12.2.2)"
                               : "the drive's I0 reply is unreadable (see the decode error)",
                           now);
        }
        return;
      }
      handle_reply(decoded.value, now);
      return;
    }
    case ChannelMode::DriveError: {
      const auto decoded = decode_drive_error(frame.payload());
      if (!decoded.ok()) {
        ++counters_.decode_errors;
        event(LinkEventKind::DecodeError, to_string(decoded.error), now);
        return;
      }
      drive_errors_.push(DriveErrorEvent{now, decoded.value});
      return;
    }
    case ChannelMode::Remote: {
      const DisplayError error = display_.apply(frame.payload());
      if (error != DisplayError::None) {
        ++counters_.decode_errors;
        event(LinkEventKind::DecodeError, to_string(error), now);
      }
      return;
    }
  }
}

void MasterLink::handle_reply(const DriveMessage& reply, MonoTime now) noexcept {
  const MessageId id = message_id(reply);
  if (!outstanding_.active || !outstanding_.expects_reply || outstanding_.id != id) {
    ++counters_.unmatched_replies;
    event(LinkEventKind::UnmatchedReply, to_string(id), now);
    return;
  }
  const Outstanding o = outstanding_;
  outstanding_ = Outstanding{};
  if (o.internal) {
    switch (id) {
      case MessageId::Init: {
        const auto* r = std::get_if<InitReply>(&reply);  // the id matched: never null
        if (r == nullptr) return;
        drive_info_ = *r;
        protocol_ = r->dcp_type;  // DCP 5.12.2.2: the drive's DCP type decides the dialect
        if (r->anomalies != 0) {
          // Only the DCP type decides whether we can travel; odd fields are said, not refused.
          event(LinkEventKind::Tolerated,
                "I0 reply with fields not as DCP 5.12.2.2 defines them (maker, version, date, "
                "language or length): accepted for its DCP type",
                now);
        }
        if (state_ == LinkState::Init && step_ == Step::I0) step_ = Step::I1;
        return;
      }
      case MessageId::DataInfo: {
        const auto* r = std::get_if<DataInfoReply>(&reply);
        active_type_ = config_.data_info_type;
        extended_active_ = config_.extended_position && r != nullptr && r->extended_protocol;
        if (state_ == LinkState::Init && step_ == Step::I1) step_ = Step::I3;
        return;
      }
      case MessageId::DateTime:
        event(LinkEventKind::TimeSent, "drive confirmed date/time", now);
        if (state_ == LinkState::Init && step_ == Step::I3) {
          step_ = Step::Done;
          handshake_done(now);
          enter(LinkState::Up, "handshake complete", now);
        }
        return;
      default:
        return;
    }
  }
  if (const auto* power = std::get_if<PowerReply>(&reply)) power_mode_ = *power;
  if (const auto* sw = std::get_if<SwitchReply>(&reply)) {
    if (o.switch_function == SwitchFunction::Reset && sw->function == SwitchFunction::Reset &&
        state_ == LinkState::Up) {
      reset_reply_at_ = now;
      enter(LinkState::Resetting, "drive accepted trip/fault reset (I2 'R')", now);
    } else if (o.switch_function == SwitchFunction::None && sw->function == SwitchFunction::None &&
               state_ == LinkState::Resetting) {
      enter(LinkState::Up, "trip/fault reset cancelled (I2 '0')", now);
    }
  }
  complete(o, RequestResult::Ok, reply, now);
}

void MasterLink::handle_drive_data(const SlaveFrame& frame, MonoTime now) noexcept {
  if (protocol_ != Protocol::Dcp3 && protocol_ != Protocol::Dcp4) return;
  const auto data = decode_drive_data(frame.data_word(), active_type_);
  if (!data) {
    ++counters_.data_word_errors;
    return;
  }
  if (data->kind == DriveData::Kind::ExtendedStatus) {
    drive_.extended = data->extended;
    drive_.extended_at = now;
  } else {
    drive_.deceleration = *data;
    drive_.deceleration_at = now;
  }
}

}  // namespace liftd::dcp
