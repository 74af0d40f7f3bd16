#include "record/lift_record.hpp"

#include <fcntl.h>
#include <stdio.h>
#include <sys/stat.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <exception>
#include <span>

#include "log/log.hpp"
#include "record/counters.hpp"
#include "record/store.hpp"
#include "record/time_text.hpp"

namespace liftd::record {

namespace {

constexpr std::string_view kComponent = "record";

bool exists(const std::string& path) {
  struct stat info {};
  return ::lstat(path.c_str(), &info) == 0;
}

/// Renames `from` to `to` without ever replacing a file already at `to`. 0 or an errno.
int rename_keeping(const std::string& from, const std::string& to) {
  if (::renameat2(AT_FDCWD, from.c_str(), AT_FDCWD, to.c_str(), RENAME_NOREPLACE) == 0) return 0;
  if (errno != EINVAL && errno != ENOSYS) return errno;
  // A file system without RENAME_NOREPLACE: look first (only the io thread moves these files).
  if (exists(to)) return EEXIST;
  return ::rename(from.c_str(), to.c_str()) == 0 ? 0 : errno;
}

std::string what_sqlite_said(const StoreError& error) {
  std::string text = error.doing + ": " + error.detail;
  if (error.system_errno != 0) text += " (" + std::string(std::strerror(error.system_errno)) + ")";
  return text;
}

}  // namespace

struct LiftRecord::State {
  Options options;
  Counters counters;
  std::unique_ptr<Store> store;
  std::string reason;  ///< why the record is off (empty while on)
  std::int64_t since_unix_ms = 0;
  std::int64_t last_counters_write_mono_ms = 0;
  /// The newest wall-clock time a call gave (names a damaged file moved aside).
  std::int64_t last_unix_ms = 0;

  void turn_off(std::string why, log::Level level, log::Fields fields) {
    store.reset();
    reason = std::move(why);
    fields.insert(fields.begin(), log::Field{"path", options.path});
    fields.push_back(log::Field{"reason", reason});
    // A record that failed is catalogued (journalctl -x says what to check); one switched off by
    // the configuration is not.
    log::event(
        level, kComponent, "record_off", fields, "the lift's record is off: " + reason,
        level >= log::Level::warn ? std::optional(log::Catalogued::RecordOff) : std::nullopt);
  }

  /// The record fails: off with a reason and one journal line; a corrupt file is moved aside.
  void fail(const StoreError& error, std::int64_t now_unix_ms) {
    const std::string& path = options.path;
    const std::string said = what_sqlite_said(error);
    log::Fields fields{{"failure", said}};
    std::string why;
    switch (error.failure) {
      case StoreFailure::cannot_open:
        why = "cannot open or create " + path + " (" + said +
              "): check that its directory exists and that liftd may write there "
              "(the unit's StateDirectory=)";
        break;
      case StoreFailure::read_only:
        why = path + " cannot be written (" + said +
              "): make the file and its directory writable for liftd";
        break;
      case StoreFailure::full:
        why = "the storage holding " + path + " is full (" + said +
              (options.max_bytes > 0 ? ", or the record reached its max_bytes" : "") +
              "): free space there; the record stays off until liftd starts again";
        break;
      case StoreFailure::io:
        why = "the storage holding " + path + " failed a read or write (" + said +
              "): check the storage (full? failing? the kernel log says); the record stays off "
              "until liftd starts again";
        break;
      case StoreFailure::newer_schema:
        why = path + " was written by a newer liftd (" + said +
              "): left untouched; run that liftd, or move the file away to start a new record";
        break;
      case StoreFailure::foreign:
        why = path + " is not a record this liftd can use (" + said +
              "): left untouched; move it away or set record.path to another file";
        break;
      case StoreFailure::busy:
        why = "another process holds the write lock of " + path + " (" + said +
              "): stop it; the record stays off until liftd starts again";
        break;
      case StoreFailure::corrupt: {
        if (store) store->skip_checkpoint_on_close();
        store.reset();
        const std::string aside = path + ".corrupt-" + format_utc_compact(now_unix_ms);
        const int failed = rename_keeping(path, aside);
        if (failed == 0) {
          // The log and its index belong with the file they were written for; a log left at the
          // old name would be replayed into the next, new record.
          for (const char* suffix : {"-wal", "-shm"}) {
            if (exists(path + suffix)) rename_keeping(path + suffix, aside + suffix);
          }
          why = path + " is damaged (" + said + "): moved aside to " + aside +
                "; the next start of liftd creates a new record";
          fields.push_back(log::Field{"moved_to", aside});
        } else {
          why = path + " is damaged (" + said + ") and could not be moved aside to " + aside +
                " (" + std::strerror(failed) + "): move it away by hand, then restart liftd";
        }
        break;
      }
      case StoreFailure::other:
        why = "the record at " + path + " failed (" + said +
              "); the record stays off until liftd starts again";
        break;
    }
    turn_off(std::move(why), log::Level::error, std::move(fields));
  }

