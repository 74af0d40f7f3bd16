// Jerk-limited motion profiles for the simulated car: constant-jerk segments planned
// analytically, so a travel on remaining distance lands exactly on its target.
// Pure code: no I/O, no clock, no allocation (fixed segment array).
#pragma once

#include <array>
#include <cstddef>

namespace liftd::dcp::sim {

/// Position, speed and acceleration along the travel direction (m, m/s, m/s^2).
struct MotionState {
  double s_m = 0.0;     ///< distance travelled since the plan's origin
  double v_mps = 0.0;   ///< speed (>= 0 in the travel direction)
  double a_mps2 = 0.0;  ///< acceleration
};

/// Limits of one kind of ramp (acceleration or deceleration).
struct RampLimits {
  double accel_mps2 = 0.5;  ///< largest magnitude of acceleration
  double jerk_mps3 = 1.0;   ///< magnitude of the jerk while the acceleration changes
};

/// One constant-jerk piece of a profile.
struct Segment {
  double t0_s = 0.0;        ///< start time
  double duration_s = 0.0;  ///< length; the last segment of a plan is open-ended
  MotionState start{};      ///< state at t0_s
  double jerk_mps3 = 0.0;   ///< constant jerk over the segment
};

/// State after `dt_s` of constant jerk from `start`.
MotionState integrate(const MotionState& start, double jerk_mps3, double dt_s) noexcept;

/// Distance to change speed from `from_mps` to `to_mps` starting and ending with zero
/// acceleration under `limits` (the classic S-curve: v_avg = (from + to) / 2).
double ramp_distance_m(double from_mps, double to_mps, const RampLimits& limits) noexcept;

/// A motion plan: a list of constant-jerk segments ending in an open-ended constant-speed
/// segment (speed 0 for a plan that stops).
class MotionPlan {
 public:
  /// DCP travels need at most: settle acceleration, 3 ramp pieces, cruise, 3 ramp pieces, hold.
  static constexpr std::size_t kMaxSegments = 12;

  /// Replaces the plan with "hold `state` (its acceleration forced to 0) from t_s on".
  void reset(double t_s, MotionState state) noexcept;
  /// The state at `t_s` (clamped to the plan's start).
  MotionState at(double t_s) const noexcept;
  /// Time at which the open-ended final segment starts.
  double settle_time_s() const noexcept;
  /// Speed of the final (open-ended) segment.
  double final_speed_mps() const noexcept;
  /// Position where the final segment starts.
  double final_position_m() const noexcept;

  /// Plans from `state` at `t_s`: reach at most `vmax_mps`, arrive at `target_s_m` with speed
  /// `end_mps`, then keep `end_mps`. Returns false when the target is too close to reach
  /// without overshoot; the plan then ramps to `end_mps` at once.
  bool plan_arrival(double t_s, MotionState state, double target_s_m, double vmax_mps,
                    double end_mps, const RampLimits& accel, const RampLimits& decel) noexcept;
  /// How a fixed-distance arrival (plan_fixed_arrival) was met.
  struct FixedArrival {
    /// False: even the `hardest` ramp cannot reach `end_mps` by the target; the plan then
    /// ramps to `end_mps` at once on `hardest` and passes the target by `overshoot_m`.
    bool fits = true;
    /// Share of the way from the normal ramps (0) to `hardest` (1) that was needed.
    double harder = 0.0;
    /// Distance by which the end speed is reached past the target (0 when it fits).
    double overshoot_m = 0.0;
  };
  /// Like plan_arrival (free to keep accelerating up to `vmax_mps` or to cruise first), but the
  /// target is a fixed distance that must be met, as the DCP3 deceleration distance SVx is
  /// (DCP 10.1.2): when the normal ramps cannot stop the speed change by the target (e.g. the car
  /// is still accelerating), the deceleration limits and the jerk that rounds off a present
  /// acceleration are raised, as little as needed, towards `hardest`.
  FixedArrival plan_fixed_arrival(double t_s, MotionState state, double target_s_m, double vmax_mps,
                                  double end_mps, const RampLimits& accel, const RampLimits& decel,
                                  const RampLimits& hardest) noexcept;
  /// Plans from `state` at `t_s`: change speed to `speed_mps` and keep it.
  void plan_speed(double t_s, MotionState state, double speed_mps, const RampLimits& accel,
                  const RampLimits& decel) noexcept;

  /// Distance from `state` until the speed is `to_mps` with zero acceleration (settling any
  /// present acceleration first), used to cost candidate plans without keeping them.
  static double ramp_distance_from_m(const MotionState& state, double to_mps,
                                     const RampLimits& accel, const RampLimits& decel) noexcept;

  /// First segment (for tests and diagnostics).
  const Segment* begin() const noexcept { return segments_.data(); }
  /// One past the last segment.
  const Segment* end() const noexcept { return segments_.data() + count_; }

 private:
  /// Empties the plan and sets its end state (acceleration kept).
  void start(double t_s, MotionState state) noexcept;
  /// Appends a segment of `jerk` for `duration` from the current end.
  void push(double jerk_mps3, double duration_s) noexcept;
  /// Appends the pieces that move the end state's speed to `to_mps` with acceleration ending 0.
  void push_ramp(double to_mps, const RampLimits& accel, const RampLimits& decel) noexcept;
  /// Appends the open-ended hold at the end state's speed.
  void push_hold() noexcept;
  /// Shortest distance from `state` to `end_mps` without exceeding `vmax_mps` or reversing a
  /// present acceleration first (what plan_arrival needs at least).
  static double min_arrival_m(const MotionState& state, double vmax_mps, double end_mps,
                              const RampLimits& accel, const RampLimits& decel) noexcept;

  std::array<Segment, kMaxSegments> segments_{};
  std::size_t count_ = 0;
  double end_t_s_ = 0.0;
  MotionState end_state_{};
};

/// Peak speed of a time-optimal travel of `distance_m` from standstill to standstill limited to
/// `vmax_mps` (the speed where acceleration and deceleration distances add up to the distance).
double peak_speed_mps(double distance_m, double vmax_mps, const RampLimits& accel,
                      const RampLimits& decel) noexcept;

}  // namespace liftd::dcp::sim
