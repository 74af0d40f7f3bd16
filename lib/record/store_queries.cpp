// The record's reads (store.cpp has opening, loading and writing): `history`, the travels
// filtered by time, floor, outcome and cause, newest first; `trend`, the daily aggregates.
#include <sqlite3.h>

#include <cmath>
#include <string>

#include "record/sqlite_calls.hpp"
#include "record/store.hpp"
#include "record/time_text.hpp"

namespace liftd::record {
namespace {

using namespace sql;

// History filters, one bit each: a statement is prepared for each combination asked, so each
// has a plan that uses the indexes its filters allow.
constexpr unsigned kFrom = 1, kTo = 2, kFloor = 4, kOutcome = 8, kCause = 16, kCurves = 32;

/// The conditions of one branch of the history query (every filter but the floor).
std::string history_conditions(unsigned filters) {
  std::string sql;
  if (filters & kFrom) sql += " AND t.start_unix_ms >= ?1";
  if (filters & kTo) sql += " AND t.start_unix_ms < ?2";
  if (filters & kOutcome) sql += " AND t.arrived = ?4";
  if (filters & kCause) sql += " AND t.cause = ?5";
  return sql;
}

std::string history_sql(unsigned filters) {
  // Newest first by start time (the history's time range is the start's too), equal starts by
  // the order they were recorded.
  const std::string order = " ORDER BY t.start_unix_ms DESC, t.id DESC";
  const std::string columns =
      "t.id, t.start_unix_ms, t.end_unix_ms, t.start_mono_ms, t.end_mono_ms, t.from_floor, "
      "t.to_floor, t.end_floor, t.kind, t.arrived, t.cause, t.duration_ms, t.top_speed_mm_s, "
      "t.stop_error_mm, t.relevel_followed";
  std::string from = "travels t";
  std::string where = " WHERE 1" + history_conditions(filters);
  if (filters & kFloor) {
    // "from_floor or to_floor is the floor" as two branches, each read newest first from its own
    // index (travels_by_from, travels_by_to) and cut at the limit, so a query reads about
    // `limit` rows of each, however many travels the floor has in the range (an OR would read
    // them all and sort them). A travel from the floor to itself is in the first branch only.
    const std::string branch = "SELECT " + columns + " FROM travels t WHERE ";
    const std::string rest = history_conditions(filters) + order + " LIMIT ?6";
    from = "(SELECT * FROM (" + branch + "t.from_floor = ?3" + rest + ") UNION ALL " +
           "SELECT * FROM (" + branch + "t.to_floor = ?3 AND t.from_floor IS NOT ?3" + rest +
           ")) t";
    where.clear();
  }
  std::string sql = "SELECT " + columns;
  if (filters & kCurves) sql += ", c.curve";
  sql += " FROM " + from;
  if (filters & kCurves) sql += " LEFT JOIN curves c ON c.travel_id = t.id";
  return sql + where + order + " LIMIT ?6";
}

double rounded(double value) {
  return std::round(value * 100.0) / 100.0;
}

}  // namespace

bool Store::history(const HistoryQuery& query, nlohmann::json& answer, StoreError& error) {
  const unsigned filters = (query.from_unix_ms ? kFrom : 0U) | (query.to_unix_ms ? kTo : 0U) |
                           (query.floor ? kFloor : 0U) | (query.outcome ? kOutcome : 0U) |
                           (query.cause ? kCause : 0U) | (query.curves ? kCurves : 0U);
  Statement& statement = history_[filters];
  if (!statement.get() && !prepare(statement, history_sql(filters), error)) {
    history_.erase(filters);
    if (error.failure == StoreFailure::foreign) error.failure = StoreFailure::other;
    return false;
  }
  sqlite3_stmt* s = statement.get();
  ResetOnExit reset_on_exit(s);
  const std::size_t limit = std::min(query.limit, kMaxHistoryLimit);
  if (query.from_unix_ms) bind_param(s, 1, *query.from_unix_ms);
  if (query.to_unix_ms) bind_param(s, 2, *query.to_unix_ms);
  if (query.floor) bind_param(s, 3, std::int64_t{*query.floor});
  if (query.outcome) bind_param(s, 4, std::int64_t{*query.outcome == "arrived" ? 1 : 0});
  if (query.cause) bind_param(s, 5, std::string_view(*query.cause));
  // One row more than asked tells whether the answer is cut.
  bind_param(s, 6, static_cast<std::int64_t>(limit) + 1);

  nlohmann::json travels = nlohmann::json::array();
  bool truncated = false;
  int code;
  while ((code = sqlite3_step(s)) == SQLITE_ROW) {
    if (travels.size() == limit) {
      truncated = true;
      break;
    }
    nlohmann::json t = nlohmann::json::object();
    t["id"] = sqlite3_column_int64(s, 0);
    t["start"] = format_utc_ms(sqlite3_column_int64(s, 1));
    t["end"] = format_utc_ms(sqlite3_column_int64(s, 2));
    t["start_mono_ms"] = sqlite3_column_int64(s, 3);
    t["end_mono_ms"] = sqlite3_column_int64(s, 4);
    t["from_floor"] = column_json(s, 5);
    t["to_floor"] = column_json(s, 6);
    t["end_floor"] = column_json(s, 7);
    t["kind"] = column_text(s, 8);
    t["outcome"] = sqlite3_column_int64(s, 9) != 0 ? "arrived" : "aborted";
    t["cause"] = column_text(s, 10);
    t["duration_ms"] = sqlite3_column_int64(s, 11);
    t["top_speed_mm_s"] = column_json(s, 12);
    t["stop_error_mm"] = column_json(s, 13);
    t["relevel_followed"] = sqlite3_column_int64(s, 14) != 0;
    if (query.curves && sqlite3_column_type(s, 15) != SQLITE_NULL) {
      nlohmann::json curve = nlohmann::json::parse(column_text(s, 15), nullptr, false);
      if (curve.is_discarded()) {
        t["curve"] = nullptr;
        t["curve_error"] = "the kept curve is not valid JSON";
      } else {
        t["curve"] = std::move(curve);
      }
    }
    travels.push_back(std::move(t));
  }
  if (code != SQLITE_ROW && code != SQLITE_DONE) {
    error = error_of(code, "reading the history");
    return false;
  }
  answer = nlohmann::json::object();
  answer["count"] = travels.size();
  answer["truncated"] = truncated;
  answer["travels"] = std::move(travels);
  return true;
}

bool Store::trend(const TrendQuery& query, nlohmann::json& answer, StoreError& error) {
  // Every UTC day the range [from, to) touches.
  const std::int64_t first_day =
      query.from_unix_ms ? utc_day(*query.from_unix_ms) : std::numeric_limits<std::int64_t>::min();
  const std::int64_t end_day = query.to_unix_ms ? utc_day(*query.to_unix_ms - 1) + 1
                                                : std::numeric_limits<std::int64_t>::max();
  // One trend statement over the days (and the floor, where asked): `row(s)` for each row.
  const auto each_row = [&](Statement& all, Statement& one_floor, auto row) {
    sqlite3_stmt* s = (query.floor ? one_floor : all).get();
    ResetOnExit reset_on_exit(s);
    bind_param(s, 1, first_day);
    bind_param(s, 2, end_day);
    if (query.floor) bind_param(s, 3, std::int64_t{*query.floor});
    int code;
    while ((code = sqlite3_step(s)) == SQLITE_ROW) row(s);
    if (code == SQLITE_DONE) return true;
    error = error_of(code, "reading the trend");
    return false;
  };
  nlohmann::json days = nlohmann::json::array();
  const bool days_read = each_row(trend_days_, trend_days_floor_, [&](sqlite3_stmt* s) {
    const std::int64_t errors = sqlite3_column_int64(s, 3);
    const std::int64_t travels = sqlite3_column_int64(s, 6);
    nlohmann::json stop_error = nlohmann::json::object();
    stop_error["count"] = errors;
    stop_error["mean"] =
        errors > 0 ? nlohmann::json(rounded(static_cast<double>(sqlite3_column_int64(s, 4)) /
                                            static_cast<double>(errors)))
                   : nlohmann::json(nullptr);
    stop_error["worst"] = column_json(s, 5);
    nlohmann::json travel_ms = nlohmann::json::object();
    travel_ms["count"] = travels;
    travel_ms["mean"] =
        travels > 0 ? nlohmann::json(rounded(static_cast<double>(sqlite3_column_int64(s, 7)) /
                                             static_cast<double>(travels)))
                    : nlohmann::json(nullptr);
    nlohmann::json day = nlohmann::json::object();
    day["day"] = format_day(sqlite3_column_int64(s, 0));
    day["floor"] = sqlite3_column_int64(s, 1);
    day["arrivals"] = sqlite3_column_int64(s, 2);
    day["stop_error_mm"] = std::move(stop_error);
    day["travel_ms"] = std::move(travel_ms);
    days.push_back(std::move(day));
  });
  if (!days_read) return false;
  nlohmann::json pairs = nlohmann::json::array();
  const bool pairs_read = each_row(trend_pairs_, trend_pairs_floor_, [&](sqlite3_stmt* s) {
    const std::int64_t travels = sqlite3_column_int64(s, 3);
    nlohmann::json pair = nlohmann::json::object();
    pair["day"] = format_day(sqlite3_column_int64(s, 0));
    pair["from"] = sqlite3_column_int64(s, 1);
    pair["to"] = sqlite3_column_int64(s, 2);
    pair["count"] = travels;
    pair["mean_ms"] = rounded(static_cast<double>(sqlite3_column_int64(s, 4)) /
                              static_cast<double>(std::max<std::int64_t>(travels, 1)));
    pairs.push_back(std::move(pair));
  });
  if (!pairs_read) return false;
  answer = nlohmann::json::object();
  answer["days"] = std::move(days);
  answer["pairs"] = std::move(pairs);
  return true;
}

}  // namespace liftd::record
