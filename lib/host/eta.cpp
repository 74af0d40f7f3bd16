#include "host/eta.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <stdexcept>
#include <utility>

namespace liftd::daemon {
namespace {

/// Seconds as `eta` gives them: whole milliseconds (the io thread's times are no finer).
double seconds(double s) {
  return std::round(std::max(0.0, s) * 1000.0) / 1000.0;
}

}  // namespace

bool eta_floor_to_floor(std::string_view kind) noexcept {
  for (std::string_view other :
       {"relevel", "relevel_distance", "inspection", "recall", "learn", "crawl", "fast_start"}) {
    if (kind == other) return false;
  }
  return true;
}

double TravelTimes::Window::median() const {
  const std::size_t n = std::min(count, kKept);
  std::array<double, kKept> sorted = values;
  std::sort(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(n));
  return n % 2 == 1 ? sorted[n / 2] : (sorted[n / 2 - 1] + sorted[n / 2]) / 2.0;
}

double cruise_speed_mm_s(std::vector<double> speeds) {
  std::erase(speeds, 0.0);
  for (double& v : speeds) v = std::abs(v);
  if (speeds.empty()) return 0.0;
  const auto tenth = speeds.begin() + static_cast<std::ptrdiff_t>(speeds.size() / 10);
  std::nth_element(speeds.begin(), tenth, speeds.end(), std::greater<>());
  const double band = 0.9 * *tenth;
  std::erase_if(speeds, [band](double v) { return v < band; });
  const auto middle = speeds.begin() + static_cast<std::ptrdiff_t>(speeds.size() / 2);
  std::nth_element(speeds.begin(), middle, speeds.end());
  return *middle;
}

TravelTimes::TravelTimes(std::vector<std::int64_t> levels_mm, EtaDefaults defaults)
    : defaults_(defaults) {
  (void)floors_.assign(levels_mm);  // the configuration's floors: ascending, at most kMaxFloors
  pairs_.resize(floors_.size() * floors_.size());
}

std::int64_t TravelTimes::level_mm(int floor) const {
  if (floor < 0 || static_cast<std::size_t>(floor) >= floors_.size()) {
    throw std::out_of_range("eta: floor " + std::to_string(floor) + " is not in the table");
  }
  return floors_.level_mm(static_cast<std::size_t>(floor));
}

void TravelTimes::travel(const MeasuredTravel& t) {
  const auto n = static_cast<int>(floors_.size());
  if (t.from < 0 || t.to < 0 || t.from >= n || t.to >= n || t.from == t.to) return;
  if (!(t.duration_s > 0.0)) return;
  pairs_[static_cast<std::size_t>(t.from * n + t.to)].add(t.duration_s);
  // The profile for the pairs never travelled: the rated speed is the fastest a travel reached
  // (a short one may never reach it, so its top speed says nothing of the rated one); the
  // acceleration from a travel that did; the overhead (start, levelling, stop) as what is left
  // of each travel's time beyond the motion the profile gives it.
  const bool up = level_mm(t.to) > level_mm(t.from);
  const std::size_t d = up ? 1 : 0;
  const double distance = std::abs(static_cast<double>(level_mm(t.to) - level_mm(t.from)));
  if (t.top_speed_mm_s > 0.0 &&
      (top_speed_[d].empty() || t.top_speed_mm_s >= 0.9 * speed_mm_s(up))) {
    top_speed_[d].add(t.top_speed_mm_s);
    if (t.acceleration_time_s && *t.acceleration_time_s > 0.0) {
      acceleration_[d].add(0.9 * t.top_speed_mm_s / *t.acceleration_time_s);
    }
  }
  runs_[d].add(distance, t.duration_s);
}

void TravelTimes::stop(double s) {
  if (s >= 0.0) stop_.add(s);
}

void TravelTimes::start(double s) {
  if (s >= 0.0) start_.add(s);
}

double TravelTimes::start_s() const {
  return start_.empty() ? 0.0 : start_.median();
}

double TravelTimes::speed_mm_s(bool up) const {
  const Window& w = of(top_speed_, up);
  return w.empty() ? defaults_.speed_mm_s : w.median();
}
double TravelTimes::acceleration_mm_s2(bool up) const {
  const Window& w = of(acceleration_, up);
  return w.empty() ? defaults_.acceleration_mm_s2 : w.median();
}
double TravelTimes::overhead_s(bool up) const {
  // This direction's travels, else the other's (as of()), each fitted with that direction's
  // profile: what each took beyond its motion, the median of it.
  const bool way = runs_[up ? 1 : 0].empty() ? !up : up;
  const Runs& r = runs_[way ? 1 : 0];
  if (r.empty()) return defaults_.overhead_s;
  Window beyond;
  for (std::size_t i = 0; i < std::min(r.count, kKept); ++i) {
    beyond.add(r.duration_s[i] -
               motion_s(r.distance_mm[i], speed_mm_s(way), acceleration_mm_s2(way)));
  }
  return std::max(0.0, beyond.median());
}
double TravelTimes::stop_s() const {
  if (!stop_.empty()) return stop_.median();
  // Not measured yet: the next travel is asked for at the arrival at the earliest, so the car
  // stands at least as long as a request takes to its run's start, once that was measured (on
  // the simulated hydraulic car 1.5 s against the configured 1.0: each queued leg came 0.5 s
  // early until a queued stop was measured).
  return std::max(defaults_.stop_s, start_s());
}

double TravelTimes::motion_s(double distance_mm, double speed, double acceleration) {
  if (distance_mm <= 0.0 || speed <= 0.0 || acceleration <= 0.0) return 0.0;
  // A trapezoid: accelerate to the speed, travel, decelerate alike; a travel too short to reach
  // the speed is a triangle.
  const double ramp_mm = speed * speed / acceleration;  // both ramps together
  if (distance_mm >= ramp_mm) return distance_mm / speed + speed / acceleration;
  return 2.0 * std::sqrt(distance_mm / acceleration);
}

double TravelTimes::profile_s(double distance_mm, bool up) const {
  return overhead_s(up) + motion_s(distance_mm, speed_mm_s(up), acceleration_mm_s2(up));
}

bool TravelTimes::learned(int from, int to) const {
  const auto n = static_cast<int>(floors_.size());
  if (from < 0 || to < 0 || from >= n || to >= n) return false;
  return !pairs_[static_cast<std::size_t>(from * n + to)].empty();
}

double TravelTimes::leg_s(int from, int to, bool* learned_out) const {
  if (from == to) {
    if (learned_out) *learned_out = true;
    return 0.0;
  }
  const bool known = learned(from, to);
  if (learned_out) *learned_out = known;
  if (known) {
    return pairs_[static_cast<std::size_t>(from * static_cast<int>(floors_.size()) + to)].median();
  }
  return profile_s(std::abs(static_cast<double>(level_mm(to) - level_mm(from))),
                   level_mm(to) > level_mm(from));
}

nlohmann::json TravelTimes::basis_json() const {
  std::size_t pairs = 0;
  for (const Window& w : pairs_) pairs += w.empty() ? 0U : 1U;
  const auto direction = [this](bool up) {
    return nlohmann::json{{"speed_mm_s", std::round(speed_mm_s(up))},
                          {"acceleration_mm_s2", std::round(acceleration_mm_s2(up))},
                          {"overhead_s", seconds(overhead_s(up))},
                          {"travels_measured", runs_[up ? 1 : 0].count}};
  };
  return {{"up", direction(true)},       {"down", direction(false)},
          {"stop_s", seconds(stop_s())}, {"start_s", seconds(start_s())},
          {"pairs_learned", pairs},      {"stops_measured", stop_.count}};
}

namespace {

struct Stop {
  int floor = 0;
  double s = 0.0;
  bool learned = true;
};

/// Where the car starts its plan from: the floor it travels to now (with the time it arrives)
/// or the floor it stands at.
struct Start {
  int floor = 0;
  double s = 0.0;
  bool learned = true;
  bool arrives = false;  ///< a running travel ends at `floor`: the car stops there first
};

Start start_of(const TravelTimes& times, const EtaCar& car) {
  Start s;
  if (car.travelling && car.target) {
    s.floor = *car.target;
    s.arrives = true;
    double whole = 0.0;
    if (car.origin) {
      whole = times.leg_s(*car.origin, *car.target, &s.learned);
    } else {
      // Started between floors (a relevelling, a travel after a stop between floors): the
      // profile from where it was then is unknown; take the distance left now.
      s.learned = false;
      const std::int64_t from = car.position_mm.value_or(times.level_mm(*car.target));
      whole = times.profile_s(std::abs(static_cast<double>(times.level_mm(*car.target) - from)),
                              times.level_mm(*car.target) > from) +
              car.elapsed_s;
    }
    s.s = std::max(0.0, whole - car.elapsed_s);
    return s;
  }
  // From rest: the request's way to the run's start, or what is left of the stop the car makes
  // after an arrival, whichever is longer.
  s.s = std::max(times.start_s(), times.stop_s() - car.since_arrival_s);
  if (car.floor) {
    s.floor = *car.floor;
  } else if (car.position_mm) {
    s.floor = times.nearest_floor(*car.position_mm);
    s.learned = false;
  }
  return s;
}

/// The time of each stop of `plan` (floors in order) after `start`.
std::vector<Stop> schedule(const TravelTimes& times, const Start& start,
                           const std::vector<int>& plan) {
  std::vector<Stop> out;
  int at = start.floor;
  double t = start.s;
  bool learned = start.learned;
  bool stopped = start.arrives;  // the car stands at `at` before it travels on
  for (int floor : plan) {
    if (floor == at && !stopped) {
      out.push_back({floor, 0.0, learned});  // the car stands there now
      continue;
    }
    bool leg_learned = true;
    if (stopped) t += times.stop_s();
    t += times.leg_s(at, floor, &leg_learned);
    learned = learned && leg_learned;
    out.push_back({floor, t, learned});
    at = floor;
    stopped = true;
  }
  return out;
}

nlohmann::json stop_json(const Stop& s) {
  return {{"floor", s.floor}, {"s", seconds(s.s)}, {"learned", s.learned}};
}

}  // namespace

nlohmann::json estimate_eta(const TravelTimes& times, const EtaCar& car,
                            const EtaQuestion& question) {
  nlohmann::json out = nlohmann::json::object();
  out["in_service"] = car.in_service;
  out["reason"] = car.in_service ? nlohmann::json(nullptr) : nlohmann::json(car.reason);
  out["basis"] = times.basis_json();
  if (!car.in_service || times.floor_count() == 0 || (!car.floor && !car.position_mm)) {
    // A car out of service reaches no floor a dispatcher could count on.
    out["stops"] = nlohmann::json::array();
    out["floors"] = nullptr;
    if (question.floor) out["with"] = nullptr;
    return out;
  }
  const Start start = start_of(times, car);
  const std::vector<Stop> stops = schedule(times, start, car.calls);

  nlohmann::json stops_json = nlohmann::json::array();
  if (start.arrives) stops_json.push_back(stop_json({start.floor, start.s, start.learned}));
  for (const Stop& s : stops) stops_json.push_back(stop_json(s));
  out["stops"] = std::move(stops_json);

  // Every floor: its first stop in the plan, else one more stop at the plan's end.
  const Start end =
      stops.empty() ? start : Start{stops.back().floor, stops.back().s, stops.back().learned, true};
  nlohmann::json floors = nlohmann::json::array();
  for (int f = 0; f < static_cast<int>(times.floor_count()); ++f) {
    std::optional<Stop> first;
    if (start.arrives && start.floor == f) first = Stop{f, start.s, start.learned};
    for (const Stop& s : stops) {
      if (!first && s.floor == f) first = s;
    }
    if (!first) first = schedule(times, end, {f}).front();
    floors.push_back(stop_json(*first));
  }
  out["floors"] = std::move(floors);

  if (question.floor && !question.position) {
    // `calls add` of a floor already planned adds nothing (docs/api.md `calls`): its stop as it
    // is, and no delay.
    std::optional<Stop> planned;
    if (start.arrives && start.floor == *question.floor) {
      planned = Stop{start.floor, start.s, start.learned};
    }
    for (const Stop& stop : stops) {
      if (!planned && stop.floor == *question.floor) planned = stop;
    }
    if (planned) {
      nlohmann::json delays = nlohmann::json::array();
      for (const Stop& stop : stops) delays.push_back({{"floor", stop.floor}, {"s", 0.0}});
      out["with"] = {
          {"floor", *question.floor}, {"position", nullptr},         {"queued", true},
          {"s", seconds(planned->s)}, {"learned", planned->learned}, {"delays", std::move(delays)}};
      return out;
    }
  }
  if (question.floor) {
    const std::size_t at = std::min(question.position.value_or(car.calls.size()), car.calls.size());
    std::vector<int> plan = car.calls;
    plan.insert(plan.begin() + static_cast<std::ptrdiff_t>(at), *question.floor);
    const std::vector<Stop> with = schedule(times, start, plan);
    nlohmann::json delays = nlohmann::json::array();
    for (std::size_t i = 0; i < stops.size(); ++i) {
      const Stop& later = with[i < at ? i : i + 1];
      delays.push_back({{"floor", stops[i].floor}, {"s", seconds(later.s - stops[i].s)}});
    }
    out["with"] = {{"floor", *question.floor},
                   {"position", at},
                   {"queued", false},
                   {"s", seconds(with[at].s)},
                   {"learned", with[at].learned},
                   {"delays", std::move(delays)}};
  }
  return out;
}

std::size_t preload_travel_times(TravelTimes& times, const nlohmann::json& travels,
                                 std::int64_t level_window_mm) {
  if (!travels.is_array()) return 0;
  std::size_t taken = 0;
  for (auto it = travels.rbegin(); it != travels.rend(); ++it) {  // oldest first
    const nlohmann::json& t = *it;
    const auto number = [&](const char* key) -> std::optional<std::int64_t> {
      const auto f = t.find(key);
      if (f == t.end() || !f->is_number_integer()) return std::nullopt;
      return f->get<std::int64_t>();
    };
    const auto from = number("from_floor");
    const auto to = number("to_floor");
    const auto end = number("end_floor");
    const auto duration_ms = number("duration_ms");
    const auto error_mm = number("stop_error_mm");
    if (t.value("outcome", "") != "arrived" || !eta_floor_to_floor(t.value("kind", "")) || !from ||
        !to || !end || *from == *to || *end != *to || !duration_ms || !error_mm ||
        std::llabs(*error_mm) > level_window_mm) {
      continue;
    }
    MeasuredTravel m;
    m.from = static_cast<int>(*from);
    m.to = static_cast<int>(*to);
    m.duration_s = static_cast<double>(*duration_ms) / 1000.0;
    m.top_speed_mm_s = static_cast<double>(number("top_speed_mm_s").value_or(0));
    times.travel(m);
    ++taken;
  }
  return taken;
}

}  // namespace liftd::daemon
