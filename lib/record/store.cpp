#include "record/store.hpp"

#include <sqlite3.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <limits>
#include <utility>

#include "record/sqlite_calls.hpp"
#include "record/time_text.hpp"

namespace liftd::record {

namespace {

using namespace sql;

// Version 1 of the record. Curves live in their own table so dropping an old curve frees its
// pages without rewriting the travel row. The daily tables are the trend's aggregates, updated
// in each travel's transaction so a trend never scans the travels.
constexpr const char* kSchema = R"sql(
CREATE TABLE meta(key TEXT PRIMARY KEY, value INTEGER NOT NULL) WITHOUT ROWID;
CREATE TABLE counters(name TEXT PRIMARY KEY, value INTEGER NOT NULL) WITHOUT ROWID;
CREATE TABLE floors(floor INTEGER PRIMARY KEY, arrivals INTEGER NOT NULL,
  errors INTEGER NOT NULL, error_sum_mm INTEGER NOT NULL, worst_mm INTEGER,
  histogram BLOB NOT NULL);
CREATE TABLE resets(id INTEGER PRIMARY KEY, at_unix_ms INTEGER NOT NULL, who TEXT NOT NULL,
  names TEXT NOT NULL);
CREATE TABLE travels(id INTEGER PRIMARY KEY, start_unix_ms INTEGER NOT NULL,
  end_unix_ms INTEGER NOT NULL, start_mono_ms INTEGER NOT NULL, end_mono_ms INTEGER NOT NULL,
  from_floor INTEGER, to_floor INTEGER, end_floor INTEGER, kind TEXT NOT NULL,
  arrived INTEGER NOT NULL, cause TEXT NOT NULL, duration_ms INTEGER NOT NULL,
  top_speed_mm_s INTEGER, stop_error_mm INTEGER, relevel_followed INTEGER NOT NULL);
CREATE INDEX travels_by_start ON travels(start_unix_ms);
CREATE INDEX travels_by_from ON travels(from_floor, start_unix_ms);
CREATE INDEX travels_by_to ON travels(to_floor, start_unix_ms);
CREATE TABLE curves(travel_id INTEGER PRIMARY KEY, curve TEXT NOT NULL);
CREATE TABLE day_floor(day INTEGER NOT NULL, floor INTEGER NOT NULL, arrivals INTEGER NOT NULL,
  errors INTEGER NOT NULL, error_sum_mm INTEGER NOT NULL, worst_mm INTEGER,
  travels INTEGER NOT NULL, travel_ms INTEGER NOT NULL, PRIMARY KEY(day, floor)) WITHOUT ROWID;
CREATE TABLE day_pair(day INTEGER NOT NULL, from_floor INTEGER NOT NULL,
  to_floor INTEGER NOT NULL, travels INTEGER NOT NULL, travel_ms INTEGER NOT NULL,
  PRIMARY KEY(day, from_floor, to_floor)) WITHOUT ROWID;
)sql";

constexpr std::size_t kHistogramBytes = StopErrorStats::kBuckets * 8;

StoreFailure failure_of(int code) {
  switch (code & 0xff) {
    case SQLITE_CANTOPEN:
      return StoreFailure::cannot_open;
    case SQLITE_READONLY:
    case SQLITE_PERM:
    case SQLITE_AUTH:
      return StoreFailure::read_only;
    case SQLITE_FULL:
      return StoreFailure::full;
    case SQLITE_IOERR:
      return StoreFailure::io;
    case SQLITE_CORRUPT:
    case SQLITE_NOTADB:
      return StoreFailure::corrupt;
    case SQLITE_BUSY:
    case SQLITE_LOCKED:
      return StoreFailure::busy;
    default:
      return StoreFailure::other;
  }
}

/// Which system call an I/O error came from (SQLite's text says only "disk I/O error").
const char* io_error_name(int code) {
  switch (code) {
    case SQLITE_IOERR_READ:
      return "a read failed";
    case SQLITE_IOERR_SHORT_READ:
      return "the file ended early";
    case SQLITE_IOERR_WRITE:
      return "a write failed";
    case SQLITE_IOERR_FSYNC:
    case SQLITE_IOERR_DIR_FSYNC:
      return "an fsync failed";
    case SQLITE_IOERR_TRUNCATE:
      return "a truncate failed";
    case SQLITE_IOERR_FSTAT:
      return "an fstat failed";
    case SQLITE_IOERR_SHMOPEN:
    case SQLITE_IOERR_SHMSIZE:
    case SQLITE_IOERR_SHMMAP:
      return "the WAL index (-shm file) failed";
    default:
      return nullptr;
  }
}

std::string encode_histogram(const StopErrorStats::Buckets& buckets) {
  std::string bytes(kHistogramBytes, '\0');
  for (std::size_t i = 0; i < buckets.size(); ++i) {
    auto v = static_cast<std::uint64_t>(buckets[i]);
    for (std::size_t b = 0; b < 8; ++b) bytes[i * 8 + b] = static_cast<char>((v >> (8 * b)) & 0xff);
  }
  return bytes;
}

StopErrorStats::Buckets decode_histogram(const unsigned char* bytes) {
  StopErrorStats::Buckets buckets{};
  for (std::size_t i = 0; i < buckets.size(); ++i) {
    std::uint64_t v = 0;
    for (std::size_t b = 0; b < 8; ++b) v |= std::uint64_t{bytes[i * 8 + b]} << (8 * b);
    buckets[i] = static_cast<std::int64_t>(v);
  }
  return buckets;
}

/// Runs one query of a single value (PRAGMA user_version and the like): `read(statement)` takes
/// column 0 of its row.
template <typename Read>
int query_one(sqlite3* db, const char* sql, Read read) {
  sqlite3_stmt* s = nullptr;
  int rc = sqlite3_prepare_v2(db, sql, -1, &s, nullptr);
  if (rc != SQLITE_OK) return rc;
  rc = sqlite3_step(s);
  if (rc == SQLITE_ROW) {
    read(s);
    rc = SQLITE_OK;
  }
  sqlite3_finalize(s);
  return rc;
}

int query_int(sqlite3* db, const char* sql, std::int64_t& value) {
  return query_one(db, sql, [&](sqlite3_stmt* s) { value = sqlite3_column_int64(s, 0); });
}

int query_text(sqlite3* db, const char* sql, std::string& value) {
  return query_one(db, sql, [&](sqlite3_stmt* s) { value = column_text(s, 0); });
}

}  // namespace

