// The lift's record in SQLite (issue #42): the schema (version 1), the write transactions
// (one per travel, one per counters write, one per reset), the queries, and what an SQLite error
// means for the record. Every statement is prepared once at open and kept.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <span>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

#include "record/counters.hpp"
#include "record/lift_record.hpp"

struct sqlite3;
struct sqlite3_stmt;

namespace liftd::record {

/// The schema version this build writes (PRAGMA user_version).
inline constexpr int kSchemaVersion = 1;

/// What went wrong with the record's file, and so what the record does about it.
enum class StoreFailure {
  cannot_open,   ///< the file cannot be opened or created (directory missing, not a directory)
  read_only,     ///< the file or its directory cannot be written
  full,          ///< the disk (or the record's max_bytes) is full
  io,            ///< the storage failed a read or write
  corrupt,       ///< the file is damaged or not a database: it is moved aside
  newer_schema,  ///< written by a newer liftd: left untouched
  foreign,       ///< a database, but not a liftd record, or a row that makes no sense: untouched
  busy,          ///< another process holds the file's write lock
  other,         ///< anything else SQLite reports
};

struct StoreError {
  StoreFailure failure = StoreFailure::other;
  int sqlite_code = 0;   ///< extended result code (0: not from SQLite)
  int system_errno = 0;  ///< the errno behind an I/O error (0: none)
  std::string doing;     ///< what the record was doing, e.g. "writing a travel"
  std::string detail;    ///< SQLite's message, or what was wrong with the content
};

struct StoreOptions {
  std::int64_t max_travels = 1'000'000;
  std::size_t curves_kept = 100;
  std::int64_t max_bytes = 0;
};

/// A prepared statement, finalized when it goes.
class Statement {
 public:
  Statement() = default;
  explicit Statement(sqlite3_stmt* statement) : statement_(statement) {}
  ~Statement();
  Statement(Statement&& other) noexcept;
  Statement& operator=(Statement&& other) noexcept;
  Statement(const Statement&) = delete;
  Statement& operator=(const Statement&) = delete;
  sqlite3_stmt* get() const noexcept { return statement_; }

 private:
  sqlite3_stmt* statement_ = nullptr;
};

class Store {
 public:
  /// Opens or creates the record at `path`: checks the schema version and the file
  /// (PRAGMA quick_check), switches to WAL and creates the schema in a new file. nullptr and
  /// `error` on failure; a corrupt file is left for the caller to move aside (after the store
  /// is gone: the connection is closed without a checkpoint, so the file stays as found).
  static std::unique_ptr<Store> open(const std::string& path, const StoreOptions& options,
                                     std::int64_t now_unix_ms, StoreError& error);
  ~Store();
  Store(const Store&) = delete;
  Store& operator=(const Store&) = delete;

  /// When the record was created (ms since the Unix epoch).
  std::int64_t since_unix_ms() const noexcept { return since_unix_ms_; }
  /// Travel rows kept.
  std::int64_t travel_count() const noexcept;

  /// Loads the kept counters, floors and resets.
  bool load(Counters& counters, StoreError& error);

  /// Writes `travels` (ids set) and every changed counter in ONE transaction, with the pruning
  /// (max_travels, curves_kept), the relevel mark and the daily aggregates. The daemon writes one
  /// travel at a time; several at once are for filling a record (the benchmark).
  bool write_travels(std::span<Travel> travels, Counters& counters, StoreError& error);
  /// Writes every changed counter in one transaction.
  bool write_counters(Counters& counters, StoreError& error);
  /// Writes the reset row and the counters it changed in one transaction.
  bool write_reset(const ResetEntry& reset, Counters& counters, StoreError& error);

  /// The history answer for a checked query (see LiftRecord::history_json).
  bool history(const HistoryQuery& query, nlohmann::json& answer, StoreError& error);
  /// The trend answer (see LiftRecord::trend_json).
  bool trend(const TrendQuery& query, nlohmann::json& answer, StoreError& error);

  /// A corrupt file: close without the checkpoint SQLite does on close, so the file's bytes
  /// stay as they were found for whoever examines it.
  void skip_checkpoint_on_close();

 private:
  Store(sqlite3* db, std::string path, const StoreOptions& options);
  bool prepare_all(StoreError& error);
  bool prepare(Statement& statement, std::string_view sql, StoreError& error);
  bool write_changed_counters(Counters& counters, StoreError& error);
  bool insert_travel(Travel& t, StoreError& error);
  bool begin(std::string_view doing, StoreError& error);
  bool commit(std::string_view doing, StoreError& error);
  void rollback();
  /// One write transaction: `body()` (false: it failed and set `error`), then the counters that
  /// changed; rolled back on any failure, the counters marked written on success.
  template <typename Body>
  bool write_with_counters(std::string_view doing, Counters& counters, StoreError& error,
                           Body body);
  StoreError error_of(int code, std::string_view doing) const;

  sqlite3* db_;
  std::string path_;
  StoreOptions options_;
  std::int64_t since_unix_ms_ = 0;
  std::int64_t first_id_ = 1;  ///< oldest travel id kept
  std::int64_t last_id_ = 0;   ///< newest travel id (0: none yet)
  /// The newest travel's floor (end floor, else target): a relevel there marks that travel.
  std::optional<int> last_floor_;

  Statement begin_, commit_, rollback_;
  Statement insert_travel_, insert_curve_, prune_travels_, prune_curves_, mark_relevel_;
  Statement upsert_day_floor_, upsert_day_pair_;
  Statement upsert_counter_, upsert_floor_, insert_reset_;
  Statement trend_days_, trend_days_floor_, trend_pairs_, trend_pairs_floor_;
  /// History statements, one per combination of filters asked (prepared when first asked).
  std::map<unsigned, Statement> history_;
};

}  // namespace liftd::record
