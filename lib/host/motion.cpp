#include "host/motion.hpp"

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <utility>
#include <vector>

namespace liftd::daemon {

namespace {

// Below this the car is taken as not moving.
constexpr double kMovingMmS = 25.0;
// Speeds are the position's change over this span (whole millimetres: 4 mm/s of resolution),
// not the sampler's 45 ms speed, whose 22 mm/s steps would flicker the phase.
constexpr auto kSpeedSpan = std::chrono::milliseconds(250);
// How far back the speed's trend is judged: long enough to see a ramp (a lift accelerates at
// 0.3..1.5 m/s^2: 75..375 mm/s in this window), short enough to follow it.
constexpr auto kTrendWindow = std::chrono::milliseconds(250);
// A change of speed over the window below this share of the travel's top speed (or 20 mm/s:
// three steps of the speed's resolution; 8 %: a cycle's timing jitter over the speed's span)
// is a steady speed.
constexpr double kSteadyShare = 0.08;
constexpr double kSteadyMmS = 20.0;
// A steady speed below this share of the travel's top speed, after it was faster: the slow
// approach to the level (crawl, the hydraulic card's slow speed, a relevelling's own speed).
constexpr double kLevellingShare = 0.5;

double span_s(MonoTime d) {
  return std::chrono::duration<double>(d).count();
}

/// The speeds (mm/s, unsigned) at each sample with a known position, over kSpeedSpan before it
/// (none until the run is that long).
struct SpeedTrack {
  std::vector<std::pair<MonoTime, double>> speeds;  // (at, speed)
};

SpeedTrack speeds_of(const std::vector<lift::TravelSample>& samples) {
  SpeedTrack track;
  std::size_t back = 0;
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const lift::TravelSample& s = samples[i];
    if (!s.position_known) continue;
    // The newest sample at least kSpeedSpan older than this one.
    while (back + 1 < i &&
           (!samples[back + 1].position_known || s.at - samples[back + 1].at >= kSpeedSpan)) {
      ++back;
    }
    const lift::TravelSample& old = samples[back];
    if (!old.position_known || s.at - old.at < kSpeedSpan) continue;
    const double mm = std::abs(static_cast<double>(s.position_mm - old.position_mm));
    track.speeds.emplace_back(s.at, mm / span_s(s.at - old.at));
  }
  return track;
}

}  // namespace

std::string_view motion_phase(bool travelling, const RecordedTravel* running) {
  if (!travelling) return "standing";
  if (running == nullptr || running->ended) return "starting";
  const SpeedTrack track = speeds_of(running->samples);
  // The phase at each speed in turn: a car that decelerates does not return to its speed
  // unless it accelerates again (a DCP4 target extension), so a rounded ramp reads as one phase.
  std::string_view phase = "starting";
  double top = 0.0;
  std::size_t before = 0;       // the newest speed at least kTrendWindow older than the current one
  std::size_t long_before = 0;  // ... and twice that
  for (std::size_t i = 0; i < track.speeds.size(); ++i) {
    const auto& [at, now] = track.speeds[i];
    top = std::max(top, now);
    while (before + 1 < i && at - track.speeds[before + 1].first >= kTrendWindow) ++before;
    while (long_before + 1 < i && at - track.speeds[long_before + 1].first >= 2 * kTrendWindow) {
      ++long_before;
    }
    if (top < kMovingMmS) continue;  // the run has not moved the car yet
    if (now < kMovingMmS) {
      phase = "levelling";  // at the level, the run's tail (brake, drive off)
      continue;
    }
    if (at - track.speeds[before].first < kTrendWindow) {
      phase = "accelerating";  // moving for less than the window: it has just set off
      continue;
    }
    const double change = now - track.speeds[before].second;
    const double steady = std::max(kSteadyMmS, kSteadyShare * top);
    const bool slowing = phase == "decelerating" || phase == "levelling";
    if (change > steady || phase == "starting") {
      phase = "accelerating";  // a ramp's gentle start is its start all the same
    } else if (change < -steady) {
      // The last metres of a slow approach slow it further: still levelling.
      if (!(phase == "levelling" && now < kLevellingShare * top)) phase = "decelerating";
    } else if (now < kLevellingShare * top) {
      phase = "levelling";
    } else if (!slowing && std::abs(now - track.speeds[long_before].second) <= steady) {
      phase = "at_speed";  // steady over two windows: not the gentle end of a ramp
    }
  }
  return phase;
}

}  // namespace liftd::daemon