Statement::~Statement() {
  sqlite3_finalize(statement_);
}

Statement::Statement(Statement&& other) noexcept
    : statement_(std::exchange(other.statement_, nullptr)) {}

Statement& Statement::operator=(Statement&& other) noexcept {
  if (this != &other) {
    sqlite3_finalize(statement_);
    statement_ = std::exchange(other.statement_, nullptr);
  }
  return *this;
}

Store::Store(sqlite3* db, std::string path, const StoreOptions& options)
    : db_(db), path_(std::move(path)), options_(options) {
  // A curve outlives no travel: keep at most as many curves as travels.
  if (options_.max_travels > 0) {
    options_.curves_kept =
        std::min(options_.curves_kept, static_cast<std::size_t>(options_.max_travels));
  }
}

Store::~Store() {
  // sqlite3_close_v2 waits for the statements (members, finalized after this body) and closes
  // the connection with the last of them.
  sqlite3_close_v2(db_);
}

StoreError Store::error_of(int code, std::string_view doing) const {
  StoreError error;
  error.failure = failure_of(code);
  error.sqlite_code = code;
  error.doing = std::string(doing);
  error.detail = sqlite3_errstr(code);
  const char* message = db_ ? sqlite3_errmsg(db_) : nullptr;
  if (message && error.detail != message) error.detail += std::string(": ") + message;
  if (const char* which = io_error_name(code)) error.detail += std::string(", ") + which;
  return error;
}

void Store::skip_checkpoint_on_close() {
  sqlite3_db_config(db_, SQLITE_DBCONFIG_NO_CKPT_ON_CLOSE, 1, nullptr);
}

