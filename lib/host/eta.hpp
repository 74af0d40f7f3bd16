// Arrival times for a group dispatcher (`eta`, docs/api.md "Arrival times"): when could the car
// stand at each floor's level, and how much later would its queued stops be if a floor were
// added. Every drive kind alike, on the io thread only: the times come from the travels the car
// made (the travel log's completed travels) and, for a pair of floors it never travelled
// between, from a motion profile fitted to those travels or, before the first one, configured
// (`eta.*`). Sans-I/O: the caller gives the time and the car's state.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "lift/floors.hpp"

namespace liftd::daemon {

/// The profile used before the car made a travel of its own (`eta.*`).
struct EtaDefaults {
  double speed_mm_s = 1000.0;         ///< eta.speed_mm_s: rated speed
  double acceleration_mm_s2 = 600.0;  ///< eta.acceleration_mm_s2: as the deceleration
  double overhead_s = 2.0;            ///< eta.start_ms: a travel's time beyond its motion
  double stop_s = 1.0;                ///< eta.stop_ms: arrival to the next travel's start
};

/// The car now, as the io thread sees it.
struct EtaCar {
  bool in_service = true;
  std::string reason;                       ///< service.reason while out of service
  std::optional<std::int64_t> position_mm;  ///< none: unknown
  std::optional<int> floor;                 ///< at rest at this floor's level
  bool travelling = false;                  ///< a run is under way
  std::optional<int> target;                ///< the running travel's target floor
  std::optional<int> origin;  ///< the floor the running travel started at (none: between)
  double elapsed_s = 0.0;     ///< since the running travel started
  /// At rest: since the last run ended. A car that just arrived can start again only once its
  /// drive finished the stop (the stop time a queued stop measures).
  double since_arrival_s = 1e9;
  std::vector<int> calls;  ///< the calls queue, in order (the target not included)
};

/// One measured travel between two floors (a finished travel of the lift's own kind).
struct MeasuredTravel {
  int from = 0;
  int to = 0;
  double duration_s = 0.0;  ///< first sample of the run to its end (the car at the level)
  double top_speed_mm_s = 0.0;
  /// Start of motion to 90 % of the top speed (none: the curve did not tell).
  std::optional<double> acceleration_time_s;
};

/// The speed a travel ran at, from its speed samples (mm/s, any sign, 0 for none): the median of
/// the samples within a tenth of its fastest tenth, i.e. of the run at speed. The samples are
/// the position's change over a few cycles, noisy by a few per cent, so the fastest ones
/// overstate the speed (on the simulated hydraulic unit by 2.4 %: 512 mm/s for its 500, which
/// put a 9 m travel never made 0.4 s early); the acceleration and the slow approach are below
/// the band. 0 without samples.
double cruise_speed_mm_s(std::vector<double> speeds);

/// The travel times the car learned, per ordered pair of floors, and the profile fitted to
/// them for the pairs it never travelled between.
class TravelTimes {
 public:
  /// Measurements kept per pair and for the profile's fit: the newest ones, their median used.
  static constexpr std::size_t kKept = 9;

  TravelTimes(std::vector<std::int64_t> levels_mm, EtaDefaults defaults);

  /// A finished travel between two floors. Ignored if a floor is out of range or they are one.
  void travel(const MeasuredTravel& t);
  /// The time a car stood at a queued stop: its arrival to the next travel's start.
  void stop(double seconds);
  /// The time from a request to travel, the car at rest, to its run's start.
  void start(double seconds);

  /// Seconds from a travel's start at `from` to the car at `to`'s level; `learned` tells whether
  /// this pair was measured.
  double leg_s(int from, int to, bool* learned = nullptr) const;
  /// Seconds the car stands at a queued stop before it travels on: measured, else the
  /// configured time or the start time, whichever is longer.
  double stop_s() const;
  /// Seconds from a request to travel, the car at rest, to the run's start (0 until measured).
  double start_s() const;
  /// The profile's time for a travel of `distance_mm` (up when `up`), overhead included.
  double profile_s(double distance_mm, bool up = true) const;
  /// Whether the pair `from`, `to` was measured.
  bool learned(int from, int to) const;

  std::size_t floor_count() const noexcept { return floors_.size(); }
  /// The level of `floor`; throws std::out_of_range for a floor the table does not have.
  std::int64_t level_mm(int floor) const;
  /// The floor nearest `position_mm` (ties: the lower), 0 without floors.
  int nearest_floor(std::int64_t position_mm) const {
    return static_cast<int>(floors_.nearest(position_mm).value_or(0));
  }
  /// `basis` of the answer: the profile in use and how many measurements it rests on.
  nlohmann::json basis_json() const;

 private:
  /// The newest kKept values and their median.
  struct Window {
    std::array<double, kKept> values{};
    std::size_t count = 0;  ///< values taken in all
    void add(double v) noexcept { values[count++ % kKept] = v; }
    bool empty() const noexcept { return count == 0; }
    double median() const;
  };
  /// The newest kKept travels of one direction, their distance and duration: the overhead is
  /// fitted to them with the profile's speed and acceleration as they stand when asked, not as
  /// they stood when each travel came (the first travels meet the configured profile).
  struct Runs {
    std::array<double, kKept> distance_mm{};
    std::array<double, kKept> duration_s{};
    std::size_t count = 0;  ///< travels taken in all
    void add(double distance, double duration) noexcept {
      distance_mm[count % kKept] = distance;
      duration_s[count++ % kKept] = duration;
    }
    bool empty() const noexcept { return count == 0; }
  };
  /// Each direction's profile (index 1: up): a hydraulic car goes down on its valve, at a speed
  /// of its own. A direction not measured yet takes the other's, then the configured one.
  const Window& of(const std::array<Window, 2>& w, bool up) const {
    return w[up ? 1 : 0].empty() ? w[up ? 0 : 1] : w[up ? 1 : 0];
  }
  double speed_mm_s(bool up) const;
  double acceleration_mm_s2(bool up) const;
  double overhead_s(bool up) const;
  static double motion_s(double distance_mm, double speed, double acceleration);

  lift::FloorTable floors_;  ///< empty when the levels given were not a valid table
  EtaDefaults defaults_;
  std::vector<Window> pairs_;  ///< [from * floors + to]
  std::array<Window, 2> top_speed_;
  std::array<Window, 2> acceleration_;
  std::array<Runs, 2> runs_;
  Window stop_;
  Window start_;
};

/// Whether a travel of this kind (its API name) is one a call runs from floor to floor: not a
/// relevelling, an inspection or recall run, a learning travel or DCP3's crawl.
bool eta_floor_to_floor(std::string_view kind) noexcept;

/// Feeds `times` the floor-to-floor travels of the lift's record (a `history` answer's
/// `travels`, newest first, as lift::LiftRecord gives them) so that arrival times after a restart
/// rest on what the car measured before it: each arrived travel of a floor-to-floor kind between
/// two different floors that ended at its target within `level_window_mm`. The record keeps the
/// highest speed sampled, not the curve: the profile's acceleration waits for new travels.
/// Returns how many travels it took.
std::size_t preload_travel_times(TravelTimes& times, const nlohmann::json& travels,
                                 std::int64_t level_window_mm);

/// `eta`'s question: the car's state, and optionally a floor to add at queue position
/// `position` (0 = before the first queued call; none: at the end).
struct EtaQuestion {
  std::optional<int> floor;
  std::optional<std::size_t> position;
};

/// The answer as `eta`'s result (docs/api.md "Arrival times").
nlohmann::json estimate_eta(const TravelTimes& times, const EtaCar& car,
                            const EtaQuestion& question);

}  // namespace liftd::daemon
