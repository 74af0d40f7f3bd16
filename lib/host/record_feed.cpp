#include "host/record_feed.hpp"

#include <algorithm>
#include <cstdlib>
#include <filesystem>

#include "host/lift_common.hpp"

namespace liftd::daemon {
namespace {

std::int64_t ms_of(MonoTime t) {
  return std::chrono::duration_cast<std::chrono::milliseconds>(t).count();
}

std::int64_t unix_ms_now() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

/// The file's name in a directory the record is kept in.
constexpr const char* kRecordFile = "record.db";
/// Where the Debian package's unit keeps it (StateDirectory=liftd) when liftd runs elsewhere.
constexpr const char* kDefaultRecordPath = "/var/lib/liftd/record.db";

}  // namespace

record::Options record_options(const config::Config& config, bool simulated) {
  record::Options options;
  options.max_travels = config.record.max_travels;
  options.curves_kept = static_cast<std::size_t>(config.record.curves_kept);
  if (!config.record.enabled) {
    options.off_reason = "record.enabled is false";
    return options;
  }
  if (!config.record.path.empty()) {
    options.path = config.record.path;
  } else if (const char* dir = std::getenv("STATE_DIRECTORY"); dir != nullptr && *dir != '\0') {
    // systemd may list several directories separated by ':'; the unit names one.
    const std::string first = std::string(dir).substr(0, std::string(dir).find(':'));
    options.path = (std::filesystem::path(first) / kRecordFile).string();
  } else if (simulated) {
    options.path = (std::filesystem::path(default_runtime_dir(config)) / kRecordFile).string();
  } else {
    options.path = kDefaultRecordPath;
  }
  return options;
}

std::optional<int> floor_near(const std::vector<std::int64_t>& levels_mm, std::int64_t position_mm,
                              std::int64_t window_mm) {
  std::optional<int> best;
  std::int64_t best_off = 0;
  for (std::size_t i = 0; i < levels_mm.size(); ++i) {
    const std::int64_t off = std::llabs(position_mm - levels_mm[i]);
    if (off <= window_mm && (!best || off < best_off)) {
      best = static_cast<int>(i);
      best_off = off;
    }
  }
  return best;
}

record::Travel record_travel(const RecordedTravel& t, const std::vector<std::int64_t>& levels_mm,
                             std::int64_t window_mm, std::int64_t start_unix_ms,
                             std::int64_t end_unix_ms, const nlohmann::json& curve) {
  record::Travel out;
  out.start_unix_ms = start_unix_ms;
  out.end_unix_ms = end_unix_ms;
  out.start_mono_ms = ms_of(t.start);
  out.end_mono_ms = ms_of(t.end);
  out.kind = t.kind;
  out.cause = t.cause.value_or("unknown");
  out.arrived = out.cause == "arrived";
  out.duration_ms = ms_of(t.end - t.start);
  if (t.target_floor) out.to_floor = static_cast<int>(*t.target_floor);
  const auto known = [](const lift::TravelSample& s) { return s.position_known; };
  const auto first = std::find_if(t.samples.begin(), t.samples.end(), known);
  const auto last = std::find_if(t.samples.rbegin(), t.samples.rend(), known);
  if (first != t.samples.end())
    out.from_floor = floor_near(levels_mm, first->position_mm, window_mm);
  if (last != t.samples.rend()) {
    out.end_floor = floor_near(levels_mm, last->position_mm, window_mm);
    if (out.arrived && out.to_floor && static_cast<std::size_t>(*out.to_floor) < levels_mm.size()) {
      out.stop_error_mm = last->position_mm - levels_mm[static_cast<std::size_t>(*out.to_floor)];
    }
  }
  for (const lift::TravelSample& s : t.samples) {
    if (!s.speed_known) continue;
    const std::int32_t speed = s.speed_mm_s < 0 ? -s.speed_mm_s : s.speed_mm_s;
    out.top_speed_mm_s = std::max(out.top_speed_mm_s.value_or(0), speed);
  }
  if (!curve.is_null()) out.curve_json = curve.dump();
  return out;
}

RecordFeed::RecordFeed(const config::Config& config, bool simulated, MonoTime now)
    : curves_kept_(static_cast<std::size_t>(config.record.curves_kept)) {
  record_ = std::make_unique<record::LiftRecord>(record_options(config, simulated), ms_of(now),
                                                 unix_ms_now());
  refresh_status();
}

void RecordFeed::refresh_status() {
  status_ = record_->status_json();
  was_on_ = record_->on();
}

void RecordFeed::travel(const record::Travel& travel, MonoTime now) {
  record_->travel(travel, ms_of(now), unix_ms_now());
  refresh_status();  // the travel count, or the record gone off
}

void RecordFeed::fault_raised(lift::FaultCode code, MonoTime now) {
  record_->fault_raised(lift::fault_code_name(code), ms_of(now));
  if (code == lift::FaultCode::LinkFault) record_->link_lost(ms_of(now));
}

void RecordFeed::learning_travel(MonoTime now) {
  record_->learning_travel(ms_of(now));
}

void RecordFeed::inputs(const std::optional<lift::Inputs>& inputs, MonoTime now) {
  if (!inputs || !inputs->valid) return;
  record::InputsSample sample;
  sample.doors_locked = inputs->doors_locked;
  sample.safety_chain = inputs->safety_chain_closed;
  sample.inspection = inputs->inspection;
  sample.recall = inputs->recall;
  record_->inputs(sample, ms_of(now));
}

void RecordFeed::tick(MonoTime now) {
  record_->tick(ms_of(now), unix_ms_now());
  if (record_->on() != was_on_) refresh_status();
}

api::Result RecordFeed::counters() const {
  return api::Result::ok(record_->counters_json());
}

api::Result RecordFeed::reset(const std::vector<std::string>& names, const std::string& who) {
  const record::ResetResult r = record_->reset(names, who, unix_ms_now());
  // A record that is off refuses every reset (it could not be kept): the lift's state, not the
  // request, is what is wrong then.
  if (!r.ok && !record_->on()) return api::Result::fail(api::ErrorCode::NotReady, r.error);
  if (!r.ok) return api::Result::fail(api::ErrorCode::BadRequest, r.error, "names");
  return api::Result::ok(record_->counters_json());
}

api::Result RecordFeed::history(const api::HistoryArgs& args) const {
  record::HistoryQuery q;
  q.from_unix_ms = args.from_unix_ms;
  q.to_unix_ms = args.to_unix_ms;
  q.floor = args.floor;
  q.outcome = args.outcome;
  q.cause = args.cause;
  q.limit = args.limit;
  q.curves = args.curves;
  return api::Result::ok(record_->history_json(q));
}

api::Result RecordFeed::trend(const api::TrendArgs& args) const {
  record::TrendQuery q;
  q.from_unix_ms = args.from_unix_ms;
  q.to_unix_ms = args.to_unix_ms;
  q.floor = args.floor;
  return api::Result::ok(record_->trend_json(q));
}

}  // namespace liftd::daemon
