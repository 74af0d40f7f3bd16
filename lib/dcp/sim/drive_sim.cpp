#include "dcp/sim/drive_sim.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <type_traits>
#include <variant>

namespace liftd::dcp::sim {

namespace {

using namespace std::chrono_literals;
namespace cb = dcp::command_bit;
namespace sb = dcp::status_bit;

constexpr MonoTime kCycle = 15ms;           // DCP 7.2: one transfer cycle
constexpr double kLevellingSpeedMps = 0.3;  // DCP 4.1 S4: v < 0.3 m/s
constexpr double kUnlockingSpeedMps = 0.8;  // DCP 4.2.1.1 bit 0: v < 0.8 m/s
constexpr double kCrawlMarginM = 0.05;      // derived DCP3 distances: 50 mm of crawl
constexpr std::uint16_t kMax15 = 0x7FFF;    // DCP 3.5.3.4: 15-bit remaining distance
constexpr std::uint16_t kMax16 = 0xFFFF;    // DCP 3.5.3.4: 16-bit remaining distance
constexpr double kStillMps = 1e-6;          // below this the car counts as stationary
// DCP 7.2: two 15 ms cycles of lag between the master's position and the drive's.
constexpr std::chrono::duration<double> kPositionLag = 30ms;

std::size_t fault_index(ReplyFault f) {
  return static_cast<std::size_t>(f);
}
std::size_t cause_index(FaultCause c) {
  return static_cast<std::size_t>(c);
}

}  // namespace

double SpeedTable::of(dcp::Speed speed) const noexcept {
  switch (speed) {
    case dcp::Speed::V0:
      return v0_mps;
    case dcp::Speed::VN:
      return vn_mps;
    case dcp::Speed::VF:
      return 0.0;
    case dcp::Speed::V1:
      return v1_mps;
    case dcp::Speed::VI:
      return vi_mps;
    case dcp::Speed::V2:
      return v2_mps;
    case dcp::Speed::V3:
      return v3_mps;
    case dcp::Speed::V4:
      return v4_mps;
    case dcp::Speed::V5:
      return v5_mps;
    case dcp::Speed::V6:
      return v6_mps;
    case dcp::Speed::V7:
      return v7_mps;
  }
  return 0.0;
}

std::string_view to_string(Phase phase) noexcept {
  switch (phase) {
    case Phase::Idle:
      return "idle";
    case Phase::Magnetising:
      return "magnetising";
    case Phase::Moving:
      return "moving";
    case Phase::FastStartHold:
      return "fast-start-hold";
    case Phase::Holding:
      return "holding";
    case Phase::Finished:
      return "finished";
  }
  return "?";
}

std::string_view to_string(TravelKind kind) noexcept {
  switch (kind) {
    case TravelKind::None:
      return "none";
    case TravelKind::Distance:
      return "distance";
    case TravelKind::Speed:
      return "speed";
    case TravelKind::Inspection:
      return "inspection";
    case TravelKind::Crawl:
      return "crawl";
    case TravelKind::Relevel:
      return "relevel";
    case TravelKind::FastStart:
      return "fast-start";
  }
  return "?";
}

std::string_view to_string(SimEvent::Kind kind) noexcept {
  switch (kind) {
    case SimEvent::Kind::PhaseChanged:
      return "phase";
    case SimEvent::Kind::TravelStarted:
      return "travel-started";
    case SimEvent::Kind::TravelEnded:
      return "travel-ended";
    case SimEvent::Kind::TargetExtended:
      return "target-extended";
    case SimEvent::Kind::ExtensionRefused:
      return "extension-refused";
    case SimEvent::Kind::FastStop:
      return "fast-stop";
    case SimEvent::Kind::Fault:
      return "fault";
    case SimEvent::Kind::FaultCleared:
      return "fault-cleared";
    case SimEvent::Kind::ChannelMessage:
      return "channel-message";
    case SimEvent::Kind::ChannelReset:
      return "channel-reset";
    case SimEvent::Kind::DriveReset:
      return "drive-reset";
    case SimEvent::Kind::Violation:
      return "violation";
  }
  return "?";
}

std::string_view to_string(Violation violation) noexcept {
  switch (violation) {
    case Violation::StopAtSpeed:
      return "stop-at-speed";
    case Violation::NoPositionAfterStop:
      return "no-position-after-stop";
  }
  return "?";
}

std::string_view to_string(FaultCause cause) noexcept {
  switch (cause) {
    case FaultCause::Injected:
      return "injected";
    case FaultCause::LinkTimeout:
      return "link-timeout";
    case FaultCause::Implausible:
      return "distance-implausible";
    case FaultCause::FastStartTimeout:
      return "fast-start-timeout";
  }
  return "?";
}

DriveSim::DriveSim(const DriveConfig& config, MonoTime now) noexcept
    : config_(config), epoch_(now), now_(now), last_good_(now), phase_since_(now) {
  origin_mm_ = static_cast<double>(config_.start_position_mm);
  plan_.reset(0.0, MotionState{});
  display_refresh_ = now;
  for (auto& line : shown_) line.fill(' ');
  for (auto& line : display_) line.fill(' ');
}

// ---------------------------------------------------------------- time and car

double DriveSim::seconds(MonoTime t) const noexcept {
  return std::chrono::duration<double>(t - epoch_).count();
}

MotionState DriveSim::state_at(MonoTime now) const noexcept {
  return plan_.at(seconds(now));
}

double Trajectory::position_mm(MonoTime t) const noexcept {
  const double s_mm = plan.at(std::chrono::duration<double>(t - epoch).count()).s_m * 1000.0;
  return origin_mm + (down ? -s_mm : s_mm);
}

double Trajectory::velocity_mps(MonoTime t) const noexcept {
  const double v = plan.at(std::chrono::duration<double>(t - epoch).count()).v_mps;
  return down ? -v : v;
}

Trajectory DriveSim::trajectory() const noexcept {
  return {plan_, epoch_, origin_mm_, down_};
}

double DriveSim::position_mm() const noexcept {
  return trajectory().position_mm(now_);
}

double DriveSim::velocity_mps() const noexcept {
  return trajectory().velocity_mps(now_);
}

bool DriveSim::stationary() const noexcept {
  const double t = seconds(now_);
  return t >= plan_.settle_time_s() && plan_.final_speed_mps() < kStillMps;
}

void DriveSim::set_position_mm(double position_mm) noexcept {
  if (phase_ != Phase::Idle || !stationary()) return;
  origin_mm_ = position_mm;
  down_ = false;
  plan_.reset(seconds(now_), MotionState{});
}

void DriveSim::advance(MonoTime now) noexcept {
  if (now < now_) now = now_;
  now_ = now;
  update_motion(now);
  update_timers(now);
}

void DriveSim::update_motion(MonoTime now) noexcept {
  if (phase_ != Phase::Moving) return;
  const double t = seconds(now);
  const MotionState st = plan_.at(t);
  // DCP 4.2.1.2: the reported deceleration distance counts up while accelerating and then
  // stays constant (also through the deceleration).
  if (st.a_mps2 >= 0.0 && st.v_mps > 0.0) {
    decel_report_m_ = std::max(decel_report_m_, ramp_distance_m(st.v_mps, 0.0, config_.decel));
  }
  if (stopping_ && t >= plan_.settle_time_s() && plan_.final_speed_mps() < kStillMps) {
    set_phase(Phase::Holding, now);  // DCP 9.1.7: S6 drops at standstill, torque held
  }
}

void DriveSim::update_timers(MonoTime now) noexcept {
  const MonoTime in_phase = now - phase_since_;
  switch (phase_) {
    case Phase::Magnetising:
      if (in_phase >= std::chrono::milliseconds(config_.magnetising_ms)) {
        if (kind_ == TravelKind::FastStart) {
          set_phase(Phase::FastStartHold, now);
        } else if (kind_ == TravelKind::Distance && go_pending_) {
          set_phase(Phase::FastStartHold, now);  // go came early; wait for the distance
        } else {
          begin_motion(now);
        }
      }
      break;
    case Phase::FastStartHold:
      if (in_phase >= std::chrono::milliseconds(config_.fast_start_limit_ms)) {
        raise_fault(FaultCause::FastStartTimeout, now);
      }
      break;
    case Phase::Holding:
      if (in_phase >= std::chrono::milliseconds(config_.hold_torque_ms)) {
        const double end_mm = position_mm();
        last_travel_mm_ = static_cast<std::int64_t>(std::llround(end_mm - travel_start_mm_));
        travel_measured_ = true;
        ++counters_.travels;
        emit(SimEvent::Kind::TravelEnded, now, last_travel_mm_);
        stop_without_i9_ = true;  // DCP 5.12.9: the master now owes an I9
        stop_at_ = now;
        max_torque_ = false;  // DCP 5.12.4: only for the next travel
        accepted_ = false;
        set_phase(Phase::Finished, now);
      }
      break;
    case Phase::Idle:
    case Phase::Moving:
    case Phase::Finished:
      break;
  }

  // DCP 7.3: 10 bad or missing frames (150 ms) during a travel -> fault, stop at once.
  const bool travelling = phase_ == Phase::Magnetising || phase_ == Phase::Moving ||
                          phase_ == Phase::FastStartHold || phase_ == Phase::Holding;
  // The n-th missing frame counts once its slot has passed by half a cycle.
  const MonoTime silence_limit = kCycle * config_.link_timeout_frames + kCycle / 2;
  if (travelling &&
      (now - last_good_ >= silence_limit || bad_streak_ >= config_.link_timeout_frames)) {
    raise_fault(FaultCause::LinkTimeout, now);
  }

  // DCP 5.4: no exchange for 1 s resets the channel; a new I0 is needed.
  if (now - last_good_ > dcp::kChannelTimeout &&
      (initialised_ || display_active_ || out_.size() > 0 || parser_.in_frame())) {
    parser_.reset(now);
    out_.clear();
    display_active_ = false;
    initialised_ = false;
    emit(SimEvent::Kind::ChannelReset, now, 0);
  }
  (void)parser_.poll(now);  // DCP 5.4: STX without ETX for 1 s

  if (reset_pending_ && now >= reset_at_) {
    reset_pending_ = false;
    clear_fault(FaultCause::LinkTimeout, now);
    clear_fault(FaultCause::FastStartTimeout, now);
    emit(SimEvent::Kind::DriveReset, now, 0);
  }

  if (display_active_ && now - display_refresh_ >= 1s) {
    display_refresh_ = now;
    render_display();
    flush_display(false);
  }
}

// ---------------------------------------------------------------- frames

Reply DriveSim::on_master_frame(std::span<const std::uint8_t, dcp::kFrameSize> bytes,
                                MonoTime now) noexcept {
  advance(now);
  ++counters_.frames;
  ++frame_index_;
  const bool inject_s7 = take_fault(ReplyFault::MessageError);
  const auto frame = inject_s7 ? std::nullopt : dcp::decode_master(bytes);

  dcp::SlaveFrame out;
  bool repeat = false;
  if (!frame) {
    // DCP 6.2 a: ignore the frame; reply with S7, current data, idle channel bytes.
    ++counters_.bad_frames;
    ++bad_streak_;
    good_streak_ = 0;
    update_timers(now);
  } else {
    bad_streak_ = 0;
    ++good_streak_;
    note_transport_delay(now);
    last_good_ = now;
    process(*frame, now);
    // DCP 7.3: resume after 10 good frames while stationary.
    if (faults_[cause_index(FaultCause::LinkTimeout)] && stationary() &&
        good_streak_ >= config_.link_timeout_frames) {
      clear_fault(FaultCause::LinkTimeout, now);
    }
    repeat = (frame->command & cb::kReplyChecksumError) != 0 && have_last_reply_;
  }

  out.status = status_byte();
  if (!frame) out.status |= sb::kMessageChecksumError;
  out.set_data_word(data_word());
  if (repeat) {
    ++counters_.repeats;
    // DCP 6.2 b: repeat the last reply. DCP3 repeats it whole; DCP4 keeps the current status
    // and data and repeats only the channel bytes (DCP 6 note).
    if (config_.protocol == dcp::Protocol::Dcp3) {
      out.status = last_reply_[0];
      out.data1 = last_reply_[1];
      out.data2 = last_reply_[2];
    }
    out.comm1 = last_reply_[3];
    out.comm2 = last_reply_[4];
  } else if (frame && now >= channel_silent_until_) {
    out.comm1 = out_.pop();
    out.comm2 = out_.pop();
  }
  const dcp::FrameBytes encoded = dcp::encode(out);
  last_reply_ = encoded;
  have_last_reply_ = true;

  Reply reply;
  reply.delay = config_.reply_delay;
  std::copy(encoded.begin(), encoded.end(), reply.bytes.begin());
  reply.size = dcp::kFrameSize;
  if (take_fault(ReplyFault::NoReply)) {
    reply.size = 0;
    return reply;
  }
  if (take_fault(ReplyFault::BadChecksum)) reply.bytes[5] ^= 0x5A;
  if (take_fault(ReplyFault::Late)) reply.delay = config_.late_reply_delay;
  if (take_fault(ReplyFault::Garbage)) {
    for (std::size_t i = 0; i < 3; ++i) {
      rng_ ^= rng_ << 13;
      rng_ ^= rng_ >> 7;
      rng_ ^= rng_ << 17;
      reply.bytes[i] = static_cast<std::uint8_t>(rng_ >> 24);
    }
    reply.size = 3;
  }
  ++counters_.replies;
  return reply;
}

std::uint8_t DriveSim::status_byte() const noexcept {
  const bool fault = std::any_of(faults_.begin(), faults_.end(), [](bool f) { return f; });
  std::uint8_t s = 0;
  if (!fault && !not_ready_ && (initialised_ || !config_.require_init)) s |= sb::kReady;
  if (phase_ == Phase::Magnetising || phase_ == Phase::Moving || phase_ == Phase::FastStartHold ||
      phase_ == Phase::Holding) {
    s |= sb::kTravelActive;
  }
  if (advance_warning_) s |= sb::kAdvanceWarning;
  if (fault) s |= sb::kGeneralFault;
  if (std::fabs(velocity_mps()) < kLevellingSpeedMps) s |= sb::kBelowLevelling;
  if (accepted_) s |= sb::kAccepted;
  if (phase_ == Phase::Moving || phase_ == Phase::FastStartHold) s |= sb::kBrakeOpen;
  return s;
}

std::uint32_t DriveSim::reported_decel_mm() const noexcept {
  // DCP 4.2.1.2: saturated while stationary or starting.
  if (phase_ != Phase::Moving || decel_report_m_ <= 0.0) return 0xFFFFFFFFU;
  return static_cast<std::uint32_t>(std::llround(decel_report_m_ * 1000.0));
}

std::uint16_t DriveSim::data_word() noexcept {
  dcp::ExtendedStatus ext = ext_flags_;
  const double v = std::fabs(velocity_mps());
  ext.below_unlocking_speed = v < kUnlockingSpeedMps;
  ext.below_border_speed = v < config_.border_speed_mps;
  ext.below_overspeed = v < config_.overspeed_mps;
  const std::uint32_t decel = reported_decel_mm();
  switch (data_info_type_) {
    case dcp::DataInfoType::Alternating:
      // DCP 4.2.2.1: alternate per frame, so each kind is refreshed every 30 ms.
      return frame_index_ % 2 == 0
                 ? dcp::encode_deceleration_distance(decel, dcp::DistanceWidth::Bits15)
                 : ext.to_word();
    case dcp::DataInfoType::Decel15:
      return dcp::encode_deceleration_distance(decel, dcp::DistanceWidth::Bits15);
    case dcp::DataInfoType::Decel16:
      return dcp::encode_deceleration_distance(decel, dcp::DistanceWidth::Bits16);
    case dcp::DataInfoType::Extended:
    case dcp::DataInfoType::ExtendedDist16:
      return ext.to_word();
  }
  return ext.to_word();
}

// ---------------------------------------------------------------- travel sequencing

bool DriveSim::can_start() const noexcept {
  const std::uint8_t s = status_byte();
  // DCP 9.1.3 / 9.1.5 / 9.1.6: only with S0 = 1, S2 = 0, S3 = 0.
  return phase_ == Phase::Idle && stationary() && (s & sb::kReady) != 0 &&
         (s & (sb::kAdvanceWarning | sb::kGeneralFault)) == 0 && !fast_stop_latched_;
}

void DriveSim::note_transport_delay(MonoTime now) noexcept {
  // A frame read later than one cycle (DCP 7.2: 15 ms) after the previous one was held up on
  // its way (the master's thread, the line, or this drive's own reading): the remaining
  // distance it carries was measured that much earlier. The largest such delay is kept for the
  // next 10 frames (DCP 7.3's supervision window), since the frames queued behind a held-up one
  // are just as old when read.
  const MonoTime late_by =
      last_good_ == MonoTime{} ? MonoTime{} : std::max(MonoTime{}, now - last_good_ - kCycle);
  if (late_by >= transport_delay_ || frames_since_delay_ >= config_.link_timeout_frames) {
    transport_delay_ = late_by;
    frames_since_delay_ = 0;
  } else {
    ++frames_since_delay_;
  }
}

void DriveSim::process(const dcp::MasterFrame& frame, MonoTime now) noexcept {
  if (now >= channel_silent_until_) {  // an injected channel silence hears nothing
    process_channel(frame.comm1, now);
    process_channel(frame.comm2, now);
  }
  const FrameView f = view(frame);
  tracker_.observe(f.type);
  if (f.type == dcp::MessageType::Invalid) return;
  if (!f.b0) {
    on_enable_off(f, now);
    return;
  }
  if (phase_ == Phase::Finished) {
    if ((!f.b1 && !f.b2) || f.type == dcp::MessageType::Speed) {
      set_phase(Phase::Idle, now);
      kind_ = TravelKind::None;
    } else {
      return;  // B1/B2 still held from the finished travel
    }
  }
  if (phase_ == Phase::Idle) {
    on_frame_at_rest(f, now);
    return;
  }
  on_frame_in_travel(f, now);
}

DriveSim::FrameView DriveSim::view(const dcp::MasterFrame& frame) const noexcept {
  FrameView f{frame};
  f.command = frame.command;
  f.type = dcp::classify_command(f.command, config_.protocol);
  f.b0 = (f.command & cb::kDriveEnable) != 0;
  f.b1 = (f.command & cb::kTravel) != 0;
  f.b2 = (f.command & cb::kStopSwitch) != 0;
  f.down = (f.command & cb::kDirectionDown) != 0;
  const auto parsed =
      (f.type == dcp::MessageType::Speed || f.type == dcp::MessageType::SpeedAfterFastStart)
          ? dcp::speed_from_word(frame.data_word())
          : std::nullopt;
  f.has_speed = parsed.has_value();
  f.speed = parsed.value_or(dcp::Speed::V0);
  f.speed_ok = f.has_speed && dcp::speed_allowed(f.speed, config_.protocol);
  return f;
}

void DriveSim::on_enable_off(const FrameView& f, MonoTime now) noexcept {
  // DCP 9.1.1 / 12.2.1: enable withdrawn: drop everything at once, the brake stops the car.
  if (phase_ != Phase::Idle && phase_ != Phase::Finished) abort_travel(now);
  if (phase_ == Phase::Finished) set_phase(Phase::Idle, now);
  kind_ = TravelKind::None;
  if (stationary()) fast_stop_latched_ = false;
  if (f.type == dcp::MessageType::Idle) accepted_ = speed_selected_;
}

void DriveSim::on_frame_at_rest(const FrameView& f, MonoTime now) noexcept {
  if (f.type == dcp::MessageType::Speed) {
    speed_selected_ = f.speed_ok;
    accepted_ = f.speed_ok;
    if (f.speed_ok) selected_ = f.speed;
    // DCP 12.1.1: fast start = speed message VF with B3=1 B2=0 B1=0 B0=1.
    if (f.speed_ok && f.speed == dcp::Speed::VF && can_start()) {
      start_travel(TravelKind::FastStart, dcp::Speed::VF, f.down, now, 0);
    }
    return;
  }
  if (!can_start()) return;
  b1_ = f.b1;
  b2_ = f.b2;
  if (f.type == dcp::MessageType::DistanceOrDecel && config_.protocol == dcp::Protocol::Dcp4 &&
      tracker_.meaning() == dcp::DistanceModeTracker::Meaning::RemainingDistance) {
    start_distance_travel(f, now);
    return;
  }
  if (f.b1 && speed_selected_) {
    switch (selected_) {
      case dcp::Speed::VI:
        start_travel(TravelKind::Inspection, selected_, f.down, now, 0);
        break;
      case dcp::Speed::V0:
        start_travel(TravelKind::Crawl, selected_, f.down, now, 0);
        break;
      case dcp::Speed::VN:
        start_travel(TravelKind::Relevel, selected_, f.down, now, 0);
        break;
      case dcp::Speed::VF:
        break;
      default:
        start_travel(TravelKind::Speed, selected_, f.down, now, 0);
        break;
    }
    return;
  }
  if (f.b2 && !f.b1 && f.type == dcp::MessageType::DistanceOrDecel) {
    // DCP 10.3 note / 9.2.1.2: B2 alone travels at crawl speed.
    start_travel(TravelKind::Crawl, dcp::Speed::V0, f.down, now, 0);
  }
}

void DriveSim::start_distance_travel(const FrameView& f, MonoTime now) noexcept {
  const bool distance_speed =
      selected_ == dcp::Speed::V4 || selected_ == dcp::Speed::V3 || selected_ == dcp::Speed::VN;
  if (!speed_selected_ || !distance_speed) {
    // DCP 9.2.1.2: VI then B2 only is an inspection travel at crawl speed.
    if (speed_selected_ && selected_ == dcp::Speed::VI && f.b2 && !f.b1) {
      start_travel(TravelKind::Crawl, dcp::Speed::V0, f.down, now, 0);
    }
    return;
  }
  const bool wide = dcp::remaining_distance_width(data_info_type_) == dcp::DistanceWidth::Bits16;
  const std::uint16_t word =
      wide ? f.frame.data_word() : static_cast<std::uint16_t>(f.frame.data_word() & kMax15);
  start_travel(TravelKind::Distance, selected_, f.down, now, word);
}

void DriveSim::on_frame_in_travel(const FrameView& f, MonoTime now) noexcept {
  // A travel is running (Magnetising, Moving, FastStartHold or Holding).
  const bool fast_stop_msg =
      f.type == dcp::MessageType::SpeedAfterFastStart && f.has_speed && f.speed == dcp::Speed::VF;
  if (fast_stop_latched_) return;  // DCP 13.2: no further travel command accepted
  if (phase_ == Phase::Moving && fast_stop_msg) {
    fast_stop_latched_ = true;
    emit(SimEvent::Kind::FastStop, now, 0);
    plan_stop(config_.fast_stop, now);
    return;
  }
  if (phase_ == Phase::Moving && f.down != down_ && !stopping_) {
    plan_stop(config_.decel, now);  // DCP 9.1.2: direction changed: decelerate, no fault
    return;
  }
  if (kind_ == TravelKind::FastStart || (kind_ == TravelKind::Distance && go_pending_)) {
    on_frame_in_fast_start(f, now);
    return;
  }
  switch (kind_) {
    case TravelKind::Distance:
      on_frame_in_distance_travel(f, now);
      break;
    case TravelKind::Speed:
      on_frame_in_speed_travel(f, now);
      break;
    case TravelKind::Inspection:
      if (f.type == dcp::MessageType::Speed) break;
      b1_ = f.b1;
      b2_ = f.b2;
      if (phase_ == Phase::Magnetising && !f.b1 && !f.b2) {
        controlled_abort(now);
      } else if (phase_ == Phase::Moving && !stopping_) {
        if (!f.b1 && !f.b2) {
          plan_stop(config_.decel, now);
        } else if (!f.b1 && !to_crawl_) {
          to_crawl_ = true;  // DCP 9.2.1.1: end zone reached: crawl while B2
          plan_to_speed(config_.speeds.v0_mps, now);
        }
      }
      break;
    case TravelKind::Crawl:
      if (f.type == dcp::MessageType::Speed) break;
      if (!f.b1 && !f.b2) stop_from_crawl(now);
      break;
    case TravelKind::Relevel:
      if (f.type == dcp::MessageType::Speed) break;
      // DCP 9.2.3.2: electric stop: decelerate to 0, hold, then S6 and S1 drop.
      if (!f.b1) stop_from_crawl(now);
      break;
    case TravelKind::FastStart:
    case TravelKind::None:
      break;
  }
}

void DriveSim::stop_from_crawl(MonoTime now) noexcept {
  if (phase_ == Phase::Magnetising) {
    controlled_abort(now);
  } else if (phase_ == Phase::Moving && !stopping_) {
    plan_stop(config_.decel, now);
  }
}

void DriveSim::on_frame_in_fast_start(const FrameView& f, MonoTime now) noexcept {
  if (f.type == dcp::MessageType::Stop) {
    controlled_abort(now);  // DCP 12.2.2
    return;
  }
  if (f.type == dcp::MessageType::SpeedAfterFastStart && kind_ == TravelKind::FastStart &&
      f.speed_ok && f.speed != dcp::Speed::VN && f.speed != dcp::Speed::VF) {
    // DCP 12.1.3: go.
    run_speed_ = f.speed;
    selected_ = f.speed;
    accepted_ = true;
    b1_ = f.b1;
    b2_ = f.b2;
    if (config_.protocol == dcp::Protocol::Dcp4) {
      kind_ = TravelKind::Distance;
      go_pending_ = true;
      return;
    }
    kind_ = f.speed == dcp::Speed::VI   ? TravelKind::Inspection
            : f.speed == dcp::Speed::V0 ? TravelKind::Crawl
                                        : TravelKind::Speed;
    if (phase_ == Phase::FastStartHold) begin_motion(now);
    return;
  }
  if (f.type == dcp::MessageType::DistanceOrDecel && go_pending_) {
    on_remaining_distance(f.frame.data_word(), now);
  }
}

void DriveSim::on_frame_in_distance_travel(const FrameView& f, MonoTime now) noexcept {
  if (f.type == dcp::MessageType::DistanceOrDecel) {
    if (b2_) on_remaining_distance(f.frame.data_word(), now);
    return;
  }
  if (f.b2 || !b2_) return;
  b2_ = false;
  if (phase_ == Phase::Magnetising) {
    controlled_abort(now);  // nothing moves yet: close the brake (DCP 12.2.2)
  } else if (phase_ == Phase::Moving && decelerating(now)) {
    plan_stop(config_.decel, now);  // DCP 3.5.3.2: stop mode "During deceleration"
  } else if (phase_ == Phase::Moving) {
    // DCP 11.1.1 d: "Stop switch bit B2 remains activated until the lift car comes to the
    // level and the drive controller switches the mechanical brake bit S6/MB off".
    report_violation(Violation::StopAtSpeed, now);
    plan_stop(config_.fast_stop, now);
  }
}

void DriveSim::on_frame_in_speed_travel(const FrameView& f, MonoTime now) noexcept {
  if (f.type == dcp::MessageType::Speed) {
    // DCP 3.1 B5: speed change during the travel.
    if ((f.command & cb::kSpeedChange) != 0 && f.speed_ok && phase_ == Phase::Moving &&
        !to_crawl_ && !stopping_) {
      run_speed_ = f.speed;
      plan_to_speed(config_.speeds.of(f.speed), now);
    }
    return;
  }
  b1_ = f.b1;
  b2_ = f.b2;
  if (phase_ == Phase::Magnetising && !f.b1 && !f.b2) {
    controlled_abort(now);
    return;
  }
  if (phase_ != Phase::Moving || stopping_) return;
  if (!f.b1 && !f.b2 && to_crawl_) {
    plan_stop(config_.decel, now);  // DCP 10.1.1 step 4: B2 positions the car at crawl
  } else if (!f.b1 && !f.b2) {
    // DCP 3.5.3.2: stop mode only "During deceleration"; at speed B1 must drop first so
    // the drive slows to crawl within SVx (DCP 10.1.1 step 3).
    report_violation(Violation::StopAtSpeed, now);
    plan_stop(config_.fast_stop, now);
  } else if (!f.b1 && !to_crawl_) {
    // DCP 10.1.1: B1 off -> decelerate to crawl within the fixed distance SVx. DCP 10.1.2 /
    // 10.2.2: the same SVx when B1 drops before Vx was reached (time-optimised short
    // travel): the car may still speed up towards Vx or cruise first, and brakes harder
    // (at most on the fast-stop ramp) when its normal ramp cannot make it.
    to_crawl_ = true;
    const double t0 = std::max(seconds(now), motion_start_s_);
    const MotionState st = plan_.at(t0);
    plan_.plan_fixed_arrival(t0, st, st.s_m + dcp3_decel_m(run_speed_),
                             config_.speeds.of(run_speed_), config_.speeds.v0_mps, config_.accel,
                             config_.decel, config_.fast_stop);
  }
}

void DriveSim::start_travel(TravelKind kind, dcp::Speed speed, bool down, MonoTime now,
                            std::int64_t distance_mm) noexcept {
  const double here = position_mm();
  kind_ = kind;
  run_speed_ = speed;
  down_ = down;
  origin_mm_ = here;
  travel_start_mm_ = here;
  plan_.reset(seconds(now), MotionState{});
  speed_selected_ = false;
  accepted_ = true;
  stopping_ = false;
  to_crawl_ = false;
  go_pending_ = false;
  decel_report_m_ = 0.0;
  // The Sv of an I7 exchanged just before this travel bounds its extensions (DCP 11.1.2 note).
  travel_i7_decel_m_ = i7_decel_m_;
  i7_decel_m_ = -1.0;
  // An injected channel silence since the stop may have eaten the I9: not the master's fault.
  const bool channel_deaf_since_stop = channel_silent_until_ > stop_at_;
  if (stop_without_i9_ && initialised_ && !channel_deaf_since_stop) {
    report_violation(Violation::NoPositionAfterStop, now);
  }
  stop_without_i9_ = false;
  crawl_limited_ = false;
  rd_saturated_ = false;
  target_s_m_ = static_cast<double>(distance_mm) / 1000.0;
  target_read_at_mps_ = 0.0;
  if (kind == TravelKind::Distance &&
      distance_mm < static_cast<std::int64_t>(config_.crawl_limit_mm)) {
    crawl_limited_ = true;  // DCP 11.1.2 safety note: start distance < 20 cm -> crawl
  }
  emit(SimEvent::Kind::TravelStarted, now, static_cast<std::int64_t>(kind), distance_mm);
  set_phase(Phase::Magnetising, now);
}

void DriveSim::begin_motion(MonoTime now) noexcept {
  const bool brake_open = phase_ == Phase::FastStartHold;
  set_phase(Phase::Moving, now);
  motion_start_s_ =
      seconds(now) + (brake_open ? 0.0 : static_cast<double>(config_.brake_release_ms) / 1000.0);
  plan_.reset(motion_start_s_, plan_.at(seconds(now)));
  switch (kind_) {
    case TravelKind::Distance:
      plan_to_target(now);
      break;
    case TravelKind::Crawl:
      plan_to_speed(config_.speeds.v0_mps, now);
      break;
    case TravelKind::Speed:
    case TravelKind::Inspection:
    case TravelKind::Relevel:
      plan_to_speed(config_.speeds.of(run_speed_), now);
      break;
    case TravelKind::FastStart:
    case TravelKind::None:
      break;
  }
}

void DriveSim::plan_stop(const RampLimits& ramp, MonoTime now) noexcept {
  const double t0 = std::max(seconds(now), motion_start_s_);
  plan_.plan_speed(t0, plan_.at(t0), 0.0, config_.accel, ramp);
  stopping_ = true;
}

void DriveSim::plan_to_speed(double speed_mps, MonoTime now) noexcept {
  const double t0 = std::max(seconds(now), motion_start_s_);
  plan_.plan_speed(t0, plan_.at(t0), speed_mps, config_.accel, config_.decel);
  stopping_ = speed_mps <= 0.0;
}

double DriveSim::target_vmax_mps() const noexcept {
  const double vmax = config_.speeds.of(run_speed_);
  return crawl_limited_ ? std::min(vmax, config_.speeds.v0_mps) : vmax;
}

void DriveSim::plan_to_target(MonoTime now) noexcept {
  const double t0 = std::max(seconds(now), motion_start_s_);
  plan_.plan_arrival(t0, plan_.at(t0), target_s_m_, target_vmax_mps(), 0.0, config_.accel,
                     config_.decel);
  stopping_ = true;
}

void DriveSim::on_remaining_distance(std::uint16_t raw, MonoTime now) noexcept {
  const bool wide = dcp::remaining_distance_width(data_info_type_) == dcp::DistanceWidth::Bits16;
  const std::uint16_t word = wide ? raw : static_cast<std::uint16_t>(raw & kMax15);
  const bool saturated = word == (wide ? kMax16 : kMax15);
  const double rd_m = static_cast<double>(word) / 1000.0;
  const double tol_m = static_cast<double>(config_.distance_tolerance_mm) / 1000.0;

  if (go_pending_) {
    // DCP 12.1.2: 0x0000 while held; the first real distance after the go starts the car.
    if (word == 0) return;
    go_pending_ = false;
    target_s_m_ = plan_.at(seconds(now)).s_m + rd_m;
    crawl_limited_ = word < config_.crawl_limit_mm;
    emit(SimEvent::Kind::TravelStarted, now, static_cast<std::int64_t>(kind_), word);
    if (phase_ == Phase::FastStartHold) begin_motion(now);
    return;
  }
  if (phase_ == Phase::Magnetising) {
    target_s_m_ = rd_m;  // not moving yet: the target may still change freely
    crawl_limited_ = word < config_.crawl_limit_mm;
    return;
  }
  if (phase_ != Phase::Moving || !accepted_) return;

  const double t = std::max(seconds(now), motion_start_s_);
  const MotionState st = plan_.at(t);
  // The master measured its position up to a cycle or two before the drive reads the frame
  // (DCP 7.2: 15 ms cycle), longer when the frame was held up on its way: allow that much
  // travel on top of the jitter tolerance. A plausibility check must judge the master's
  // target, not the age of the frame carrying it.
  const double lag_s =
      kPositionLag.count() + std::chrono::duration<double>(transport_delay_).count();
  const double lag_tol_m = tol_m + st.v_mps * lag_s;
  const double implied_m = st.s_m + rd_m;
  const double diff_m = implied_m - target_s_m_;
  // While the distance is saturated, and on the first real value after it, any extension
  // counts: the true target is only known from then on.
  const bool exact = saturated || rd_saturated_;
  rd_saturated_ = saturated;
  // DCP 3.5.3.4: a remaining distance of 0 says the car is at its target. While this drive's
  // car is on or past its own target (it ran past braking on a harder ramp after a late
  // correction) the master agrees with the drive: nothing to judge and nothing to change.
  if (word == 0 && diff_m >= 0.0) return;
  const double extend_tol_m = exact ? 1e-4 : lag_tol_m;
  if (diff_m >= 0.0 ? diff_m <= extend_tol_m : -diff_m <= lag_tol_m) {
    // DCP 3.5.3.4: "the drive unit must process always the remaining distance during the
    // total travel". A distance read at speed is off by the master's measuring lag times that
    // speed; once a target came from a moving car, each reading at a lower speed is the better
    // one and the drive follows it, so the readings converge on the level as the car slows.
    // A target read at rest (the start of a travel) is exact and stays. A correction while
    // the car already brakes may need a slightly harder ramp (at most the fast-stop ramp). A
    // reading of 0 (the master sees the car on or past its level) says no more than that the
    // lag is there: never a target behind the car.
    if (!saturated && word != 0 && st.v_mps < target_read_at_mps_) {
      target_s_m_ = implied_m;
      target_read_at_mps_ = st.v_mps;
      const double t0 = std::max(seconds(now), motion_start_s_);
      plan_.plan_fixed_arrival(t0, plan_.at(t0), target_s_m_, target_vmax_mps(), 0.0, config_.accel,
                               config_.decel, config_.fast_stop);
      stopping_ = true;
    }
    return;
  }
  const double remaining_m = target_s_m_ - st.s_m;
  const double stop_m = MotionPlan::ramp_distance_from_m(st, 0.0, config_.accel, config_.decel);
  if (refuse_next_target_) {  // injected: this drive's plausibility check says no
    refuse_next_target_ = false;
    refuse_target(word, now);
    return;
  }
  if (diff_m > 0.0) {
    // DCP 11.1.2 note: "The controller can increase the remaining distance while it is greater
    // than the deceleration distance the drive controller had transmitted before the beginning
    // of the travel" (Sv of I7, 11.1.2.1), and never once the car decelerates.
    const double limit_m = std::max(stop_m, travel_i7_decel_m_);
    if (st.a_mps2 >= 0.0 && remaining_m > limit_m) {
      target_s_m_ = implied_m;
      target_read_at_mps_ = st.v_mps;
      plan_to_target(now);
      ++counters_.extensions;
      if (!saturated) emit(SimEvent::Kind::TargetExtended, now, word);
    } else {
      refuse_target(word, now);
    }
    return;
  }
  // A nearer level: DCP 3.5.3.4 "the drive unit must process always the remaining distance
  // during the total travel" and 11.1.2 "the drive controller calculates a time optimised lift
  // travel curve online": a level the car can still reach on its normal ramp is taken over.
  if (rd_m > stop_m + tol_m) {
    target_s_m_ = implied_m;
    target_read_at_mps_ = st.v_mps;
    plan_to_target(now);
    ++counters_.shortened;
    emit(SimEvent::Kind::TargetExtended, now, word);
    return;
  }
  refuse_target(word, now);
}

void DriveSim::refuse_target(std::uint16_t word, MonoTime now) noexcept {
  // DCP 4.1 S5 note: "If a plausibility error is found in the remaining distance transmitted,
  // the drive controller should carry out an emergency stop. This bit is then cleared until
  // the lift has stopped. The drive controller should then output an error message."
  accepted_ = false;
  ++counters_.refused_extensions;
  ++counters_.implausible;
  emit(SimEvent::Kind::ExtensionRefused, now, word);
  emit(SimEvent::Kind::Fault, now, static_cast<std::int64_t>(FaultCause::Implausible), word);
  send_error_message("DISTANCE IMPLAUSIBLE");
  plan_stop(config_.fast_stop, now);
}

bool DriveSim::decelerating(MonoTime now) const noexcept {
  // The car is on its final ramp: slowing down (a < 0) towards standstill, or already below
  // the levelling speed of DCP 4.1 S4 (v < 0.3 m/s).
  const MotionState st = plan_.at(std::max(seconds(now), motion_start_s_));
  return (stopping_ && st.a_mps2 < 0.0) || std::fabs(st.v_mps) < kLevellingSpeedMps;
}

void DriveSim::report_violation(Violation kind, MonoTime now) noexcept {
  ++violations_[static_cast<std::size_t>(kind)];
  ++counters_.violations;
  emit(SimEvent::Kind::Violation, now, static_cast<std::int64_t>(kind));
}

void DriveSim::controlled_abort(MonoTime now) noexcept {
  // DCP 12.2.2: close the brake (S6 = 0), hold, then S1 = 0.
  go_pending_ = false;
  plan_.reset(seconds(now), plan_.at(seconds(now)));
  set_phase(Phase::Holding, now);
}

void DriveSim::abort_travel(MonoTime now) noexcept {
  if (phase_ == Phase::Moving) {
    const double t0 = std::max(seconds(now), motion_start_s_);
    plan_.plan_speed(t0, plan_.at(t0), 0.0, config_.accel, config_.brake_stop);
    stopping_ = true;
    const double end_s_mm = plan_.final_position_m() * 1000.0;
    last_travel_mm_ = std::llround(origin_mm_ + (down_ ? -end_s_mm : end_s_mm) - travel_start_mm_);
    travel_measured_ = true;
    stop_without_i9_ = true;  // DCP 5.12.9: an aborted travel is a stop too
    stop_at_ = now;
  }
  kind_ = TravelKind::None;
  go_pending_ = false;
  accepted_ = false;
  to_crawl_ = false;
  set_phase(Phase::Idle, now);
}

void DriveSim::set_phase(Phase phase, MonoTime now) noexcept {
  if (phase_ == phase) return;
  phase_ = phase;
  phase_since_ = now;
  emit(SimEvent::Kind::PhaseChanged, now, static_cast<std::int64_t>(phase));
}

double DriveSim::dcp3_decel_m(dcp::Speed speed) const noexcept {
  const auto bit = static_cast<std::uint16_t>(speed);
  std::size_t index = 0;
  while (index < 11 && (bit >> index) != 1U) ++index;
  if (index < config_.dcp3_decel_mm.size() && config_.dcp3_decel_mm[index] != 0) {
    return static_cast<double>(config_.dcp3_decel_mm[index]) / 1000.0;
  }
  return ramp_distance_m(config_.speeds.of(speed), config_.speeds.v0_mps, config_.decel) +
         kCrawlMarginM;
}

DriveSim::StartParameters DriveSim::start_parameters(std::uint32_t distance_cm,
                                                     bool fast) const noexcept {
  double vmax = fast ? config_.speeds.v4_mps : config_.speeds.v3_mps;
  if (distance_cm * 10U < config_.crawl_limit_mm) vmax = config_.speeds.v0_mps;
  const double distance_m = static_cast<double>(distance_cm) / 100.0;
  const double peak = peak_speed_mps(distance_m, vmax, config_.accel, config_.decel);
  StartParameters p;
  const bool long_travel = peak >= vmax * (1.0 - 1e-9);
  p.travel_type = long_travel ? 'l' : 's';
  const double full_m =
      ramp_distance_m(0.0, vmax, config_.accel) + ramp_distance_m(vmax, 0.0, config_.decel);
  p.total_cm = long_travel ? static_cast<std::uint32_t>(std::lround(full_m * 100.0)) : distance_cm;
  p.decel_cm =
      static_cast<std::uint32_t>(std::lround(ramp_distance_m(peak, 0.0, config_.decel) * 100.0));
  return p;
}

// ---------------------------------------------------------------- faults

void DriveSim::raise_fault(FaultCause cause, MonoTime now) noexcept {
  if (faults_[cause_index(cause)]) return;
  faults_[cause_index(cause)] = true;
  emit(SimEvent::Kind::Fault, now, static_cast<std::int64_t>(cause));
  switch (cause) {
    case FaultCause::Injected:
      send_error_message("GENERAL FAULT");
      break;
    case FaultCause::LinkTimeout:
      send_error_message("DCP TIMEOUT");
      break;
    case FaultCause::Implausible:
      send_error_message("DISTANCE IMPLAUSIBLE");
      break;
    case FaultCause::FastStartTimeout:
      send_error_message("FAST START TIMEOUT");
      break;
  }
  // DCP 4.1 S3: drive off, brake applied.
  if (phase_ != Phase::Idle && phase_ != Phase::Finished) abort_travel(now);
}

void DriveSim::clear_fault(FaultCause cause, MonoTime now) noexcept {
  if (!faults_[cause_index(cause)]) return;
  faults_[cause_index(cause)] = false;
  emit(SimEvent::Kind::FaultCleared, now, static_cast<std::int64_t>(cause));
}

void DriveSim::set_general_fault(bool on, MonoTime now) noexcept {
  advance(now);
  if (on)
    raise_fault(FaultCause::Injected, now);
  else
    clear_fault(FaultCause::Injected, now);
}

void DriveSim::inject(ReplyFault fault, std::uint32_t frames) noexcept {
  fault_frames_[fault_index(fault)] = frames;
}

void DriveSim::set_fault_rate(ReplyFault fault, double probability) noexcept {
  fault_rate_[fault_index(fault)] = std::clamp(probability, 0.0, 1.0);
}

void DriveSim::clear_reply_faults() noexcept {
  fault_frames_.fill(0);
  fault_rate_.fill(0.0);
}

void DriveSim::inject_channel(ChannelFault fault, MonoTime now, MonoTime duration) noexcept {
  using namespace dcp::channel_char;
  switch (fault) {
    case ChannelFault::Partial: {
      // STX, the expanded-data mode and the start of an I-message, never an ETX: the master's
      // channel must reset itself 1 s later (DCP 5.4).
      constexpr std::array<std::uint8_t, 4> kPartial{kStx, kModeExpanded, 'I', '7'};
      out_.push_raw(kPartial);
      break;
    }
    case ChannelFault::Garbage: {
      // A frame with an undefined mode byte, then stray control characters outside a frame.
      constexpr std::array<std::uint8_t, 7> kGarbage{kStx, 0x11, 'X', 'Y', kEtx, 0x05, 0x17};
      out_.push_raw(kGarbage);
      break;
    }
    case ChannelFault::Silence:
      channel_silent_until_ = now + duration;
      break;
  }
}

bool DriveSim::take_fault(ReplyFault fault) noexcept {
  auto& n = fault_frames_[fault_index(fault)];
  if (n > 0) {
    --n;
    return true;
  }
  const double rate = fault_rate_[fault_index(fault)];
  if (rate <= 0.0) return false;
  // xorshift64: deterministic, allocation free.
  rng_ ^= rng_ << 13;
  rng_ ^= rng_ >> 7;
  rng_ ^= rng_ << 17;
  return static_cast<double>(rng_ >> 11) / 9007199254740992.0 < rate;  // 2^53
}

void DriveSim::emit(SimEvent::Kind kind, MonoTime now, std::int64_t value,
                    std::int64_t detail) noexcept {
  const std::size_t slot = (event_head_ + event_count_) % kEventCapacity;
  events_[slot] = SimEvent{now, kind, value, detail};
  if (event_count_ < kEventCapacity) {
    ++event_count_;
  } else {
    event_head_ = (event_head_ + 1) % kEventCapacity;  // drop the oldest
  }
}

bool DriveSim::pop_event(SimEvent& out) noexcept {
  if (event_count_ == 0) return false;
  out = events_[event_head_];
  event_head_ = (event_head_ + 1) % kEventCapacity;
  --event_count_;
  return true;
}

// ---------------------------------------------------------------- channel (DCP 5)

void DriveSim::process_channel(std::uint8_t byte, MonoTime now) noexcept {
  switch (parser_.feed(byte, now)) {
    case dcp::ParseStatus::Reset:
      if (parser_.reset_reason() == dcp::ChannelReset::StxEtx) {
        // DCP 5.10: STX ETX returns both ends to their initial state (display cleared).
        out_.clear();
        display_active_ = false;
        emit(SimEvent::Kind::ChannelReset, now, 1);
      }
      break;
    case dcp::ParseStatus::Complete: {
      const dcp::ChannelFrame& frame = parser_.frame();
      if (frame.mode == dcp::ChannelMode::Expanded) {
        handle_i_message(frame.payload(), now);
      } else if (frame.mode == dcp::ChannelMode::Remote) {
        const auto keys = dcp::decode_keypad(frame.payload());
        if (keys.ok()) handle_keypad(keys.value, now);
      }
      break;
    }
    case dcp::ParseStatus::NeedMore:
    case dcp::ParseStatus::Bad:
      break;
  }
}

void DriveSim::send_error_message(std::string_view text) noexcept {
  std::array<std::uint8_t, 20> body{};  // DCP 5.11: 1..20 characters
  const std::size_t n = std::min(text.size(), body.size());
  for (std::size_t i = 0; i < n; ++i) body[i] = static_cast<std::uint8_t>(text[i]);
  out_.push_message(dcp::channel_char::kModeDriveError,
                    std::span<const std::uint8_t>(body.data(), n));
}

void DriveSim::handle_i_message(std::span<const std::uint8_t> payload, MonoTime now) noexcept {
  const auto request = dcp::decode_master_message(payload);
  if (!request.ok()) {
    if (payload.size() >= 2 && payload[1] == static_cast<std::uint8_t>(dcp::MessageId::Init)) {
      // DCP 5.12.2: no travel after a faulty I0; report it.
      initialised_ = false;
      send_error_message("INIT MESSAGE INVALID");
    }
    return;  // anything else unreadable: no answer
  }
  std::optional<dcp::DriveMessage> reply;
  std::visit(
      [&](const auto& m) {
        using T = std::decay_t<decltype(m)>;
        if constexpr (std::is_same_v<T, dcp::InitRequest>) {
          // DCP 5.12.2: switch to the master's language, English when not supported.
          const bool german = m.language == dcp::Code2{'D', 'E'};
          language_ = german ? dcp::Code2{'D', 'E'} : dcp::Code2{'E', 'N'};
          initialised_ = true;
          data_info_type_ = dcp::DataInfoType::Alternating;  // DCP 5.12.3: '0' until I1
          extended_i9_ = false;
          reply = dcp::InitReply{config_.maker, config_.version, config_.date, config_.protocol,
                                 language_};
        } else if constexpr (std::is_same_v<T, dcp::DataInfoRequest>) {
          // An older drive knows no I1 and stays at type '0' (DCP 5.12.3.1).
          if (config_.older_drive) return;
          data_info_type_ = m.type;
          extended_i9_ = m.extended_protocol;  // DCP 5.12.3.2: extended protocol supported
          reply = dcp::DataInfoReply{m.extended_protocol};
        } else if constexpr (std::is_same_v<T, dcp::SwitchRequest>) {
          dcp::SwitchReply r{dcp::SwitchFunction::None, m.reserve};
          switch (m.function) {
            case dcp::SwitchFunction::None:
              reset_pending_ = false;  // DCP 5.12.4: cancel inside the 200 ms window
              max_torque_ = false;
              break;
            case dcp::SwitchFunction::MaxTorque:
              max_torque_ = true;
              r.function = dcp::SwitchFunction::MaxTorque;
              break;
            case dcp::SwitchFunction::Reset:
              // DCP 5.12.4.2: answer '0' when the fault cannot be reset.
              if (!faults_[cause_index(FaultCause::Injected)]) {
                reset_pending_ = true;
                // DCP 5.12.4: at least 200 ms after the reply, at most 1000 ms.
                reset_at_ = now + std::chrono::milliseconds(config_.reset_delay_ms);
                r.function = dcp::SwitchFunction::Reset;
              }
              break;
          }
          reply = r;
        } else if constexpr (std::is_same_v<T, dcp::DateTimeRequest>) {
          date_time_ = m.time;
          reply = dcp::DateTimeReply{};
        } else if constexpr (std::is_same_v<T, dcp::PowerRequest>) {
          power_supply_ = m.supply;  // both supplies and all saving modes are supported
          energy_mode_ = m.saving;
          reply = dcp::PowerReply{power_supply_, energy_mode_};
        } else if constexpr (std::is_same_v<T, dcp::StartParamsRequest>) {
          const StartParameters p =
              start_parameters(m.distance_cm, m.max_speed == dcp::MaxSpeed::V4);
          i7_decel_m_ = static_cast<double>(p.decel_cm) / 100.0;
          reply = dcp::StartParamsReply{
              p.travel_type == 'l' ? dcp::TravelKind::Long : dcp::TravelKind::Short, p.total_cm,
              p.decel_cm};
        } else if constexpr (std::is_same_v<T, dcp::LoadRequest>) {
          load_percent_ = m.load_percent;
          reply = dcp::LoadReply{};
        } else if constexpr (std::is_same_v<T, dcp::PositionRequest>) {
          if (m.position_mm) controller_position_mm_ = *m.position_mm;
          stop_without_i9_ = false;
          // DCP 5.12.9.2: extended reply with the distance measured over the last travel.
          dcp::SignedMm travel;
          if (travel_measured_) travel = static_cast<std::int32_t>(last_travel_mm_);
          reply = dcp::PositionReply{extended_i9_, travel};
        }
      },
      request.value);
  if (!reply) return;
  const auto encoded = dcp::encode(*reply);
  if (!encoded.ok()) return;
  ++counters_.i_messages;
  emit(SimEvent::Kind::ChannelMessage, now, payload[1]);
  if (config_.older_drive && std::holds_alternative<dcp::InitReply>(*reply)) {
    // An older drive's I0 reply: version "1.00" and date "000000" (no digits / no date), the
    // DCP type character still in its place (DCP 5.12.2.2).
    std::array<std::uint8_t, 32> body{};
    const auto bytes = encoded.value.bytes();
    const std::size_t n = std::min(bytes.size(), body.size());
    std::copy_n(bytes.begin(), n, body.begin());
    constexpr std::array<std::uint8_t, 10> kOdd{'1', '.', '0', '0', '0', '0', '0', '0', '0', '0'};
    std::copy(kOdd.begin(), kOdd.end(), body.begin() + 4);  // after 'I' '0' HK1 HK2
    out_.push_message(dcp::channel_char::kModeExpanded,
                      std::span<const std::uint8_t>(body.data(), n));
    return;
  }
  out_.push_message(dcp::channel_char::kModeExpanded, encoded.value.bytes());
}

void DriveSim::handle_keypad(std::uint8_t buttons, MonoTime now) noexcept {
  constexpr int kPages = 4;
  const bool first = !display_active_;
  display_active_ = true;
  const int before = menu_page_;
  // DCP 5.6.3: button "1" = previous page, button "2" = next page.
  if ((buttons & 0x04) != 0) menu_page_ = (menu_page_ + kPages - 1) % kPages;
  if ((buttons & 0x08) != 0) menu_page_ = (menu_page_ + 1) % kPages;
  display_refresh_ = now;
  render_display();
  flush_display(first || before != menu_page_);
}

void DriveSim::render_display() noexcept {
  std::array<char, 21> line{};
  auto set = [&](int row) {
    auto& dst = display_[static_cast<std::size_t>(row)];
    dst.fill(' ');
    for (std::size_t i = 0; i < dst.size() && line[i] != '\0'; ++i) dst[i] = line[i];
  };
  const bool de = language_[0] == 'D';
  switch (menu_page_) {
    case 0:
      std::snprintf(line.data(), line.size(), "DCP%c SIM %s",
                    config_.protocol == dcp::Protocol::Dcp3 ? '3' : '4', de ? "STATUS" : "STATUS");
      set(0);
      std::snprintf(line.data(), line.size(), "%s %+08.0f mm", de ? "Pos" : "Pos", position_mm());
      set(1);
      std::snprintf(line.data(), line.size(), "v %+6.3f m/s", velocity_mps());
      set(2);
      std::snprintf(line.data(), line.size(), "%.*s", 20, to_string(phase_).data());
      set(3);
      break;
    case 1:
      std::snprintf(line.data(), line.size(), "%s", de ? "FAHRTEN" : "TRAVELS");
      set(0);
      std::snprintf(line.data(), line.size(), "%.*s", 20, to_string(kind_).data());
      set(1);
      std::snprintf(line.data(), line.size(), "%s %+lld mm", de ? "zuletzt" : "last",
                    static_cast<long long>(last_travel_mm_));
      set(2);
      std::snprintf(line.data(), line.size(), "%s %llu", de ? "Anzahl" : "count",
                    static_cast<unsigned long long>(counters_.travels));
      set(3);
      break;
    case 2:
      std::snprintf(line.data(), line.size(), "DCP LINK");
      set(0);
      std::snprintf(line.data(), line.size(), "frames %llu",
                    static_cast<unsigned long long>(counters_.frames));
      set(1);
      std::snprintf(line.data(), line.size(), "bad %llu",
                    static_cast<unsigned long long>(counters_.bad_frames));
      set(2);
      std::snprintf(line.data(), line.size(), "repeats %llu",
                    static_cast<unsigned long long>(counters_.repeats));
      set(3);
      break;
    default: {
      std::snprintf(line.data(), line.size(), "%s", de ? "FEHLER" : "FAULTS");
      set(0);
      for (int row = 1; row < 4; ++row) {
        const auto cause = static_cast<FaultCause>(row - 1);
        std::snprintf(line.data(), line.size(), "%c %.*s", faults_[cause_index(cause)] ? '*' : '-',
                      18, to_string(cause).data());
        set(row);
      }
      break;
    }
  }
}

void DriveSim::flush_display(bool all) noexcept {
  for (std::size_t row = 0; row < display_.size(); ++row) {
    if (!all && display_[row] == shown_[row]) continue;
    // DCP 5.7 example 1: line, cursor position 0, 20 characters.
    std::array<std::uint8_t, 22> body{};
    body[0] = static_cast<std::uint8_t>(dcp::channel_char::kLine1 + row);
    body[1] = dcp::channel_char::kCursor0;
    for (std::size_t i = 0; i < 20; ++i) body[2 + i] = static_cast<std::uint8_t>(display_[row][i]);
    if (out_.push_message(dcp::channel_char::kModeRemote, body)) shown_[row] = display_[row];
  }
}

}  // namespace liftd::dcp::sim