std::unique_ptr<Store> Store::open(const std::string& path, const StoreOptions& options,
                                   std::int64_t now_unix_ms, StoreError& error) {
  sqlite3* db = nullptr;
  const int flags = SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE | SQLITE_OPEN_NOMUTEX;
  const int rc = sqlite3_open_v2(path.c_str(), &db, flags, nullptr);
  // The store owns the connection from here, even a failed one (sqlite3_close_v2 frees both).
  std::unique_ptr<Store> store(new Store(db, path, options));
  if (rc != SQLITE_OK) {
    error = store->error_of(rc, "opening the file");
    // Right after the failed open the errno SQLite kept is the open's own (later, other calls
    // may have replaced it, so it is taken only here).
    error.system_errno = sqlite3_system_errno(db);
    return nullptr;
  }
  sqlite3_extended_result_codes(db, 1);
  if (sqlite3_db_readonly(db, "main") == 1) {
    error = store->error_of(SQLITE_READONLY, "opening the file");
    error.detail = "the file can only be opened for reading";
    return nullptr;
  }

  // Nothing is written before the version and the file are checked, so a newer record stays
  // untouched and a damaged one is moved aside as it was found.
  std::int64_t version = 0;
  if (int code = query_int(db, "PRAGMA user_version", version); code != SQLITE_OK) {
    error = store->error_of(code, "reading the schema version");
    if (error.failure == StoreFailure::corrupt || error.failure == StoreFailure::other) {
      store->skip_checkpoint_on_close();
    }
    return nullptr;
  }
  if (version > kSchemaVersion) {
    error = StoreError{StoreFailure::newer_schema, 0, 0, "reading the schema version",
                       "schema version " + std::to_string(version) + ", this liftd knows " +
                           std::to_string(kSchemaVersion) + " and older"};
    return nullptr;
  }
  std::string check;
  if (int code = query_text(db, "PRAGMA quick_check", check); code != SQLITE_OK) {
    error = store->error_of(code, "checking the file (PRAGMA quick_check)");
    if (error.failure == StoreFailure::corrupt) store->skip_checkpoint_on_close();
    return nullptr;
  }
  if (check != "ok") {
    store->skip_checkpoint_on_close();
    error = StoreError{StoreFailure::corrupt, SQLITE_CORRUPT, 0,
                       "checking the file (PRAGMA quick_check)", check};
    return nullptr;
  }
  std::int64_t tables = 0;
  if (int code = query_int(db, "SELECT count(*) FROM sqlite_schema", tables); code != SQLITE_OK) {
    error = store->error_of(code, "reading the schema");
    return nullptr;
  }
  if (version == 0 && tables != 0) {
    error = StoreError{StoreFailure::foreign, 0, 0, "reading the schema",
                       "the file is an SQLite database with " + std::to_string(tables) +
                           " tables but no liftd schema version: not a liftd record"};
    return nullptr;
  }

  // WAL: a travel's transaction appends its pages to the log and nothing else, and readers never
  // block the writer. synchronous=FULL syncs the log at each commit: a power cut loses no
  // committed travel, only the counters changed since the last write (at most a minute of them,
  // issue #42). NORMAL would sync only at checkpoints, every 4 MiB of log: a power cut could take
  // hours of travels with it. The sync adds no bytes to what the flash is written; its cost is
  // the commit's wait on the io thread (record-bench: a travel's transaction).
  // Pages of 1 KiB, not SQLite's 4 KiB: a travel's transaction touches about ten pages besides
  // its curve (the row, its three index entries, the counters, the floor, the day's aggregates),
  // and each goes whole into the log. record-bench, per 1000 travels: 40 MB at 4 KiB against
  // 12 MB at 1 KiB without curves, 155 MB against 120 MB with a 10 s travel's curve; an idle hour
  // of counters writes 247 kB against 63 kB. The page size holds from the file's creation on.
  if (version == 0) {
    if (int code = sqlite3_exec(db, "PRAGMA page_size=1024", nullptr, nullptr, nullptr);
        code != SQLITE_OK) {
      error = store->error_of(code, "setting the page size");
      return nullptr;
    }
  }
  std::string mode;
  if (int code = query_text(db, "PRAGMA journal_mode=WAL", mode); code != SQLITE_OK) {
    error = store->error_of(code, "switching to WAL mode");
    return nullptr;
  }
  if (mode != "wal") {
    error = StoreError{StoreFailure::other, 0, 0, "switching to WAL mode",
                       "the file stays in journal mode \"" + mode + "\""};
    return nullptr;
  }
  // secure_delete off: Debian builds SQLite with it on, which zeroes the pages of every curve
  // dropped (one per travel once curves_kept are kept) and so writes each curve twice more (the
  // log, then the checkpoint): record-bench measured 201 kB a travel with it, 106 kB without.
  // wal_autocheckpoint: a checkpoint (and its fsyncs) after about 4 MiB of log as with SQLite's
  // default of 1000 pages of 4 KiB, so the counters' and aggregates' pages, written by every
  // travel, reach the file once per checkpoint, not once per ten travels.
  // journal_size_limit: the log file shrinks back to 4 MiB after a checkpoint.
  std::string pragmas =
      "PRAGMA synchronous=FULL; PRAGMA secure_delete=OFF; PRAGMA wal_autocheckpoint=4000; "
      "PRAGMA journal_size_limit=4194304;";
  if (options.max_bytes > 0) {
    std::int64_t page_size = 1024;
    query_int(db, "PRAGMA page_size", page_size);
    const std::int64_t pages = std::max<std::int64_t>(options.max_bytes / page_size, 1);
    pragmas += "PRAGMA max_page_count=" + std::to_string(pages) + ";";
  }
  if (int code = sqlite3_exec(db, pragmas.c_str(), nullptr, nullptr, nullptr); code != SQLITE_OK) {
    error = store->error_of(code, "setting the connection's pragmas");
    return nullptr;
  }
  // The io thread must not stall on another process's lock (an sqlite3 shell on the board, say)
  // for longer than a cycle of its own work.
  sqlite3_busy_timeout(db, 100);

  if (version == 0) {
    const std::string create =
        "BEGIN IMMEDIATE;" + std::string(kSchema) +
        "INSERT INTO meta(key, value) VALUES('since_unix_ms', " + std::to_string(now_unix_ms) +
        "); PRAGMA user_version=" + std::to_string(kSchemaVersion) + "; COMMIT;";
    if (int code = sqlite3_exec(db, create.c_str(), nullptr, nullptr, nullptr); code != SQLITE_OK) {
      error = store->error_of(code, "creating the record's tables");
      sqlite3_exec(db, "ROLLBACK", nullptr, nullptr, nullptr);
      return nullptr;
    }
  }
  if (!store->prepare_all(error)) return nullptr;

  std::int64_t since = now_unix_ms;
  if (int code = query_int(db, "SELECT value FROM meta WHERE key = 'since_unix_ms'", since);
      code != SQLITE_OK) {
    error = store->error_of(code, "reading when the record began");
    return nullptr;
  }
  store->since_unix_ms_ = since;

  // The newest travel (for the relevel mark) and the id range kept (ids only grow, and only the
  // oldest go, so the range is the count).
  sqlite3_stmt* s = nullptr;
  int code = sqlite3_prepare_v2(
      db,
      "SELECT (SELECT min(id) FROM travels), id, coalesce(end_floor, to_floor) FROM travels "
      "ORDER BY id DESC LIMIT 1",
      -1, &s, nullptr);
  if (code == SQLITE_OK) {
    code = sqlite3_step(s);
    if (code == SQLITE_ROW) {
      store->first_id_ = sqlite3_column_int64(s, 0);
      store->last_id_ = sqlite3_column_int64(s, 1);
      const auto floor = column_optional(s, 2);
      if (floor) store->last_floor_ = static_cast<int>(*floor);
      code = SQLITE_OK;
    } else if (code == SQLITE_DONE) {
      code = SQLITE_OK;
    }
  }
  sqlite3_finalize(s);
  if (code != SQLITE_OK) {
    error = store->error_of(code, "reading the newest travel");
    return nullptr;
  }
  return store;
}

