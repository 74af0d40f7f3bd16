// The lift's record end to end (docs/api.md "The lift's record", issue #42), on every drive kind
// alike: a travel is counted and kept with its floors, outcome and stopping error; a daemon
// started again on the same file finds the counters and the travel and counts on from them; a
// record that cannot be written is off with a reason, and the lift goes on working; the record's
// commands refuse bad requests and say what is allowed.
#include <gtest/gtest.h>
#include <sqlite3.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "e2e/drive_cases.hpp"
#include "e2e/harness.hpp"
#include "e2e/witness.hpp"

namespace liftd::e2e {
namespace {

using namespace std::chrono_literals;

/// A directory of the test's own, beside the daemons' (each Lift removes its own on exit).
class RecordDir {
 public:
  explicit RecordDir(const std::string& name)
      : path_(std::filesystem::temp_directory_path() /
              ("liftd-record-" + std::to_string(::getpid()) + "-" + name)) {
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~RecordDir() {
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
  }
  std::string file() const { return (path_ / "record.db").string(); }
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

json with_record(json config, const std::string& path) {
  config["record"] = {{"path", path}};
  return config;
}

/// A travel to `floor` that finished (the watch stream's end event).
void travel_to(Lift& lift, int floor) {
  ASSERT_TRUE(lift.wait_drive_state("ready")) << lift.status().dump();
  const json r = lift.call({{"cmd", "travel"}, {"floor", floor}});
  ASSERT_TRUE(r.value("ok", false)) << r.dump();
  const json ended = lift.wait_travel_end(40s);
  ASSERT_TRUE(ended.is_object()) << lift.log();
  ASSERT_EQ(ended["data"]["event"], "finished") << ended.dump();
}

/// The `counters` result once the record holds `travels` travels (the travel log completes a
/// travel with its last sample, a step after the travel event).
json counters_once(Lift& lift, std::int64_t travels) {
  json result;
  const auto deadline = std::chrono::steady_clock::now() + 5s;
  do {
    const json r = lift.call({{"cmd", "counters"}});
    EXPECT_TRUE(r.value("ok", false)) << r.dump();
    result = r["result"];
    if (result["counters"].value("travels", 0) >= travels) break;
    std::this_thread::sleep_for(50ms);
  } while (std::chrono::steady_clock::now() < deadline);
  return result;
}

json floor_row(const json& counters, int floor) {
  for (const json& f : counters["floors"]) {
    if (f["floor"] == floor) return f;
  }
  return nullptr;
}

class RecordParity : public ::testing::TestWithParam<DriveCase> {};

TEST_P(RecordParity, ATravelIsCountedKeptAndFoundAgainAfterARestart) {
  judged_unless_stalled([] {
    const DriveCase& c = GetParam();
    RecordDir dir(std::string("parity-") + c.name);
    std::string kind;
    {
      Lift lift(std::string("record-") + c.name, 4, json::object(), {},
                with_record(c.config, dir.file()));
      ASSERT_EQ(lift.setup_error(), "") << lift.log();
      const json status = lift.status();
      EXPECT_EQ(status["record"]["state"], "on") << status.dump();
      EXPECT_EQ(status["record"]["path"], dir.file());
      travel_to(lift, 1);
      const json counters = counters_once(lift, 1);
      EXPECT_EQ(counters["record"], "on");
      EXPECT_EQ(counters["counters"]["travels"], 1) << counters.dump();
      EXPECT_EQ(counters["counters"]["motor_starts"], 1) << counters.dump();
      const json arrived = floor_row(counters, 1);
      ASSERT_TRUE(arrived.is_object()) << counters.dump();
      EXPECT_EQ(arrived["arrivals"], 1);
      EXPECT_EQ(arrived["stop_error_mm"]["count"], 1);

      const json history = lift.call({{"cmd", "history"}});
      ASSERT_TRUE(history.value("ok", false)) << history.dump();
      ASSERT_EQ(history["result"]["travels"].size(), 1U) << history.dump();
      const json& t = history["result"]["travels"][0];
      kind = t["kind"].get<std::string>();
      EXPECT_EQ(counters["counters"]["travels." + kind + ".arrived"], 1) << counters.dump();
      EXPECT_EQ(t["from_floor"], 0) << t.dump();
      EXPECT_EQ(t["to_floor"], 1) << t.dump();
      EXPECT_EQ(t["end_floor"], 1) << t.dump();
      EXPECT_EQ(t["outcome"], "arrived");
      EXPECT_EQ(t["cause"], "arrived");
      ASSERT_TRUE(t["stop_error_mm"].is_number_integer()) << t.dump();
      EXPECT_LE(std::llabs(t["stop_error_mm"].get<std::int64_t>()), 20) << t.dump();
      EXPECT_GT(t["top_speed_mm_s"].get<std::int64_t>(), 100) << t.dump();
      EXPECT_GT(t["duration_ms"].get<std::int64_t>(), 1000) << t.dump();
      // The day's trend: the arrival at floor 1 with its stopping error, and the floor-to-floor
      // time from 0 to 1 (the travel's duration: it is the only one).
      const json trend = lift.call({{"cmd", "trend"}, {"floor", 1}});
      ASSERT_TRUE(trend.value("ok", false)) << trend.dump();
      ASSERT_EQ(trend["result"]["days"].size(), 1U) << trend.dump();
      const json& day = trend["result"]["days"][0];
      EXPECT_EQ(day["arrivals"], 1) << day.dump();
      EXPECT_EQ(day["travel_ms"]["count"], 1) << day.dump();
      EXPECT_EQ(day["travel_ms"]["mean"].get<double>(), t["duration_ms"].get<double>());
      ASSERT_EQ(trend["result"]["pairs"].size(), 1U) << trend.dump();
      EXPECT_EQ(trend["result"]["pairs"][0]["from"], 0);
      EXPECT_EQ(trend["result"]["pairs"][0]["to"], 1);
      // The same travel from the other side of the filters.
      const json none = lift.call({{"cmd", "history"}, {"outcome", "aborted"}});
      EXPECT_TRUE(none["result"]["travels"].empty()) << none.dump();
      const json by_floor = lift.call({{"cmd", "history"}, {"floor", 1}, {"curves", true}});
      ASSERT_EQ(by_floor["result"]["travels"].size(), 1U) << by_floor.dump();
      EXPECT_FALSE(by_floor["result"]["travels"][0]["curve"]["t_ms"].empty()) << by_floor.dump();
    }
    // Started again on the same file: the counters and the travel are there, and count on.
    Lift again(std::string("record-again-") + c.name, 4, json::object(), {},
               with_record(c.config, dir.file()));
    ASSERT_EQ(again.setup_error(), "") << again.log();
    const json kept = counters_once(again, 1);
    EXPECT_EQ(kept["counters"]["travels"], 1) << kept.dump();
    EXPECT_EQ(kept["counters"]["travels." + kind + ".arrived"], 1) << kept.dump();
    // `eta` starts from the travels the record kept (docs/api.md "Arrival times"): the pair
    // 0 -> 1 is known before the car moved again.
    const json eta = again.call({{"cmd", "eta"}});
    ASSERT_TRUE(eta.value("ok", false)) << eta.dump();
    EXPECT_EQ(eta["result"]["basis"]["pairs_learned"], 1) << eta.dump();
    EXPECT_EQ(eta["result"]["floors"][1]["learned"], true) << eta.dump();
    travel_to(again, 2);  // the simulated car starts at the lowest floor again
    const json counted = counters_once(again, 2);
    EXPECT_EQ(counted["counters"]["travels"], 2) << counted.dump();
    const json history = again.call({{"cmd", "history"}});
    ASSERT_EQ(history["result"]["travels"].size(), 2U) << history.dump();
    EXPECT_EQ(history["result"]["travels"][0]["to_floor"], 2) << "newest first";
    EXPECT_GT(history["result"]["travels"][0]["id"], history["result"]["travels"][1]["id"]);
    EXPECT_EQ(history["result"]["travels"][1]["to_floor"], 1);
  });
}

TEST_P(RecordParity, ARecordThatCannotBeWrittenIsOffAndTheLiftGoesOn) {
  judged_unless_stalled([] {
    const DriveCase& c = GetParam();
    // No file can be made under /proc, not even by root.
    Lift lift(std::string("record-off-") + c.name, 4, json::object(), {},
              with_record(c.config, "/proc/liftd-record/record.db"));
    ASSERT_EQ(lift.setup_error(), "") << lift.log();
    const json status = lift.status();
    EXPECT_EQ(status["record"]["state"], "off") << status.dump();
    ASSERT_TRUE(status["record"]["reason"].is_string()) << status.dump();
    EXPECT_NE(status["record"]["reason"].get<std::string>().find("/proc/liftd-record"),
              std::string::npos)
        << status.dump();
    EXPECT_NE(lift.log().find("[event=record_off"), std::string::npos) << lift.log();
    travel_to(lift, 1);
    const json counters = counters_once(lift, 1);
    EXPECT_EQ(counters["record"], "off") << counters.dump();
    EXPECT_EQ(counters["counters"]["travels"], 1) << "counted in memory: " << counters.dump();
    const json history = lift.call({{"cmd", "history"}});
    ASSERT_TRUE(history.value("ok", false)) << history.dump();
    EXPECT_TRUE(history["result"]["travels"].empty()) << history.dump();
    // A reset could not be kept: refused as the lift's state, nothing reset.
    const json reset = lift.call({{"cmd", "counters_reset"}, {"names", {"all"}}});
    EXPECT_EQ(reset["error"]["code"], "not_ready") << reset.dump();
    EXPECT_EQ(counters_once(lift, 1)["counters"]["travels"], 1);
  });
}

INSTANTIATE_TEST_SUITE_P(EveryDriveKind, RecordParity, ::testing::ValuesIn(drive_cases()),
                         drive_case_name);

TEST(RecordParityCases, EveryRegisteredDriveKindHasItsCases) {
  expect_a_case_for_every_kind();
}

/// `PRAGMA integrity_check` of a record file and its `travels` rows.
std::pair<std::string, std::int64_t> check_file(const std::string& file) {
  sqlite3* db = nullptr;
  std::string verdict = "cannot open";
  std::int64_t rows = -1;
  if (sqlite3_open_v2(file.c_str(), &db, SQLITE_OPEN_READONLY, nullptr) == SQLITE_OK) {
    sqlite3_exec(
        db, "PRAGMA integrity_check",
        [](void* out, int, char** values, char**) {
          *static_cast<std::string*>(out) = values[0] != nullptr ? values[0] : "null";
          return 0;
        },
        &verdict, nullptr);
    sqlite3_exec(
        db, "SELECT count(*) FROM travels",
        [](void* out, int, char** values, char**) {
          *static_cast<std::int64_t*>(out) = std::atoll(values[0]);
          return 0;
        },
        &rows, nullptr);
  }
  sqlite3_close(db);
  return {verdict, rows};
}

// SIGKILL in the middle of a travel: what was committed (the travel before) is all there, the
// file passes its integrity check, and the next start counts on. (tests/record kills a writer at
// random moments a hundred times; this is the daemon itself.)
TEST(RecordFile, AKillMidTravelLosesNothingThatWasKept) {
  judged_unless_stalled([] {
    RecordDir dir("kill");
    {
      Lift lift("record-kill", 4, json::object(), {}, with_record(json::object(), dir.file()));
      ASSERT_EQ(lift.setup_error(), "") << lift.log();
      travel_to(lift, 1);
      (void)counters_once(lift, 1);
      ASSERT_TRUE(lift.call({{"cmd", "travel"}, {"floor", 3}}).value("ok", false));
      ASSERT_TRUE(lift.wait_moved(1000, 300)) << lift.status().dump();
      ASSERT_TRUE(lift.stop_daemon(SIGKILL, 5s).has_value());
    }
    const auto [verdict, rows] = check_file(dir.file());
    EXPECT_EQ(verdict, "ok");
    EXPECT_EQ(rows, 1);
    Lift again("record-kill-again", 4, json::object(), {}, with_record(json::object(), dir.file()));
    ASSERT_EQ(again.setup_error(), "") << again.log();
    EXPECT_EQ(again.status()["record"]["state"], "on");
    EXPECT_EQ(counters_once(again, 1)["counters"]["travels"], 1);
  });
}

/// Starts a lift on `file` as it is, and expects the record off with a reason that holds `says`.
json expect_record_off(const std::string& name, const std::string& file, const std::string& says) {
  Lift lift(name, 4, json::object(), {}, with_record(json::object(), file));
  EXPECT_EQ(lift.setup_error(), "") << lift.log();
  const json record = lift.status()["record"];
  EXPECT_EQ(record["state"], "off") << record.dump();
  EXPECT_NE(record.value("reason", "").find(says), std::string::npos) << record.dump();
  EXPECT_NE(lift.log().find("[event=record_off"), std::string::npos) << lift.log();
  // The lift goes on working.
  travel_to(lift, 1);
  return record;
}

std::string read_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// A file that is no database is kept aside under a new name, byte for byte, and never written.
TEST(RecordFile, ACorruptFileIsKeptAsideAndTheRecordIsOff) {
  RecordDir dir("corrupt");
  const std::string garbage(8192, '\x5a');
  {
    std::ofstream out(dir.file(), std::ios::binary);
    out << garbage;
  }
  (void)expect_record_off("record-corrupt", dir.file(), "is damaged");
  std::vector<std::filesystem::path> aside;
  for (const auto& entry : std::filesystem::directory_iterator(dir.path())) {
    if (entry.path().filename().string().rfind("record.db.corrupt-", 0) == 0) {
      aside.push_back(entry.path());
    }
  }
  ASSERT_EQ(aside.size(), 1U);
  EXPECT_EQ(read_bytes(aside[0].string()), garbage);
}

// A record from a newer liftd (a higher schema version) is left as it is.
TEST(RecordFile, ARecordOfANewerVersionIsLeftAloneAndTheRecordIsOff) {
  RecordDir dir("newer");
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(dir.file().c_str(), &db), SQLITE_OK);
  ASSERT_EQ(sqlite3_exec(db, "PRAGMA user_version = 99; CREATE TABLE later(x);", nullptr, nullptr,
                         nullptr),
            SQLITE_OK);
  sqlite3_close(db);
  const std::string before = read_bytes(dir.file());
  (void)expect_record_off("record-newer", dir.file(), "written by a newer liftd");
  EXPECT_EQ(read_bytes(dir.file()), before);
}

// Requests the record's commands refuse, each with the field and what is allowed; none changes
// anything.
TEST(RecordCommands, BadRequestsAreRefusedAndSayWhatIsAllowed) {
  RecordDir dir("bad-requests");
  Lift lift("record-bad", 4, json::object(), {}, with_record(json::object(), dir.file()));
  ASSERT_EQ(lift.setup_error(), "") << lift.log();
  struct Case {
    json request;
    const char* field;
    const char* says;
  };
  const Case cases[] = {
      {{{"cmd", "history"}, {"from", "yesterday"}}, "from", "YYYY-MM-DD"},
      {{{"cmd", "history"}, {"from", "2026-02-30"}}, "from", "YYYY-MM-DD"},
      {{{"cmd", "history"}, {"to", "2026-11-01T08:00:00"}}, "to", "YYYY-MM-DDTHH:MM:SS"},
      {{{"cmd", "history"}, {"from", "2026-11-02"}, {"to", "2026-11-01"}}, "from", "before"},
      {{{"cmd", "history"}, {"limit", 0}}, "limit", "1..10000"},
      {{{"cmd", "history"}, {"outcome", "crashed"}}, "outcome", "arrived"},
      {{{"cmd", "trend"}, {"floor", -1}}, "floor", "0..63"},
      {{{"cmd", "counters_reset"}, {"names", json::array()}}, "names", "array of 1..256"},
      {{{"cmd", "counters_reset"}, {"names", "all"}}, "names", "array of 1..256"},
      {{{"cmd", "counters_reset"}, {"names", {"no_such_counter"}}}, "names", "no_such_counter"},
  };
  for (const Case& c : cases) {
    const json r = lift.call(c.request);
    ASSERT_TRUE(r.is_object()) << c.request.dump();
    EXPECT_FALSE(r.value("ok", true)) << c.request.dump() << " -> " << r.dump();
    EXPECT_EQ(r["error"]["code"], "bad_request") << c.request.dump() << " -> " << r.dump();
    EXPECT_EQ(r["error"].value("field", ""), c.field) << c.request.dump() << " -> " << r.dump();
    EXPECT_NE(r["error"].value("message", "").find(c.says), std::string::npos)
        << c.request.dump() << " -> " << r.dump();
  }
  // A good reset is recorded with who asked.
  const json reset = lift.call({{"cmd", "counters_reset"}, {"names", {"faults.*"}}});
  ASSERT_TRUE(reset.value("ok", false)) << reset.dump();
  const json after = lift.call({{"cmd", "counters"}});
  ASSERT_EQ(after["result"]["resets"].size(), 1U) << after.dump();
  EXPECT_EQ(after["result"]["resets"][0]["names"], json::array({"faults.*"}));
  EXPECT_NE(after["result"]["resets"][0]["who"].get<std::string>().find("uid "), std::string::npos);
}

}  // namespace
}  // namespace liftd::e2e
