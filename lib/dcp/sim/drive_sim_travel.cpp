// The simulated DCP drive's travel sequencing: starting, the travel kinds of DCP chapters 9 to
// 13, the motion plans on remaining distance, stops and aborts.
#include "dcp/sim/drive_sim.hpp"

#include <algorithm>
#include <cmath>

#include "dcp/sim/drive_sim_detail.hpp"

namespace liftd::dcp::sim {

using namespace detail;

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

}  // namespace liftd::dcp::sim
