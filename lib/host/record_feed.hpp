// The lift's record (lib/record) as every drive kind's io thread feeds it: the travels the travel
// log completes, the faults raised, the machine inputs as the cycle sees them, and the passing of
// time; and the API's record commands answered from it. Never on the real-time thread: the record
// writes to the board's storage.
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "api/backend.hpp"
#include "common/mono_time.hpp"
#include "config/config.hpp"
#include "host/travel_log.hpp"
#include "lift/faults.hpp"
#include "lift/inputs.hpp"
#include "record/lift_record.hpp"

namespace liftd::daemon {

/// Where the record is kept: record.path, else record.db in the unit's StateDirectory
/// ($STATE_DIRECTORY), with --simulate in the runtime directory, else /var/lib/liftd/record.db.
/// record.enabled false: no path (the record is off).
record::Options record_options(const config::Config& config, bool simulated);

/// The floor whose level `position_mm` is within `window_mm` of, if any.
std::optional<int> floor_near(const std::vector<std::int64_t>& levels_mm, std::int64_t position_mm,
                              std::int64_t window_mm);

/// One travel of the travel log as the record keeps it (`curve`: its curve, or null).
record::Travel record_travel(const RecordedTravel& t, const std::vector<std::int64_t>& levels_mm,
                             std::int64_t window_mm, std::int64_t start_unix_ms,
                             std::int64_t end_unix_ms, const nlohmann::json& curve);

class RecordFeed {
 public:
  RecordFeed(const config::Config& config, bool simulated, MonoTime now);

  /// A travel the travel log completed (TravelLog's completion listener).
  void travel(const record::Travel& travel, MonoTime now);
  /// A fault raised (a link fault also counts as a link loss).
  void fault_raised(lift::FaultCode code, MonoTime now);
  /// A learning travel ran through the shaft (its legs are travels of their own).
  void learning_travel(MonoTime now);
  /// The machine inputs the cycle sees now (nullopt: none yet).
  void inputs(const std::optional<lift::Inputs>& inputs, MonoTime now);
  /// Every poll of the io thread: operating time, and the counters written once a minute.
  void tick(MonoTime now);
  /// Whether the record keeps the travels' curves (record.curves_kept above 0).
  bool wants_curves() const noexcept { return curves_kept_ > 0; }

  /// status.record: {"state": "on"|"off", "path", "reason"}.
  const api::SharedJson& status() const noexcept { return status_; }
  api::Result counters() const;
  api::Result reset(const std::vector<std::string>& names, const std::string& who);
  api::Result history(const api::HistoryArgs& args) const;
  api::Result trend(const api::TrendArgs& args) const;

 private:
  void refresh_status();

  std::unique_ptr<record::LiftRecord> record_;
  std::size_t curves_kept_;
  api::SharedJson status_;
  bool was_on_ = false;
};

}  // namespace liftd::daemon
