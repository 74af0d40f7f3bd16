#include "dcp/sim/profile.hpp"

#include <algorithm>
#include <cmath>

namespace liftd::dcp::sim {

namespace {
// Bisection steps for peak-speed searches: 2^-60 of a few m/s is far below a micrometre.
constexpr int kBisectionSteps = 60;
// Plans treat speeds and times below this as zero (1 um/s, 1 ns).
constexpr double kEpsilon = 1e-9;
}  // namespace

MotionState integrate(const MotionState& start, double jerk_mps3, double dt_s) noexcept {
  const double t = dt_s;
  MotionState out;
  out.s_m = start.s_m + start.v_mps * t + start.a_mps2 * t * t / 2.0 + jerk_mps3 * t * t * t / 6.0;
  out.v_mps = start.v_mps + start.a_mps2 * t + jerk_mps3 * t * t / 2.0;
  out.a_mps2 = start.a_mps2 + jerk_mps3 * t;
  return out;
}

double ramp_distance_m(double from_mps, double to_mps, const RampLimits& limits) noexcept {
  const double dv = std::fabs(to_mps - from_mps);
  const double a = limits.accel_mps2;
  const double j = limits.jerk_mps3;
  if (dv <= 0.0 || a <= 0.0 || j <= 0.0) return 0.0;
  // Full acceleration is reached when dv >= a^2 / j; otherwise a triangular acceleration.
  const double duration_s = dv >= a * a / j ? dv / a + a / j : 2.0 * std::sqrt(dv / j);
  return (from_mps + to_mps) / 2.0 * duration_s;
}

void MotionPlan::start(double t_s, MotionState state) noexcept {
  count_ = 0;
  end_t_s_ = t_s;
  end_state_ = state;
}

void MotionPlan::reset(double t_s, MotionState state) noexcept {
  state.a_mps2 = 0.0;
  start(t_s, state);
  push_hold();
}

void MotionPlan::push(double jerk_mps3, double duration_s) noexcept {
  if (duration_s <= kEpsilon) return;
  if (count_ + 1 >= kMaxSegments) return;  // keep the last slot for the hold segment
  segments_[count_] = Segment{end_t_s_, duration_s, end_state_, jerk_mps3};
  ++count_;
  end_state_ = integrate(end_state_, jerk_mps3, duration_s);
  end_t_s_ += duration_s;
}

void MotionPlan::push_hold() noexcept {
  end_state_.a_mps2 = 0.0;
  if (end_state_.v_mps < kEpsilon) end_state_.v_mps = 0.0;
  segments_[count_] = Segment{end_t_s_, 0.0, end_state_, 0.0};
  ++count_;
}

void MotionPlan::push_ramp(double to_mps, const RampLimits& accel,
                           const RampLimits& decel) noexcept {
  const double ja = accel.jerk_mps3;
  const double jd = decel.jerk_mps3;
  // Settle an acceleration that points the wrong way or would overshoot the target speed.
  if (end_state_.a_mps2 > 0.0 &&
      to_mps < end_state_.v_mps + end_state_.a_mps2 * end_state_.a_mps2 / (2.0 * ja)) {
    push(-ja, end_state_.a_mps2 / ja);
    end_state_.a_mps2 = 0.0;
  } else if (end_state_.a_mps2 < 0.0 &&
             to_mps > end_state_.v_mps - end_state_.a_mps2 * end_state_.a_mps2 / (2.0 * jd)) {
    push(jd, -end_state_.a_mps2 / jd);
    end_state_.a_mps2 = 0.0;
  }
  const bool up = to_mps > end_state_.v_mps;
  const double dv = std::fabs(to_mps - end_state_.v_mps);
  const double a0 = std::fabs(end_state_.a_mps2);
  if (dv <= kEpsilon && a0 <= kEpsilon) {
    end_state_.a_mps2 = 0.0;
    return;
  }
  const double amax = up ? accel.accel_mps2 : decel.accel_mps2;
  const double j = up ? ja : jd;
  const double sign = up ? 1.0 : -1.0;
  const double dv_full = (amax * amax - a0 * a0) / (2.0 * j) + amax * amax / (2.0 * j);
  if (dv >= dv_full) {
    push(sign * j, (amax - a0) / j);
    push(0.0, (dv - dv_full) / amax);
    push(-sign * j, amax / j);
  } else {
    const double apeak = std::sqrt(j * dv + a0 * a0 / 2.0);
    push(sign * j, (apeak - a0) / j);
    push(-sign * j, apeak / j);
  }
  // Snap away rounding noise so chained ramps start from exact values.
  end_state_.v_mps = to_mps;
  end_state_.a_mps2 = 0.0;
}

double MotionPlan::ramp_distance_from_m(const MotionState& state, double to_mps,
                                        const RampLimits& accel, const RampLimits& decel) noexcept {
  MotionPlan scratch;
  scratch.start(0.0, state);
  scratch.push_ramp(to_mps, accel, decel);
  return scratch.end_state_.s_m - state.s_m;
}

namespace {

/// Distance of going to `peak_mps` from `state`, then on to `end_mps`.
double arrival_cost_m(const MotionState& state, double peak_mps, double end_mps,
                      const RampLimits& accel, const RampLimits& decel) noexcept {
  const RampLimits& second = peak_mps >= end_mps ? decel : accel;
  return MotionPlan::ramp_distance_from_m(state, peak_mps, accel, decel) +
         ramp_distance_m(peak_mps, end_mps, second);
}

/// The slowest peak reachable from `state` without first reversing a present acceleration,
/// kept within [end_mps, max(vmax_mps, end_mps)].
double lowest_peak_mps(const MotionState& state, double vmax_mps, double end_mps,
                       const RampLimits& accel, const RampLimits& decel) noexcept {
  double settle_mps = state.v_mps;
  if (state.a_mps2 > 0.0) settle_mps += state.a_mps2 * state.a_mps2 / (2.0 * accel.jerk_mps3);
  if (state.a_mps2 < 0.0) settle_mps -= state.a_mps2 * state.a_mps2 / (2.0 * decel.jerk_mps3);
  return std::max(end_mps, std::min(settle_mps, std::max(vmax_mps, end_mps)));
}

/// `from` moved a share `k` (0..1) of the way to `to`.
double blend(double from, double to, double k) noexcept {
  return from + k * (to - from);
}

}  // namespace

double MotionPlan::min_arrival_m(const MotionState& state, double vmax_mps, double end_mps,
                                 const RampLimits& accel, const RampLimits& decel) noexcept {
  return arrival_cost_m(state, lowest_peak_mps(state, vmax_mps, end_mps, accel, decel), end_mps,
                        accel, decel);
}

bool MotionPlan::plan_arrival(double t_s, MotionState state, double target_s_m, double vmax_mps,
                              double end_mps, const RampLimits& accel,
                              const RampLimits& decel) noexcept {
  const double remaining_m = target_s_m - state.s_m;
  auto cost = [&](double peak_mps) {
    return arrival_cost_m(state, peak_mps, end_mps, accel, decel);
  };
  const double lo_mps = lowest_peak_mps(state, vmax_mps, end_mps, accel, decel);
  vmax_mps = std::max(vmax_mps, end_mps);
  start(t_s, state);
  if (cost(lo_mps) > remaining_m + kEpsilon) {
    push_ramp(end_mps, accel, decel);
    push_hold();
    return false;
  }
  double peak_mps = vmax_mps;
  if (cost(vmax_mps) > remaining_m) {
    double lo = lo_mps;
    double hi = vmax_mps;
    for (int i = 0; i < kBisectionSteps; ++i) {
      const double mid = (lo + hi) / 2.0;
      (cost(mid) <= remaining_m ? lo : hi) = mid;
    }
    peak_mps = lo;
  }
  const double cruise_m = remaining_m - cost(peak_mps);
  push_ramp(peak_mps, accel, decel);
  if (peak_mps > kEpsilon && cruise_m > 0.0) push(0.0, cruise_m / peak_mps);
  push_ramp(end_mps, accel, decel);
  push_hold();
  return true;
}

MotionPlan::FixedArrival MotionPlan::plan_fixed_arrival(double t_s, MotionState state,
                                                        double target_s_m, double vmax_mps,
                                                        double end_mps, const RampLimits& accel,
                                                        const RampLimits& decel,
                                                        const RampLimits& hardest) noexcept {
  // Share k of the way from the normal limits to the hardest: the deceleration ramp, and the
  // jerk that rounds off a present acceleration (the car turns from speeding up to braking).
  auto accel_at = [&](double k) {
    return RampLimits{accel.accel_mps2,
                      std::max(accel.jerk_mps3, blend(accel.jerk_mps3, hardest.jerk_mps3, k))};
  };
  auto decel_at = [&](double k) {
    return RampLimits{std::max(decel.accel_mps2, blend(decel.accel_mps2, hardest.accel_mps2, k)),
                      std::max(decel.jerk_mps3, blend(decel.jerk_mps3, hardest.jerk_mps3, k))};
  };
  const double remaining_m = target_s_m - state.s_m;
  auto fits = [&](double k) {
    return min_arrival_m(state, vmax_mps, end_mps, accel_at(k), decel_at(k)) <=
           remaining_m + kEpsilon;
  };
  FixedArrival result;
  if (!fits(0.0)) {
    if (!fits(1.0)) {
      result.fits = false;
      result.harder = 1.0;
      plan_speed(t_s, state, end_mps, accel_at(1.0), decel_at(1.0));
      result.overshoot_m = std::max(0.0, final_position_m() - target_s_m);
      return result;
    }
    // Both limits grow with k and the distance shrinks with them: bisect the least k that fits.
    double lo = 0.0;
    double hi = 1.0;
    for (int i = 0; i < kBisectionSteps; ++i) {
      const double mid = (lo + hi) / 2.0;
      (fits(mid) ? hi : lo) = mid;
    }
    result.harder = hi;
  }
  plan_arrival(t_s, state, target_s_m, vmax_mps, end_mps, accel_at(result.harder),
               decel_at(result.harder));
  return result;
}

void MotionPlan::plan_speed(double t_s, MotionState state, double speed_mps,
                            const RampLimits& accel, const RampLimits& decel) noexcept {
  start(t_s, state);
  push_ramp(speed_mps, accel, decel);
  push_hold();
}

MotionState MotionPlan::at(double t_s) const noexcept {
  if (count_ == 0) return end_state_;
  std::size_t i = 0;
  while (i + 1 < count_ && segments_[i + 1].t0_s <= t_s) ++i;
  const Segment& seg = segments_[i];
  double dt = std::max(0.0, t_s - seg.t0_s);
  if (i + 1 < count_) dt = std::min(dt, seg.duration_s);
  return integrate(seg.start, seg.jerk_mps3, dt);
}

double MotionPlan::settle_time_s() const noexcept {
  return count_ == 0 ? end_t_s_ : segments_[count_ - 1].t0_s;
}

double MotionPlan::final_speed_mps() const noexcept {
  return count_ == 0 ? end_state_.v_mps : segments_[count_ - 1].start.v_mps;
}

double MotionPlan::final_position_m() const noexcept {
  return count_ == 0 ? end_state_.s_m : segments_[count_ - 1].start.s_m;
}

double peak_speed_mps(double distance_m, double vmax_mps, const RampLimits& accel,
                      const RampLimits& decel) noexcept {
  auto cost = [&](double v) {
    return ramp_distance_m(0.0, v, accel) + ramp_distance_m(v, 0.0, decel);
  };
  if (distance_m <= 0.0) return 0.0;
  if (cost(vmax_mps) <= distance_m) return vmax_mps;
  double lo = 0.0;
  double hi = vmax_mps;
  for (int i = 0; i < kBisectionSteps; ++i) {
    const double mid = (lo + hi) / 2.0;
    (cost(mid) <= distance_m ? lo : hi) = mid;
  }
  return lo;
}

}  // namespace liftd::dcp::sim
