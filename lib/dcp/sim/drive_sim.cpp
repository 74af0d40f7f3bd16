// The simulated DCP drive: its events and names, its time and car, the frame exchange (DCP 4,
// 6 and 7) and its faults. The travel sequencing is in drive_sim_travel.cpp, the
// communication channel (DCP 5) in drive_sim_channel.cpp.
#include "dcp/sim/drive_sim.hpp"

#include <algorithm>
#include <cmath>
#include <optional>

#include "dcp/sim/drive_sim_detail.hpp"

namespace liftd::dcp::sim {

using namespace detail;

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

}  // namespace liftd::dcp::sim