bool Store::prepare(Statement& statement, std::string_view sql, StoreError& error) {
  sqlite3_stmt* s = nullptr;
  const int code = sqlite3_prepare_v3(db_, sql.data(), static_cast<int>(sql.size()),
                                      SQLITE_PREPARE_PERSISTENT, &s, nullptr);
  if (code != SQLITE_OK) {
    error = error_of(code, "preparing the record's statements");
    // A version-1 record without a version-1 table was altered by hand: not ours to repair.
    if (error.failure == StoreFailure::other) error.failure = StoreFailure::foreign;
    return false;
  }
  statement = Statement(s);
  return true;
}

bool Store::prepare_all(StoreError& error) {
  return prepare(begin_, "BEGIN IMMEDIATE", error) && prepare(commit_, "COMMIT", error) &&
         prepare(rollback_, "ROLLBACK", error) &&
         prepare(insert_travel_,
                 "INSERT INTO travels(start_unix_ms, end_unix_ms, start_mono_ms, end_mono_ms, "
                 "from_floor, to_floor, end_floor, kind, arrived, cause, duration_ms, "
                 "top_speed_mm_s, stop_error_mm, relevel_followed) "
                 "VALUES(?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11, ?12, ?13, 0)",
                 error) &&
         prepare(insert_curve_, "INSERT INTO curves(travel_id, curve) VALUES(?1, ?2)", error) &&
         prepare(prune_travels_, "DELETE FROM travels WHERE id <= ?1", error) &&
         prepare(prune_curves_, "DELETE FROM curves WHERE travel_id <= ?1", error) &&
         prepare(mark_relevel_, "UPDATE travels SET relevel_followed = 1 WHERE id = ?1", error) &&
         prepare(upsert_day_floor_,
                 "INSERT INTO day_floor(day, floor, arrivals, errors, error_sum_mm, worst_mm, "
                 "travels, travel_ms) VALUES(?1, ?2, 1, ?3, ?4, ?5, ?6, ?7) "
                 "ON CONFLICT(day, floor) DO UPDATE SET arrivals = arrivals + 1, "
                 "errors = errors + excluded.errors, "
                 "error_sum_mm = error_sum_mm + excluded.error_sum_mm, "
                 "worst_mm = CASE WHEN excluded.worst_mm IS NOT NULL AND (worst_mm IS NULL OR "
                 "abs(excluded.worst_mm) > abs(worst_mm)) THEN excluded.worst_mm "
                 "ELSE worst_mm END, "
                 "travels = travels + excluded.travels, travel_ms = travel_ms + excluded.travel_ms",
                 error) &&
         prepare(upsert_day_pair_,
                 "INSERT INTO day_pair(day, from_floor, to_floor, travels, travel_ms) "
                 "VALUES(?1, ?2, ?3, 1, ?4) ON CONFLICT(day, from_floor, to_floor) DO UPDATE SET "
                 "travels = travels + 1, travel_ms = travel_ms + excluded.travel_ms",
                 error) &&
         prepare(upsert_counter_,
                 "INSERT INTO counters(name, value) VALUES(?1, ?2) "
                 "ON CONFLICT(name) DO UPDATE SET value = excluded.value",
                 error) &&
         prepare(upsert_floor_,
                 "INSERT OR REPLACE INTO floors(floor, arrivals, errors, error_sum_mm, worst_mm, "
                 "histogram) VALUES(?1, ?2, ?3, ?4, ?5, ?6)",
                 error) &&
         prepare(insert_reset_, "INSERT INTO resets(at_unix_ms, who, names) VALUES(?1, ?2, ?3)",
                 error) &&
         prepare(trend_days_,
                 "SELECT day, floor, arrivals, errors, error_sum_mm, worst_mm, travels, travel_ms "
                 "FROM day_floor WHERE day >= ?1 AND day < ?2 ORDER BY day, floor",
                 error) &&
         prepare(trend_days_floor_,
                 "SELECT day, floor, arrivals, errors, error_sum_mm, worst_mm, travels, travel_ms "
                 "FROM day_floor WHERE day >= ?1 AND day < ?2 AND floor = ?3 ORDER BY day, floor",
                 error) &&
         prepare(trend_pairs_,
                 "SELECT day, from_floor, to_floor, travels, travel_ms FROM day_pair "
                 "WHERE day >= ?1 AND day < ?2 ORDER BY day, from_floor, to_floor",
                 error) &&
         prepare(trend_pairs_floor_,
                 "SELECT day, from_floor, to_floor, travels, travel_ms FROM day_pair "
                 "WHERE day >= ?1 AND day < ?2 AND (from_floor = ?3 OR to_floor = ?3) "
                 "ORDER BY day, from_floor, to_floor",
                 error);
}

