#include "record/counters.hpp"

#include <cmath>
#include <cstdlib>
#include <numeric>

namespace liftd::record {

namespace {

std::int64_t magnitude(std::int64_t v) {
  return v < 0 ? -v : v;
}

bool starts_with(std::string_view text, std::string_view prefix) {
  return text.substr(0, prefix.size()) == prefix;
}

std::string join(const std::vector<std::string>& parts, std::string_view separator) {
  std::string out;
  for (const std::string& p : parts) {
    if (!out.empty()) out += separator;
    out += p;
  }
  return out;
}

}  // namespace

void StopErrorStats::add(std::int64_t error_mm) {
  const std::int64_t size = magnitude(error_mm);
  const std::size_t bucket = size >= kHistogramMm ? kBuckets - 1 : static_cast<std::size_t>(size);
  ++buckets_[bucket];
  ++count_;
  sum_mm_ += error_mm;
  if (!worst_mm_ || size > magnitude(*worst_mm_)) worst_mm_ = error_mm;
}

std::optional<double> StopErrorStats::mean_mm() const {
  if (count_ == 0) return std::nullopt;
  return static_cast<double>(sum_mm_) / static_cast<double>(count_);
}

std::optional<std::int64_t> StopErrorStats::p95_mm() const {
  if (count_ == 0) return std::nullopt;
  // Nearest rank: the smallest value with at least 95 % of the stops at or below it.
  const std::int64_t rank = (95 * count_ + 99) / 100;
  std::int64_t seen = 0;
  for (std::size_t i = 0; i + 1 < kBuckets; ++i) {
    seen += buckets_[i];
    if (seen >= rank) return static_cast<std::int64_t>(i);
  }
  return worst_mm_ ? magnitude(*worst_mm_) : kHistogramMm;
}

bool StopErrorStats::restore(std::int64_t count, std::int64_t sum_mm,
                             std::optional<std::int64_t> worst_mm, const Buckets& buckets) {
  const std::int64_t total = std::accumulate(buckets.begin(), buckets.end(), std::int64_t{0});
  if (total != count || count < 0 || (count > 0) != worst_mm.has_value()) return false;
  count_ = count;
  sum_mm_ = sum_mm;
  worst_mm_ = worst_mm;
  buckets_ = buckets;
  return true;
}

std::string counter_name_part(std::string_view text) {
  if (text.empty()) return "unknown";
  std::string out;
  out.reserve(text.size());
  for (char c : text) {
    if (c >= 'A' && c <= 'Z') {
      out += static_cast<char>(c - 'A' + 'a');
    } else if ((c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_') {
      out += c;
    } else {
      out += '_';
    }
  }
  return out;
}

const std::vector<std::string>& fixed_counter_names() {
  static const std::vector<std::string> names = {
      "travels",          "motor_starts", "running_ms",  "relevels",
      "learning_travels", "link_losses",  "door_cycles", "safety_chain_openings",
      "inspection_ms",    "recall_ms",    "operating_ms"};
  return names;
}

const std::vector<std::string>& counter_families() {
  static const std::vector<std::string> families = {"travels.", "aborts.", "faults."};
  return families;
}

Counters::Counters() {
  for (const std::string& name : fixed_counter_names()) values_[name] = 0;
}

void Counters::add(const std::string& name, std::int64_t amount) {
  values_[name] += amount;
  changed_names_.insert(name);
}

void Counters::count_travel(const Travel& t) {
  const std::string kind = counter_name_part(t.kind);
  add("travels", 1);
  add("travels." + kind + (t.arrived ? ".arrived" : ".aborted"), 1);
  add("motor_starts", 1);
  if (t.duration_ms > 0) add("running_ms", t.duration_ms);
  if (is_relevel(t.kind)) add("relevels", 1);
  if (!t.arrived) add("aborts." + counter_name_part(t.cause), 1);
  if (t.arrived && t.end_floor) {
    FloorCounters& floor = floors_[*t.end_floor];
    ++floor.arrivals;
    if (t.stop_error_mm) floor.stop_error.add(*t.stop_error_mm);
    changed_floors_.insert(*t.end_floor);
  }
}

void Counters::count_fault(std::string_view code) {
  add("faults." + counter_name_part(code), 1);
}

bool is_relevel(std::string_view kind) {
  return kind.substr(0, 7) == "relevel";
}

bool is_floor_to_floor(const Travel& t) {
  return t.arrived && t.from_floor && t.end_floor && *t.from_floor != *t.end_floor &&
         t.to_floor == t.end_floor && !is_relevel(t.kind);
}

void Counters::count_learning_travel() {
  add("learning_travels", 1);
}

void Counters::count_link_loss() {
  add("link_losses", 1);
}

void Counters::count_inputs(const InputsSample& sample, std::int64_t now_mono_ms) {
  if (last_inputs_) {
    const InputsSample& last = *last_inputs_;
    const std::int64_t elapsed = now_mono_ms - last_inputs_mono_ms_;
    // The switch's state of the last look holds until this one (the io thread looks often).
    if (elapsed > 0 && last.inspection) add("inspection_ms", elapsed);
    if (elapsed > 0 && last.recall) add("recall_ms", elapsed);
    if (last.doors_locked && !sample.doors_locked) doors_opened_ = true;
    if (!last.doors_locked && sample.doors_locked && doors_opened_) {
      add("door_cycles", 1);
      doors_opened_ = false;
    }
    if (last.safety_chain && !sample.safety_chain) add("safety_chain_openings", 1);
  }
  last_inputs_ = sample;
  last_inputs_mono_ms_ = now_mono_ms;
}

void Counters::start_operating(std::int64_t now_mono_ms) {
  last_operating_mono_ms_ = now_mono_ms;
}

void Counters::count_operating(std::int64_t now_mono_ms) {
  if (last_operating_mono_ms_ && now_mono_ms > *last_operating_mono_ms_) {
    add("operating_ms", now_mono_ms - *last_operating_mono_ms_);
  }
  if (!last_operating_mono_ms_ || now_mono_ms > *last_operating_mono_ms_) {
    last_operating_mono_ms_ = now_mono_ms;
  }
}

std::optional<std::string> Counters::check_reset(const std::vector<std::string>& names) const {
  const std::string allowed =
      "a counter name (" + join(fixed_counter_names(), ", ") +
      ", or a name counters lists), a prefix ending in \".*\" (travels.*, aborts.*, faults.*), "
      "\"floors\" or \"all\"";
  if (names.empty()) return "no counter named to reset: give " + allowed;
  for (const std::string& name : names) {
    if (name == "all" || name == "floors" || values_.contains(name)) continue;
    if (name.size() > 2 && name.ends_with(".*")) {
      const std::string_view prefix = std::string_view(name).substr(0, name.size() - 1);
      bool known = false;
      for (const std::string& family : counter_families()) known = known || prefix == family;
      for (const auto& [counter, value] : values_) known = known || starts_with(counter, prefix);
      if (known) continue;
    }
    return "unknown counter name \"" + name + "\": give " + allowed;
  }
  return std::nullopt;
}

void Counters::apply_reset(const std::vector<std::string>& names, std::string_view who,
                           std::int64_t at_unix_ms) {
  for (const std::string& name : names) {
    const bool all = name == "all";
    if (all || name == "floors") {
      for (auto& [floor, counters] : floors_) {
        counters = FloorCounters{};
        changed_floors_.insert(floor);
      }
    }
    if (name == "floors") continue;
    const bool prefix = name.ends_with(".*");
    const std::string_view stem = std::string_view(name).substr(0, name.size() - 1);
    for (auto& [counter, value] : values_) {
      if (all || counter == name || (prefix && starts_with(counter, stem))) {
        value = 0;
        changed_names_.insert(counter);
      }
    }
  }
  resets_.push_back(ResetEntry{at_unix_ms, std::string(who), names});
}

std::int64_t Counters::value(std::string_view name) const {
  const auto it = values_.find(name);
  return it == values_.end() ? 0 : it->second;
}

void Counters::mark_written() {
  changed_names_.clear();
  changed_floors_.clear();
}

void Counters::restore_value(const std::string& name, std::int64_t value) {
  values_[name] = value;
}

void Counters::restore_floor(int floor, const FloorCounters& counters) {
  floors_[floor] = counters;
}

void Counters::restore_reset(ResetEntry entry) {
  resets_.push_back(std::move(entry));
}

}  // namespace liftd::record