  /// A query failed: a failure of the file turns the record off as a write's would; anything
  /// else (another process's lock, say) is that query's error alone.
  nlohmann::json query_failed(const StoreError& error, nlohmann::json answer) {
    switch (error.failure) {
      case StoreFailure::cannot_open:
      case StoreFailure::read_only:
      case StoreFailure::full:
      case StoreFailure::io:
      case StoreFailure::corrupt:
        fail(error, last_unix_ms);
        answer["record"] = "off";
        answer["error"] = reason;
        break;
      default:
        answer["error"] = what_sqlite_said(error);
        break;
    }
    return answer;
  }

  /// An exception from inside (out of memory, say): off, never past the public API.
  void fail_inside(const char* doing) {
    std::string what = "unknown exception";
    try {
      throw;
    } catch (const std::exception& e) {
      what = e.what();
    } catch (...) {
    }
    try {
      turn_off(std::string("internal error while ") + doing + ": " + what, log::Level::error, {});
    } catch (...) {
      store.reset();
      reason = "internal error";
    }
  }

  void write_counters(std::int64_t now_mono_ms) {
    StoreError error;
    if (!store->write_counters(counters, error)) {
      fail(error, last_unix_ms);
      return;
    }
    last_counters_write_mono_ms = now_mono_ms;
  }
};

LiftRecord::LiftRecord(Options options, std::int64_t now_mono_ms, std::int64_t now_unix_ms) {
  try {
    state_ = std::make_unique<State>();
    State& s = *state_;
    s.options = std::move(options);
    s.since_unix_ms = now_unix_ms;
    s.last_unix_ms = now_unix_ms;
    s.last_counters_write_mono_ms = now_mono_ms;
    s.counters.start_operating(now_mono_ms);
    if (s.options.path.empty()) {
      s.turn_off(s.options.off_reason.empty() ? "record.path is not set" : s.options.off_reason,
                 log::Level::info, {});
      return;
    }
    const StoreOptions store_options{s.options.max_travels, s.options.curves_kept,
                                     s.options.max_bytes};
    StoreError error;
    s.store = Store::open(s.options.path, store_options, now_unix_ms, error);
    if (!s.store) {
      s.fail(error, now_unix_ms);
      return;
    }
    if (!s.store->load(s.counters, error)) {
      s.fail(error, now_unix_ms);
      return;
    }
    s.since_unix_ms = s.store->since_unix_ms();
  } catch (...) {
    if (state_) state_->fail_inside("opening the record");
  }
}

LiftRecord::~LiftRecord() {
  try {
    if (state_ && state_->store) {
      StoreError error;
      state_->store->write_counters(state_->counters, error);
    }
  } catch (...) {
    // Best effort: the last interval's counters are what a failed write here loses.
  }
}

bool LiftRecord::on() const noexcept {
  return state_ && state_->store != nullptr;
}

nlohmann::json LiftRecord::status_json() const {
  if (!state_) return nlohmann::json::object();
  try {
    nlohmann::json status = nlohmann::json::object();
    status["state"] = on() ? "on" : "off";
    status["path"] = state_->options.path;
    status["reason"] = on() ? nlohmann::json(nullptr) : nlohmann::json(state_->reason);
    status["travels"] = on() ? state_->store->travel_count() : 0;
    return status;
  } catch (...) {
    return nlohmann::json::object();
  }
}

void LiftRecord::travel(Travel t, std::int64_t now_mono_ms, std::int64_t now_unix_ms) {
  if (!state_) return;
  State& s = *state_;
  try {
    s.last_unix_ms = now_unix_ms;
    s.counters.count_travel(t);
    s.counters.count_operating(now_mono_ms);
    if (!s.store) return;
    StoreError error;
    if (!s.store->write_travels(std::span<Travel>(&t, 1), s.counters, error)) {
      s.fail(error, now_unix_ms);
      return;
    }
    s.last_counters_write_mono_ms = now_mono_ms;
  } catch (...) {
    s.fail_inside("writing a travel");
  }
}

void LiftRecord::fault_raised(std::string_view code, std::int64_t /*now_mono_ms*/) {
  if (!state_) return;
  try {
    state_->counters.count_fault(code);
  } catch (...) {
    state_->fail_inside("counting a fault");
  }
}

void LiftRecord::link_lost(std::int64_t /*now_mono_ms*/) {
  if (!state_) return;
  try {
    state_->counters.count_link_loss();
  } catch (...) {
    state_->fail_inside("counting a link loss");
  }
}

void LiftRecord::learning_travel(std::int64_t /*now_mono_ms*/) {
  if (!state_) return;
  try {
    state_->counters.count_learning_travel();
  } catch (...) {
    state_->fail_inside("counting a learning travel");
  }
}

void LiftRecord::inputs(const InputsSample& sample, std::int64_t now_mono_ms) {
  if (!state_) return;
  try {
    state_->counters.count_inputs(sample, now_mono_ms);
  } catch (...) {
    state_->fail_inside("counting the inputs");
  }
}

void LiftRecord::tick(std::int64_t now_mono_ms, std::int64_t now_unix_ms) {
  if (!state_) return;
  State& s = *state_;
  try {
    s.last_unix_ms = now_unix_ms;
    s.counters.count_operating(now_mono_ms);
    // Counters alone are written at most once per interval (the flash's wear: issue #42 allows
    // one transaction per travel plus one per counters_interval_ms).
    if (s.store && s.counters.changed() &&
        now_mono_ms - s.last_counters_write_mono_ms >= s.options.counters_interval_ms) {
      s.write_counters(now_mono_ms);
    }
  } catch (...) {
    s.fail_inside("writing the counters");
  }
}

nlohmann::json LiftRecord::counters_json() const {
  if (!state_) return nlohmann::json::object();
  try {
    const Counters& c = state_->counters;
    nlohmann::json counters = nlohmann::json::object();
    for (const auto& [name, value] : c.values()) counters[name] = value;
    nlohmann::json floors = nlohmann::json::array();
    for (const auto& [floor, kept] : c.floors()) {
      const StopErrorStats& e = kept.stop_error;
      nlohmann::json error = nlohmann::json::object();
      error["count"] = e.count();
      error["mean"] = e.mean_mm() ? nlohmann::json(std::round(*e.mean_mm() * 100.0) / 100.0)
                                  : nlohmann::json(nullptr);
      error["p95"] = e.p95_mm() ? nlohmann::json(*e.p95_mm()) : nlohmann::json(nullptr);
      error["worst"] = e.worst_mm() ? nlohmann::json(*e.worst_mm()) : nlohmann::json(nullptr);
      nlohmann::json row = nlohmann::json::object();
      row["floor"] = floor;
      row["arrivals"] = kept.arrivals;
      row["stop_error_mm"] = std::move(error);
      floors.push_back(std::move(row));
    }
    nlohmann::json resets = nlohmann::json::array();
    for (const ResetEntry& r : c.resets()) {
      nlohmann::json row = nlohmann::json::object();
      row["at"] = format_utc_ms(r.at_unix_ms);
      row["who"] = r.who;
      row["names"] = r.names;
      resets.push_back(std::move(row));
    }
    nlohmann::json answer = nlohmann::json::object();
    answer["record"] = on() ? "on" : "off";
    answer["since"] = format_utc_ms(state_->since_unix_ms);
    answer["counters"] = std::move(counters);
    answer["floors"] = std::move(floors);
    answer["resets"] = std::move(resets);
    return answer;
  } catch (...) {
    return nlohmann::json::object();
  }
}

ResetResult LiftRecord::reset(const std::vector<std::string>& names, std::string_view who,
                              std::int64_t now_unix_ms) {
  if (!state_) return {false, "the record could not be set up"};
  State& s = *state_;
  try {
    s.last_unix_ms = now_unix_ms;
    if (auto refused = s.counters.check_reset(names)) return {false, *refused};
    // A reset that cannot be kept would come undone at the next start: refuse it.
    if (!s.store) return {false, "nothing is reset, the lift's record is off: " + s.reason};
    s.counters.apply_reset(names, who, now_unix_ms);
    StoreError error;
    if (!s.store->write_reset(s.counters.resets().back(), s.counters, error)) {
      s.fail(error, now_unix_ms);
      return {false, "the reset is not kept, the lift's record is off: " + s.reason};
    }
    return {true, ""};
  } catch (...) {
    s.fail_inside("resetting counters");
    return {false, "internal error: " + s.reason};
  }
}

namespace {

nlohmann::json empty_history(std::string_view record) {
  nlohmann::json answer = nlohmann::json::object();
  answer["travels"] = nlohmann::json::array();
  answer["count"] = 0;
  answer["truncated"] = false;
  answer["record"] = record;
  return answer;
}

nlohmann::json empty_trend(std::string_view record) {
  nlohmann::json answer = nlohmann::json::object();
  answer["days"] = nlohmann::json::array();
  answer["pairs"] = nlohmann::json::array();
  answer["record"] = record;
  return answer;
}

}  // namespace

nlohmann::json LiftRecord::history_json(const HistoryQuery& query) const {
  if (!state_) return empty_history("off");
  try {
    if (query.outcome && *query.outcome != "arrived" && *query.outcome != "aborted") {
      nlohmann::json answer = empty_history(on() ? "on" : "off");
      answer["error"] =
          "outcome must be \"arrived\" or \"aborted\", not \"" + *query.outcome + "\"";
      return answer;
    }
    if (!on()) return empty_history("off");
    nlohmann::json answer;
    StoreError error;
    if (!state_->store->history(query, answer, error)) {
      return state_->query_failed(error, empty_history("on"));
    }
    answer["record"] = "on";
    return answer;
  } catch (...) {
    nlohmann::json answer = empty_history(on() ? "on" : "off");
    answer["error"] = "internal error while reading the history";
    return answer;
  }
}

nlohmann::json LiftRecord::trend_json(const TrendQuery& query) const {
  if (!state_) return empty_trend("off");
  try {
    if (!on()) return empty_trend("off");
    nlohmann::json answer;
    StoreError error;
    if (!state_->store->trend(query, answer, error)) {
      return state_->query_failed(error, empty_trend("on"));
    }
    answer["record"] = "on";
    return answer;
  } catch (...) {
    nlohmann::json answer = empty_trend(on() ? "on" : "off");
    answer["error"] = "internal error while reading the trend";
    return answer;
  }
}

}  // namespace liftd::record