std::int64_t Store::travel_count() const noexcept {
  return last_id_ >= first_id_ ? last_id_ - first_id_ + 1 : 0;
}

bool Store::load(Counters& counters, StoreError& error) {
  sqlite3_stmt* s = nullptr;
  auto fail = [&](int code, std::string_view doing) {
    error = error_of(code, doing);
    sqlite3_finalize(s);
    return false;
  };
  int code = sqlite3_prepare_v2(db_, "SELECT name, value FROM counters", -1, &s, nullptr);
  if (code != SQLITE_OK) return fail(code, "reading the counters");
  while ((code = sqlite3_step(s)) == SQLITE_ROW) {
    counters.restore_value(column_text(s, 0), sqlite3_column_int64(s, 1));
  }
  if (code != SQLITE_DONE) return fail(code, "reading the counters");
  sqlite3_finalize(s);
  s = nullptr;

  code = sqlite3_prepare_v2(
      db_, "SELECT floor, arrivals, errors, error_sum_mm, worst_mm, histogram FROM floors", -1, &s,
      nullptr);
  if (code != SQLITE_OK) return fail(code, "reading the floors' counters");
  while ((code = sqlite3_step(s)) == SQLITE_ROW) {
    const std::int64_t floor = sqlite3_column_int64(s, 0);
    const auto* bytes = static_cast<const unsigned char*>(sqlite3_column_blob(s, 5));
    const auto size = static_cast<std::size_t>(sqlite3_column_bytes(s, 5));
    FloorCounters kept;
    kept.arrivals = sqlite3_column_int64(s, 1);
    if (size != kHistogramBytes || bytes == nullptr ||
        !kept.stop_error.restore(sqlite3_column_int64(s, 2), sqlite3_column_int64(s, 3),
                                 column_optional(s, 4), decode_histogram(bytes))) {
      error = StoreError{StoreFailure::foreign, 0, 0, "reading the floors' counters",
                         "the row of floor " + std::to_string(floor) +
                             " has a stopping-error histogram that does not fit its count (" +
                             std::to_string(size) + " bytes, " + std::to_string(kHistogramBytes) +
                             " expected)"};
      sqlite3_finalize(s);
      return false;
    }
    counters.restore_floor(static_cast<int>(floor), kept);
  }
  if (code != SQLITE_DONE) return fail(code, "reading the floors' counters");
  sqlite3_finalize(s);
  s = nullptr;

  code = sqlite3_prepare_v2(db_, "SELECT id, at_unix_ms, who, names FROM resets ORDER BY id", -1,
                            &s, nullptr);
  if (code != SQLITE_OK) return fail(code, "reading the resets");
  while ((code = sqlite3_step(s)) == SQLITE_ROW) {
    ResetEntry entry{sqlite3_column_int64(s, 1), column_text(s, 2), {}};
    const nlohmann::json names = nlohmann::json::parse(column_text(s, 3), nullptr, false);
    if (!names.is_array() ||
        !std::all_of(names.begin(), names.end(), [](const auto& n) { return n.is_string(); })) {
      error = StoreError{StoreFailure::foreign, 0, 0, "reading the resets",
                         "reset " + std::to_string(sqlite3_column_int64(s, 0)) +
                             ": names is not a JSON array of texts"};
      sqlite3_finalize(s);
      return false;
    }
    for (const auto& n : names) entry.names.push_back(n.get<std::string>());
    counters.restore_reset(std::move(entry));
  }
  if (code != SQLITE_DONE) return fail(code, "reading the resets");
  sqlite3_finalize(s);
  return true;
}

