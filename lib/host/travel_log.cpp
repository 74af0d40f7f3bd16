#include "host/travel_log.hpp"

#include <utility>

#include "api/backend.hpp"

namespace liftd::daemon {
namespace {

nlohmann::json bit_list(std::uint32_t bits, const std::vector<std::string>& names) {
  nlohmann::json out = nlohmann::json::array();
  for (std::size_t i = 0; i < names.size() && i < 32; ++i) {
    if (!names[i].empty() && ((bits >> i) & 1U) != 0) out.push_back(names[i]);
  }
  return out;
}

nlohmann::json name_table(const std::vector<std::string>& names) {
  nlohmann::json out = nlohmann::json::array();
  for (const std::string& name : names) {
    if (!name.empty()) out.push_back(name);
  }
  return out;
}

std::int64_t to_ms(MonoTime t) {
  return std::chrono::duration_cast<std::chrono::milliseconds>(t).count();
}

}  // namespace

std::vector<std::int64_t> floor_levels_mm(const config::Config& config) {
  std::vector<std::int64_t> out;
  for (const auto& f : config.floors) out.push_back(f.level_mm);
  return out;
}

std::string travel_end_cause(bool aborted, std::string_view cause_name) {
  return aborted ? std::string(cause_name) : std::string("arrived");
}

TravelLog::TravelLog(TravelBitNames names, std::vector<std::int64_t> floors_mm)
    : names_(std::move(names)), floors_mm_(std::move(floors_mm)) {}

void TravelLog::add(const lift::TravelSample& sample) {
  if (!in_run_ || sample.run != current_run_) {
    if (travels_.size() == kTravelsKept) travels_.pop_front();
    RecordedTravel t;
    t.id = next_id_++;
    t.kind = std::string(sample.kind);
    t.start = sample.at;
    if (pending_end_ && pending_end_->first >= sample.at) {
      t.cause = std::move(pending_end_->second);
    }
    pending_end_.reset();
    travels_.push_back(std::move(t));
    current_run_ = sample.run;
    in_run_ = true;
  }
  RecordedTravel& t = travels_.back();
  if (!sample.kind.empty()) t.kind = std::string(sample.kind);
  if (sample.target_floor >= 0) t.target_floor = static_cast<std::size_t>(sample.target_floor);
  t.end = sample.at;
  append(t, sample);
  if (sample.last) {
    t.ended = true;
    in_run_ = false;
    if (t.cause) complete(t);
  }
}

void TravelLog::append(RecordedTravel& t, const lift::TravelSample& sample) {
  const bool keep = sample.last || t.seen % t.stride == 0;
  ++t.seen;
  if (!keep) return;
  if (t.samples.size() >= kMaxSamples) {
    // Keep every second sample: the curve covers the whole run at half the resolution.
    std::size_t kept = 0;
    for (std::size_t i = 0; i < t.samples.size(); i += 2) t.samples[kept++] = t.samples[i];
    t.samples.resize(kept);
    t.stride *= 2;
  }
  t.samples.push_back(sample);
}

void TravelLog::end(MonoTime at, std::string_view cause) {
  for (auto it = travels_.rbegin(); it != travels_.rend(); ++it) {
    if (it->cause || it->start > at) continue;
    it->cause = std::string(cause);
    if (it->ended) complete(*it);
    return;
  }
  pending_end_ = std::make_pair(at, std::string(cause));
}

nlohmann::json TravelLog::sample_json(const RecordedTravel& t, const lift::TravelSample& s) const {
  nlohmann::json j = nlohmann::json::object();
  j["t_ms"] = to_ms(s.at - t.start);
  j["position_mm"] = s.position_known ? nlohmann::json(s.position_mm) : nlohmann::json(nullptr);
  j["speed_mm_s"] = s.speed_known ? nlohmann::json(s.speed_mm_s) : nlohmann::json(nullptr);
  j["remaining_mm"] = s.remaining_known ? nlohmann::json(s.remaining_mm) : nlohmann::json(nullptr);
  j["command"] = bit_list(s.command_bits, names_.command);
  j["status"] = bit_list(s.status_bits, names_.status);
  return j;
}

nlohmann::json TravelLog::curve_columns(const RecordedTravel& t) const {
  nlohmann::json t_ms = nlohmann::json::array();
  nlohmann::json position = nlohmann::json::array();
  nlohmann::json speed = nlohmann::json::array();
  nlohmann::json remaining = nlohmann::json::array();
  nlohmann::json command = nlohmann::json::array();
  nlohmann::json status = nlohmann::json::array();
  for (const lift::TravelSample& s : t.samples) {
    t_ms.push_back(to_ms(s.at - t.start));
    position.push_back(s.position_known ? nlohmann::json(s.position_mm) : nlohmann::json(nullptr));
    speed.push_back(s.speed_known ? nlohmann::json(s.speed_mm_s) : nlohmann::json(nullptr));
    remaining.push_back(s.remaining_known ? nlohmann::json(s.remaining_mm)
                                          : nlohmann::json(nullptr));
    command.push_back(s.command_bits);
    status.push_back(s.status_bits);
  }
  nlohmann::json out = nlohmann::json::object();
  out["stride"] = t.stride;
  out["command_bits"] = names_.command;
  out["status_bits"] = names_.status;
  out["t_ms"] = std::move(t_ms);
  out["position_mm"] = std::move(position);
  out["speed_mm_s"] = std::move(speed);
  out["remaining_mm"] = std::move(remaining);
  out["command"] = std::move(command);
  out["status"] = std::move(status);
  return out;
}

nlohmann::json TravelLog::to_json(
    std::size_t last,
    const std::function<std::chrono::system_clock::time_point(MonoTime)>& wall) const {
  nlohmann::json list = nlohmann::json::array();
  const std::size_t first = travels_.size() > last ? travels_.size() - last : 0;
  for (std::size_t i = first; i < travels_.size(); ++i) {
    const RecordedTravel& t = travels_[i];
    nlohmann::json j = nlohmann::json::object();
    j["id"] = t.id;
    j["kind"] = t.kind;
    j["start"] = api::format_utc(wall(t.start));
    j["end"] = t.ended ? nlohmann::json(api::format_utc(wall(t.end))) : nlohmann::json(nullptr);
    j["duration_ms"] = to_ms(t.end - t.start);
    j["cause"] = t.cause ? nlohmann::json(*t.cause) : nlohmann::json(nullptr);
    if (t.target_floor) {
      j["target_floor"] = *t.target_floor;
      j["target_mm"] = *t.target_floor < floors_mm_.size()
                           ? nlohmann::json(floors_mm_[*t.target_floor])
                           : nlohmann::json(nullptr);
    } else {
      j["target_floor"] = nullptr;
      j["target_mm"] = nullptr;
    }
    j["stride"] = t.stride;
    j["command_bits"] = name_table(names_.command);
    j["status_bits"] = name_table(names_.status);
    nlohmann::json samples = nlohmann::json::array();
    for (const lift::TravelSample& s : t.samples) samples.push_back(sample_json(t, s));
    j["samples"] = std::move(samples);
    list.push_back(std::move(j));
  }
  return {{"travels", std::move(list)}, {"dropped_samples", dropped_}};
}

}  // namespace liftd::daemon
