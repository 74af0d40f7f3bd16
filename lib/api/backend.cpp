#include "api/backend.hpp"

#include <chrono>
#include <cstdio>
#include <ctime>
#include <memory>
#include <utility>

namespace liftd::api {

const std::array<InputFlag, 28> kInputFlags = {{
    {"safety_chain", &Inputs::safety_chain, "safety chain closed"},
    {"doors_closed", &Inputs::doors_closed, "all doors closed"},
    {"doors_locked", &Inputs::doors_locked, "all doors locked"},
    {"door_reversal", &Inputs::door_reversal, "doors reopening (light curtain, door-open button)"},
    {"inspection", &Inputs::inspection, "inspection switch on"},
    {"recall", &Inputs::recall, "recall (test control) switch on"},
    {"button_up", &Inputs::button_up, "inspection/recall up button pressed"},
    {"button_down", &Inputs::button_down, "inspection/recall down button pressed"},
    {"zone_level", &Inputs::zone_level, "car inside the stopping zone of a level"},
    {"zone_door", &Inputs::zone_door, "car inside the door (unlocking) zone"},
    {"relevel_up", &Inputs::relevel_up, "car below the level beyond tolerance"},
    {"relevel_down", &Inputs::relevel_down, "car above the level beyond tolerance"},
    {"end_zone_top", &Inputs::end_zone_top, "car in the top end zone"},
    {"end_zone_bottom", &Inputs::end_zone_bottom, "car in the bottom end zone"},
    {"decel_v4_up", &Inputs::decel_v4_up, "DCP3 deceleration point V4, up"},
    {"decel_v4_down", &Inputs::decel_v4_down, "DCP3 deceleration point V4, down"},
    {"decel_v3_up", &Inputs::decel_v3_up, "DCP3 deceleration point V3, up"},
    {"decel_v3_down", &Inputs::decel_v3_down, "DCP3 deceleration point V3, down"},
    {"decel_v2_up", &Inputs::decel_v2_up, "DCP3 deceleration point V2, up"},
    {"decel_v2_down", &Inputs::decel_v2_down, "DCP3 deceleration point V2, down"},
    {"decel_v1_up", &Inputs::decel_v1_up, "DCP3 deceleration point V1, up"},
    {"decel_v1_down", &Inputs::decel_v1_down, "DCP3 deceleration point V1, down"},
    {"decel_v7_up", &Inputs::decel_v7_up, "DCP3 deceleration point V7, up"},
    {"decel_v7_down", &Inputs::decel_v7_down, "DCP3 deceleration point V7, down"},
    {"decel_v6_up", &Inputs::decel_v6_up, "DCP3 deceleration point V6, up"},
    {"decel_v6_down", &Inputs::decel_v6_down, "DCP3 deceleration point V6, down"},
    {"decel_v5_up", &Inputs::decel_v5_up, "DCP3 deceleration point V5, up"},
    {"decel_v5_down", &Inputs::decel_v5_down, "DCP3 deceleration point V5, down"},
}};

void InputUpdate::apply_to(Inputs& inputs) const {
  for (std::size_t i = 0; i < kInputFlags.size(); ++i) {
    if (flags[i]) inputs.*(kInputFlags[i].member) = *flags[i];
  }
  if (position_mm) inputs.position_mm = position_mm;
}

namespace {
/// The one empty object default-made values share: a snapshot made for each request allocates
/// nothing for it.
const std::shared_ptr<nlohmann::json>& shared_empty_object() {
  static const auto empty = std::make_shared<nlohmann::json>(nlohmann::json::object());
  return empty;
}
}  // namespace

SharedJson::SharedJson() : value_(shared_empty_object()) {}

SharedJson::SharedJson(nlohmann::json value)
    : value_(std::make_shared<nlohmann::json>(std::move(value))) {}

SharedJson& SharedJson::operator=(nlohmann::json value) {
  value_ = std::make_shared<nlohmann::json>(std::move(value));
  return *this;
}

nlohmann::json& SharedJson::edit() {
  if (value_.use_count() != 1) value_ = std::make_shared<nlohmann::json>(*value_);
  return *value_;
}

std::string_view to_string(LinkState state) noexcept {
  switch (state) {
    case LinkState::Down:
      return "down";
    case LinkState::Init:
      return "init";
    case LinkState::Up:
      return "up";
    case LinkState::Fault:
      return "fault";
  }
  return "down";
}

namespace {

template <typename T>
nlohmann::json or_null(const std::optional<T>& value) {
  return value ? nlohmann::json(*value) : nlohmann::json(nullptr);
}

std::string hex_bytes(const std::vector<std::uint8_t>& bytes) {
  std::string out;
  char buf[4];
  for (std::size_t i = 0; i < bytes.size(); ++i) {
    std::snprintf(buf, sizeof buf, i == 0 ? "%02X" : " %02X", bytes[i]);
    out += buf;
  }
  return out;
}

}  // namespace

std::string format_utc(std::chrono::system_clock::time_point time) {
  using namespace std::chrono;
  const auto ms_total = duration_cast<milliseconds>(time.time_since_epoch()).count();
  auto seconds = static_cast<std::time_t>(ms_total / 1000);
  auto ms = ms_total % 1000;
  if (ms < 0) {
    ms += 1000;
    --seconds;
  }
  std::tm tm{};
  gmtime_r(&seconds, &tm);
  char buf[96];
  std::snprintf(buf, sizeof buf, "%04d-%02d-%02dT%02d:%02d:%02d.%03dZ", tm.tm_year + 1900,
                tm.tm_mon + 1, tm.tm_mday, tm.tm_hour, tm.tm_min, tm.tm_sec, static_cast<int>(ms));
  return buf;
}

std::optional<std::int64_t> parse_utc_ms(std::string_view text) {
  // YYYY-MM-DD, then optionally THH:MM:SS, .mmm and Z (a time needs its Z: UTC only).
  const auto digits = [&](std::size_t at, std::size_t n) -> std::optional<int> {
    if (at + n > text.size()) return std::nullopt;
    int value = 0;
    for (std::size_t i = at; i < at + n; ++i) {
      if (text[i] < '0' || text[i] > '9') return std::nullopt;
      value = value * 10 + (text[i] - '0');
    }
    return value;
  };
  const auto year = digits(0, 4);
  const auto month = digits(5, 2);
  const auto day = digits(8, 2);
  if (!year || !month || !day || text.size() < 10 || text[4] != '-' || text[7] != '-') {
    return std::nullopt;
  }
  int hour = 0;
  int minute = 0;
  int second = 0;
  int ms = 0;
  if (text.size() > 10) {
    const auto h = digits(11, 2);
    const auto m = digits(14, 2);
    const auto sec = digits(17, 2);
    if (text[10] != 'T' || !h || !m || !sec || text[13] != ':' || text[16] != ':') {
      return std::nullopt;
    }
    std::size_t at = 19;
    if (at < text.size() && text[at] == '.') {
      const auto frac = digits(at + 1, 3);
      if (!frac) return std::nullopt;
      ms = *frac;
      at += 4;
    }
    if (at + 1 != text.size() || text[at] != 'Z') return std::nullopt;
    hour = *h;
    minute = *m;
    second = *sec;
  }
  if (*month < 1 || *month > 12 || *day < 1 || hour > 23 || minute > 59 || second > 59) {
    return std::nullopt;
  }
  using namespace std::chrono;
  const year_month_day date{std::chrono::year(*year),
                            std::chrono::month(static_cast<unsigned>(*month)),
                            std::chrono::day(static_cast<unsigned>(*day))};
  if (!date.ok()) return std::nullopt;  // 2026-02-30
  const auto at =
      sys_days(date) + hours(hour) + minutes(minute) + seconds(second) + milliseconds(ms);
  return duration_cast<milliseconds>(at.time_since_epoch()).count();
}

// Objects are built key by key: the initializer-list form of nlohmann::json copies every value
// once more and costs about twice the time, and status is the request a dispatcher sends most
// (api-bench).
nlohmann::json to_json(const StatusSnapshot& s) {
  nlohmann::json faults = nlohmann::json::array();
  for (const auto& f : s.faults) {
    nlohmann::json fault = nlohmann::json::object();
    fault["code"] = f.code;
    fault["text"] = f.text;
    fault["since"] = format_utc(f.since);
    faults.push_back(std::move(fault));
  }
  nlohmann::json j = nlohmann::json::object();
  const std::string kind(drive::to_string(s.drive_kind));
  nlohmann::json& drive_object = j["drive"];
  drive_object["kind"] = kind;
  drive_object["state"] = drive::to_string(s.drive_state);
  nlohmann::json& link = j["link"];
  link["state"] = to_string(s.link);
  nlohmann::json& car = j["car"];
  car["position_mm"] = or_null(s.position_mm);
  car["floor"] = or_null(s.floor);
  car["next_possible_stop"] = or_null(s.next_possible_stop);
  car["brake_open"] = s.brake_open;
  car["contactors_on"] = s.contactors_on;
  car["doors"] = or_null(s.doors);
  car["motion"] = s.motion;
  nlohmann::json& travel = j["travel"];
  travel["state"] = s.travel_state;
  travel["direction"] = or_null(s.travel_direction);
  travel["target_floor"] = or_null(s.target_floor);
  travel["calls"] = s.calls;
  travel["last_slip_mm"] = or_null(s.last_travel_slip_mm);
  j["faults"] = std::move(faults);
  nlohmann::json& service = j["service"];
  service["in_service"] = s.out_of_service.empty();
  service["reason"] =
      s.out_of_service.empty() ? nlohmann::json(nullptr) : nlohmann::json(s.out_of_service);
  nlohmann::json& rt = j["rt"];
  rt["realtime"] = s.rt.realtime;
  rt["policy"] = s.rt.policy;
  rt["priority"] = s.rt.priority;
  rt["memory_locked"] = s.rt.memory_locked;
  j[kind] = *s.details;
  if (!s.record->empty()) j["record"] = *s.record;
  return j;
}

nlohmann::json to_json(const StatsSnapshot& s) {
  nlohmann::json out = nlohmann::json::object();
  out["link"]["frames_sent"] = s.frames_sent;
  nlohmann::json& cycle = out["cycle"];
  cycle["cycles"] = s.cycles;
  cycle["dropped_events"] = s.dropped_events;
  cycle["dropped_travel_samples"] = s.dropped_travel_samples;
  out[std::string(drive::to_string(s.drive_kind))] = s.details;
  return out;
}

nlohmann::json to_json(const TraceEntry& e) {
  const auto t_us = std::chrono::duration_cast<std::chrono::microseconds>(e.at).count();
  return {{"t_us", t_us},
          {"tx", hex_bytes(e.tx)},
          {"rx", e.rx ? nlohmann::json(hex_bytes(*e.rx)) : nlohmann::json(nullptr)}};
}

nlohmann::json to_json(const Inputs& inputs) {
  nlohmann::json out = nlohmann::json::object();
  for (const auto& flag : kInputFlags) out[std::string(flag.name)] = inputs.*(flag.member);
  out["position_mm"] = or_null(inputs.position_mm);
  return out;
}

namespace {
void no_travel(Responder& done) {
  done(Result::fail(ErrorCode::NotReady, "this daemon has no travel control for its drive"));
}
}  // namespace

Result Backend::save_trace() {
  return Result::fail(ErrorCode::NotReady, "this daemon keeps no flight recorder");
}

Result Backend::travels(std::size_t) {
  return Result::fail(ErrorCode::NotReady, "this daemon records no travels");
}

namespace {
Result no_record() {
  return Result::fail(ErrorCode::NotOffered, "this daemon keeps no record of the lift");
}
}  // namespace

Result Backend::counters() {
  return no_record();
}
Result Backend::reset_counters(const std::vector<std::string>&, const std::string&) {
  return no_record();
}
Result Backend::history(const HistoryArgs&) {
  return no_record();
}
Result Backend::trend(const TrendArgs&) {
  return no_record();
}
Result Backend::eta(const EtaArgs&) {
  return Result::fail(ErrorCode::NotOffered, "no arrival times: this backend has no travels");
}

void Backend::travel(const TravelArgs&, Responder done) {
  no_travel(done);
}
void Backend::stop(Responder done) {
  no_travel(done);
}
void Backend::relevel(Responder done) {
  no_travel(done);
}
void Backend::learn(Responder done) {
  done(Result::fail(ErrorCode::NotOffered, "this backend has no learning travel"));
}
void Backend::inspection(bool, const std::string&, Responder done) {
  no_travel(done);
}
void Backend::calls(const CallsArgs&, Responder done) {
  no_travel(done);
}

void Backend::sim(const SimRequest&, Responder done) {
  done(Result::fail(ErrorCode::NotReady, "only with liftd --simulate"));
}

}  // namespace liftd::api