bool Store::begin(std::string_view doing, StoreError& error) {
  if (const int code = run(begin_.get()); code != SQLITE_OK) {
    error = error_of(code, doing);
    return false;
  }
  return true;
}

bool Store::commit(std::string_view doing, StoreError& error) {
  if (const int code = run(commit_.get()); code != SQLITE_OK) {
    error = error_of(code, doing);
    rollback();
    return false;
  }
  return true;
}

void Store::rollback() {
  if (!sqlite3_get_autocommit(db_)) run(rollback_.get());
}

bool Store::write_changed_counters(Counters& counters, StoreError& error) {
  sqlite3_stmt* s = upsert_counter_.get();
  for (const std::string& name : counters.changed_names()) {
    bind_param(s, 1, name);
    bind_param(s, 2, counters.value(name));
    if (const int code = run(s); code != SQLITE_OK) {
      error = error_of(code, "writing the counters");
      return false;
    }
  }
  s = upsert_floor_.get();
  for (int floor : counters.changed_floors()) {
    const FloorCounters& kept = counters.floors().at(floor);
    const std::string histogram = encode_histogram(kept.stop_error.buckets());
    bind_param(s, 1, std::int64_t{floor});
    bind_param(s, 2, kept.arrivals);
    bind_param(s, 3, kept.stop_error.count());
    bind_param(s, 4, kept.stop_error.sum_mm());
    bind_param(s, 5, kept.stop_error.worst_mm());
    bind_blob(s, 6, histogram.data(), histogram.size());
    if (const int code = run(s); code != SQLITE_OK) {
      error = error_of(code, "writing the floors' counters");
      return false;
    }
  }
  return true;
}

