// The lift's record (issue #42): lifetime counters and every travel, kept on the board's storage
// in SQLite (WAL mode) so they survive restarts. Only the daemon's io thread calls it, never the
// real-time thread: every call may write to the storage.
//
// A record that cannot be opened or written turns "off" with a reason and one journal line; from
// then on every call only counts in memory (no I/O), so the lift keeps running whatever the
// storage does.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

namespace liftd::record {

struct Options {
  /// The database file; empty: the record is off, reason "record.path is not set".
  std::string path;
  /// With no path: why the record is not kept, for status and the journal (empty: "record.path
  /// is not set").
  std::string off_reason;
  std::int64_t max_travels = 1'000'000;  ///< travels kept; the oldest go first (0: no limit)
  std::size_t curves_kept = 100;         ///< the newest travels that keep their curve
  /// Changed counters without a travel written at most this often.
  std::int64_t counters_interval_ms = 60'000;
  /// Largest size of the database file in bytes (SQLite's max_page_count, in whole pages); 0: no
  /// bound besides the storage's. A record that reaches it turns off as on a full disk.
  std::int64_t max_bytes = 0;
};

/// One travel as the record keeps it (the host builds it from its travel log).
struct Travel {
  std::int64_t id = 0;  ///< the record's own id (0 before it is written)
  std::int64_t start_unix_ms = 0, end_unix_ms = 0;  ///< wall clock, ms since the Unix epoch (UTC)
  std::int64_t start_mono_ms = 0, end_mono_ms = 0;  ///< CLOCK_MONOTONIC ms
  std::optional<int> from_floor{};                  ///< the floor the car stood at when it started
  std::optional<int> to_floor{};                    ///< the travel's target floor
  std::optional<int> end_floor{};  ///< the floor whose level the car stood at after it
  /// Run kind as the API names it: "travel", "relevel", "inspection", "learn", ... (any short
  /// text).
  std::string kind;
  bool arrived = false;  ///< finished (true) or aborted (false)
  std::string cause;     ///< "arrived" or the abort cause's API name ("link_down", ...)
  std::int64_t duration_ms = 0;
  std::optional<std::int32_t> top_speed_mm_s{};  ///< largest |speed| sampled
  std::optional<std::int64_t> stop_error_mm{};   ///< end position - target level (signed)
  bool relevel_followed = false;  ///< the record sets it itself: a relevel at its floor came next
  std::string curve_json;         ///< the travel's curve as a JSON text (may be empty)
};

/// What the machine inputs showed in one look of the io thread.
struct InputsSample {
  bool doors_locked = false;
  bool safety_chain = false;
  bool inspection = false;
  bool recall = false;
};

struct HistoryQuery {
  std::optional<std::int64_t> from_unix_ms{}, to_unix_ms{};  ///< start time range, [from, to)
  std::optional<int> floor{};                                ///< from_floor or to_floor equals it
  std::optional<std::string> outcome{};                      ///< "arrived" or "aborted"
  std::optional<std::string> cause{};
  std::size_t limit = 100;  ///< newest first; at most kMaxHistoryLimit
  bool curves = false;      ///< include curve (parsed JSON) where kept
};

/// The most travels one history answer holds (a larger limit is cut to it).
inline constexpr std::size_t kMaxHistoryLimit = 10'000;

struct TrendQuery {
  std::optional<std::int64_t> from_unix_ms{}, to_unix_ms{};  ///< every UTC day the range touches
  std::optional<int> floor{};
};

struct ResetResult {
  bool ok = false;
  std::string error;
};

/// One thread only (the daemon's io thread): nothing in it is locked.
class LiftRecord {
 public:
  /// Opens or creates the record at options.path. Never throws. A failure (directory missing or
  /// read-only, disk full, corrupt file, file from a newer schema version, path empty) leaves the
  /// record off with a reason and writes ONE journal line (component "record") saying what was
  /// wrong, where and what to do.
  LiftRecord(Options options, std::int64_t now_mono_ms, std::int64_t now_unix_ms);
  /// Writes changed counters (best effort).
  ~LiftRecord();
  LiftRecord(const LiftRecord&) = delete;
  LiftRecord& operator=(const LiftRecord&) = delete;

  bool on() const noexcept;
  /// {"state":"on"|"off","path":"...","reason":null|"...","travels":N}
  nlohmann::json status_json() const;
  /// A travel ended: counters and the travel row (and its curve) in ONE write transaction.
  void travel(Travel t, std::int64_t now_mono_ms, std::int64_t now_unix_ms);
  void fault_raised(std::string_view code, std::int64_t now_mono_ms);
  void link_lost(std::int64_t now_mono_ms);
  /// A learning travel ended (its legs are travels of their own).
  void learning_travel(std::int64_t now_mono_ms);
  void inputs(const InputsSample& sample, std::int64_t now_mono_ms);
  /// Operating time; writes counters that changed since the last write at most once per
  /// counters_interval_ms (a travel's transaction writes them too).
  void tick(std::int64_t now_mono_ms, std::int64_t now_unix_ms);
  /// {"record":"on"|"off","since":"...","counters":{name:value},"floors":[...],"resets":[...]}
  nlohmann::json counters_json() const;
  /// names: counter names, prefixes ending in ".*" ("faults.*"), "floors" or "all".
  ResetResult reset(const std::vector<std::string>& names, std::string_view who,
                    std::int64_t now_unix_ms);
  /// {"record":"on"|"off","travels":[...],"count":N,"truncated":bool} (+"error" for a bad
  /// query or a failed read)
  nlohmann::json history_json(const HistoryQuery& query) const;
  /// {"record":"on"|"off","days":[...],"pairs":[...]} (+"error" for a failed read)
  nlohmann::json trend_json(const TrendQuery& query) const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace liftd::record
