// The counting rules of the lift's record (issue #42), with no I/O: which event moves which
// lifetime counter, the door and safety-chain edges, the times the switches were on, and the
// stopping error per floor. The store (store.hpp) writes what changed; the façade
// (lift_record.hpp) ties the two together.
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "record/lift_record.hpp"

namespace liftd::record {

/// The stopping errors at one floor, kept as a fixed histogram of |error| so the 95th percentile
/// survives restarts without keeping every value. The errors are whole millimetres, so buckets
/// of 1 mm hold each value exactly: the percentile is exact below kHistogramMm, and a stop at or
/// beyond it goes to the overflow bucket (there the percentile answers the worst error).
class StopErrorStats {
 public:
  static constexpr std::int64_t kHistogramMm = 100;
  static constexpr std::size_t kBuckets = static_cast<std::size_t>(kHistogramMm) + 1;
  using Buckets = std::array<std::int64_t, kBuckets>;

  void add(std::int64_t error_mm);
  std::int64_t count() const noexcept { return count_; }
  std::int64_t sum_mm() const noexcept { return sum_mm_; }
  /// The error with the largest |error|, its sign kept (the first of equals); none without stops.
  std::optional<std::int64_t> worst_mm() const noexcept { return worst_mm_; }
  /// Signed mean (the bias of the stops); none without stops.
  std::optional<double> mean_mm() const;
  /// The nearest-rank 95th percentile of |error|; none without stops.
  std::optional<std::int64_t> p95_mm() const;
  const Buckets& buckets() const noexcept { return buckets_; }

  /// Puts back what the store kept; false when the parts do not agree (count != bucket total).
  bool restore(std::int64_t count, std::int64_t sum_mm, std::optional<std::int64_t> worst_mm,
               const Buckets& buckets);

 private:
  std::int64_t count_ = 0;
  std::int64_t sum_mm_ = 0;
  std::optional<std::int64_t> worst_mm_;
  Buckets buckets_{};
};

struct FloorCounters {
  std::int64_t arrivals = 0;
  StopErrorStats stop_error;
};

struct ResetEntry {
  std::int64_t at_unix_ms = 0;
  std::string who;
  std::vector<std::string> names;
};

/// A text as one part of a dotted counter name: lower case, anything but a-z 0-9 _ turned to _
/// (so a kind or cause can never add a dot), "unknown" when empty.
std::string counter_name_part(std::string_view text);
/// A relevelling run, whatever the drive kind calls it ("relevel", DCP4's "relevel_distance").
bool is_relevel(std::string_view kind);
/// A travel from one floor to another that arrived at its target: what floor-to-floor times
/// are made of (not a relevelling, an inspection run or a learning leg, which have no other
/// floor as their target).
bool is_floor_to_floor(const Travel& t);

/// The counters that exist from the start (with 0); the others appear with their first event.
const std::vector<std::string>& fixed_counter_names();
/// The families of counters named after an event's kind, cause or code ("travels.", ...).
const std::vector<std::string>& counter_families();

class Counters {
 public:
  Counters();

  /// A travel ended: travels, travels.<kind>.<outcome>, motor_starts, running_ms, relevels,
  /// learning_travels, aborts.<cause>, and the arrival and stopping error at end_floor.
  void count_travel(const Travel& t);
  void count_fault(std::string_view code);
  void count_link_loss();
  /// A learning travel ended (all its legs: one learning travel).
  void count_learning_travel();
  /// One look at the inputs: door cycles and safety-chain openings from the edges since the
  /// last look, inspection_ms and recall_ms for the time since the last look the switch was on.
  void count_inputs(const InputsSample& sample, std::int64_t now_mono_ms);
  /// operating_ms: the time since the last call (or since start_operating).
  void count_operating(std::int64_t now_mono_ms);
  /// The moment operating time starts counting (the daemon's start).
  void start_operating(std::int64_t now_mono_ms);

  /// Why `names` cannot be reset (the first unknown name and what is allowed); none if they can.
  std::optional<std::string> check_reset(const std::vector<std::string>& names) const;
  /// Sets the named counters to 0 (check_reset first) and keeps the reset in resets().
  void apply_reset(const std::vector<std::string>& names, std::string_view who,
                   std::int64_t at_unix_ms);

  std::int64_t value(std::string_view name) const;
  const std::map<std::string, std::int64_t, std::less<>>& values() const noexcept {
    return values_;
  }
  const std::map<int, FloorCounters>& floors() const noexcept { return floors_; }
  const std::vector<ResetEntry>& resets() const noexcept { return resets_; }

  /// What changed since mark_written(): counter names and floors.
  bool changed() const noexcept { return !changed_names_.empty() || !changed_floors_.empty(); }
  const std::set<std::string, std::less<>>& changed_names() const noexcept {
    return changed_names_;
  }
  const std::set<int>& changed_floors() const noexcept { return changed_floors_; }
  void mark_written();

  /// Loading from the store: the values it kept (not marked changed).
  void restore_value(const std::string& name, std::int64_t value);
  void restore_floor(int floor, const FloorCounters& counters);
  void restore_reset(ResetEntry entry);

 private:
  void add(const std::string& name, std::int64_t amount);

  std::map<std::string, std::int64_t, std::less<>> values_;
  std::map<int, FloorCounters> floors_;
  std::vector<ResetEntry> resets_;
  std::set<std::string, std::less<>> changed_names_;
  std::set<int> changed_floors_;

  std::optional<std::int64_t> last_operating_mono_ms_;
  std::optional<InputsSample> last_inputs_;
  std::int64_t last_inputs_mono_ms_ = 0;
  /// The doors unlocked since they were last seen locked: the next lock ends a cycle.
  bool doors_opened_ = false;
};

}  // namespace liftd::record