bool Store::insert_travel(Travel& t, StoreError& error) {
  auto fail = [&](int code) {
    error = error_of(code, "writing a travel");
    return false;
  };
  sqlite3_stmt* s = insert_travel_.get();
  bind_param(s, 1, t.start_unix_ms);
  bind_param(s, 2, t.end_unix_ms);
  bind_param(s, 3, t.start_mono_ms);
  bind_param(s, 4, t.end_mono_ms);
  bind_param(s, 5, t.from_floor);
  bind_param(s, 6, t.to_floor);
  bind_param(s, 7, t.end_floor);
  bind_param(s, 8, std::string_view(t.kind));
  bind_param(s, 9, std::int64_t{t.arrived ? 1 : 0});
  bind_param(s, 10, std::string_view(t.cause));
  bind_param(s, 11, t.duration_ms);
  bind_param(s, 12,
             t.top_speed_mm_s ? std::optional<std::int64_t>(*t.top_speed_mm_s) : std::nullopt);
  bind_param(s, 13, t.stop_error_mm);
  if (const int code = run(s); code != SQLITE_OK) return fail(code);
  t.id = sqlite3_last_insert_rowid(db_);
  t.relevel_followed = false;

  // A relevel right after a travel to the same floor says that travel's stop needed a
  // correction: the mark goes on that travel's row in the relevel's transaction.
  const std::optional<int> floor = t.end_floor ? t.end_floor : t.to_floor;
  if (is_relevel(t.kind) && last_id_ > 0 && floor && last_floor_ == floor) {
    bind_param(mark_relevel_.get(), 1, last_id_);
    if (const int code = run(mark_relevel_.get()); code != SQLITE_OK) return fail(code);
  }

  if (options_.curves_kept > 0 && !t.curve_json.empty()) {
    bind_param(insert_curve_.get(), 1, t.id);
    bind_param(insert_curve_.get(), 2, std::string_view(t.curve_json));
    if (const int code = run(insert_curve_.get()); code != SQLITE_OK) return fail(code);
  }
  // Only the newest curves_kept travels keep a curve and only the newest max_travels travels
  // stay (issue #42); ids only grow, so "older" is "a smaller id".
  const auto curves_kept = static_cast<std::int64_t>(options_.curves_kept);
  if (t.id - curves_kept >= 1) {
    bind_param(prune_curves_.get(), 1, t.id - curves_kept);
    if (const int code = run(prune_curves_.get()); code != SQLITE_OK) return fail(code);
  }
  if (options_.max_travels > 0 && t.id - options_.max_travels >= first_id_) {
    bind_param(prune_travels_.get(), 1, t.id - options_.max_travels);
    if (const int code = run(prune_travels_.get()); code != SQLITE_OK) return fail(code);
  }

  // The trend's daily aggregates: arrivals and stopping error at the floor where the car
  // stopped, and the floor-to-floor time of ordinary travels between two floors.
  if (t.arrived && t.end_floor) {
    const std::int64_t day = utc_day(t.start_unix_ms);
    const bool floor_to_floor = is_floor_to_floor(t);
    s = upsert_day_floor_.get();
    bind_param(s, 1, day);
    bind_param(s, 2, std::int64_t{*t.end_floor});
    bind_param(s, 3, std::int64_t{t.stop_error_mm ? 1 : 0});
    bind_param(s, 4, t.stop_error_mm.value_or(0));
    bind_param(s, 5, t.stop_error_mm);
    bind_param(s, 6, std::int64_t{floor_to_floor ? 1 : 0});
    bind_param(s, 7, floor_to_floor ? t.duration_ms : 0);
    if (const int code = run(s); code != SQLITE_OK) return fail(code);
    if (floor_to_floor) {
      s = upsert_day_pair_.get();
      bind_param(s, 1, day);
      bind_param(s, 2, std::int64_t{*t.from_floor});
      bind_param(s, 3, std::int64_t{*t.end_floor});
      bind_param(s, 4, t.duration_ms);
      if (const int code = run(s); code != SQLITE_OK) return fail(code);
    }
  }
  return true;
}

bool Store::write_travels(std::span<Travel> travels, Counters& counters, StoreError& error) {
  if (!begin("writing a travel", error)) return false;
  // What the transaction changes in memory, put back if it does not commit.
  const std::int64_t first_id = first_id_, last_id = last_id_;
  const std::optional<int> last_floor = last_floor_;
  auto undo = [&] {
    rollback();
    first_id_ = first_id;
    last_id_ = last_id;
    last_floor_ = last_floor;
    for (Travel& t : travels) t.id = 0;
    return false;
  };
  for (Travel& t : travels) {
    if (!insert_travel(t, error)) return undo();
    if (last_id_ == 0) first_id_ = t.id;
    last_id_ = t.id;
    last_floor_ = t.end_floor ? t.end_floor : t.to_floor;
    if (options_.max_travels > 0) first_id_ = std::max(first_id_, t.id - options_.max_travels + 1);
  }
  if (!write_changed_counters(counters, error)) return undo();
  if (!commit("writing a travel", error)) return undo();
  counters.mark_written();
  return true;
}

template <typename Body>
bool Store::write_with_counters(std::string_view doing, Counters& counters, StoreError& error,
                                Body body) {
  if (!begin(doing, error)) return false;
  if (!body() || !write_changed_counters(counters, error)) {
    rollback();
    return false;
  }
  if (!commit(doing, error)) return false;
  counters.mark_written();
  return true;
}

bool Store::write_counters(Counters& counters, StoreError& error) {
  if (!counters.changed()) return true;
  return write_with_counters("writing the counters", counters, error, [] { return true; });
}

bool Store::write_reset(const ResetEntry& reset, Counters& counters, StoreError& error) {
  const std::string names = nlohmann::json(reset.names).dump();
  return write_with_counters("writing a reset", counters, error, [&] {
    sqlite3_stmt* s = insert_reset_.get();
    bind_param(s, 1, reset.at_unix_ms);
    bind_param(s, 2, std::string_view(reset.who));
    bind_param(s, 3, std::string_view(names));
    if (const int code = run(s); code != SQLITE_OK) {
      error = error_of(code, "writing a reset");
      return false;
    }
    return true;
  });
}

}  // namespace liftd::record
