// record-bench: the lift's record (lib/record) at the size issue #42 asks it to hold. It fills a
// record with one million travels spread over a year (random floors of a 10-floor building) in
// a temporary file, then times
//   - opening it (the integrity check at each start reads the whole file),
//   - `history` of one floor in one month (the issue's bound: under 50 ms),
//   - `trend` of one month (the issue's bound: under 200 ms),
// each the median of several runs, and measures what normal operation writes to the storage:
// 1000 travels through LiftRecord, one transaction each, each with the curve of a 10 s travel
// as the travel log writes it (700 samples of about 60 bytes), and an hour of idle ticks. It
// exits 1 if a bound is missed.
//
//   record-bench [--dir DIR] [--travels N] [--keep]
//     --dir DIR     where the temporary record goes (default $TMPDIR or /tmp)
//     --travels N   travels in the filled record (default 1000000)
//     --keep        leave the record file behind
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "record/counters.hpp"
#include "record/lift_record.hpp"
#include "record/store.hpp"

namespace {

using namespace liftd::record;
using Clock = std::chrono::steady_clock;

constexpr std::int64_t kYearMs = 365LL * 86'400'000;
constexpr std::int64_t kMonthMs = 30LL * 86'400'000;
/// 2026-01-01T00:00:00Z: the filled year starts here.
constexpr std::int64_t kYearStart = 1'767'225'600'000;
constexpr int kFloors = 10;
constexpr double kHistoryBoundMs = 50.0;  // issue #42
constexpr double kTrendBoundMs = 200.0;   // issue #42
constexpr int kRuns = 9;

double ms_since(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

double median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  return values[values.size() / 2];
}

/// The median time of `kRuns` calls of `body` (after one call that warms the page cache as a
/// board's running daemon would have it).
double median_ms(const std::function<void()>& body) {
  body();
  std::vector<double> times;
  for (int i = 0; i < kRuns; ++i) {
    const auto start = Clock::now();
    body();
    times.push_back(ms_since(start));
  }
  return median(times);
}

/// A line of /proc/self/io ("wchar", "write_bytes"): bytes this process wrote (-1 if unknown).
std::int64_t proc_io(const std::string& key) {
  std::ifstream in("/proc/self/io");
  std::string name;
  std::int64_t value = 0;
  while (in >> name >> value) {
    if (name == key + ":") return value;
  }
  return -1;
}

/// The curve of a 10 s DCP4 travel as the travel log keeps it for the record
/// (TravelLog::curve_columns): 700 samples of 15 ms in columns, about 24 bytes a sample (a real
/// 9.6 s travel of the simulated lift: 628 samples, 15 kB).
std::string typical_curve(std::mt19937& random) {
  std::uniform_int_distribution<int> jitter(-3, 3);
  constexpr int kSamples = 700;
  std::string t_ms;
  std::string position;
  std::string speed;
  std::string remaining;
  std::string command;
  std::string status;
  for (int i = 0; i < kSamples; ++i) {
    const char* sep = i > 0 ? "," : "";
    t_ms += sep + std::to_string(i * 15);  // DCP cycles
    position += sep + std::to_string(3000 + i * 9 + jitter(random));
    speed += sep + std::to_string(std::min({i * 20, 1000, (kSamples - i) * 20}));
    remaining += sep + std::to_string(9300 - i * 9);
    command += sep + std::to_string(i < 10 || i > kSamples - 10 ? 0 : 5);
    status += sep + std::to_string(i < 10 || i > kSamples - 10 ? 17 : 99);
  }
  return R"({"stride":1,"command_bits":["B0_enable","B1_travel","B2_stop","B3_speed","B4_down",)"
         R"("B5_change","B6_desired","B7_reply_error"],"status_bits":["S0_ready",)"
         R"("S1_travel_active","S2_advance_warning","S3_general_fault","S4_below_levelling",)"
         R"("S5_accepted","S6_brake_open","S7_message_error"],"t_ms":[)" +
         t_ms + R"(],"position_mm":[)" + position + R"(],"speed_mm_s":[)" + speed +
         R"(],"remaining_mm":[)" + remaining + R"(],"command":[)" + command + R"(],"status":[)" +
         status + "]}";
}

/// A travel of the filled year: mostly ordinary travels that arrive, some relevels, some aborts.
Travel random_travel(std::mt19937& random, std::int64_t start_unix_ms, std::int64_t mono_ms) {
  std::uniform_int_distribution<int> floor(0, kFloors - 1);
  std::uniform_int_distribution<int> percent(0, 99);
  std::normal_distribution<double> error(0.0, 3.0);
  std::uniform_int_distribution<int> duration(3000, 15000);
  Travel t;
  t.start_unix_ms = start_unix_ms;
  t.start_mono_ms = mono_ms;
  t.from_floor = floor(random);
  int to = floor(random);
  if (to == *t.from_floor) to = (to + 1) % kFloors;
  t.to_floor = to;
  t.duration_ms = duration(random);
  t.end_unix_ms = t.start_unix_ms + t.duration_ms;
  t.end_mono_ms = t.start_mono_ms + t.duration_ms;
  const int roll = percent(random);
  t.kind = roll < 3 ? "relevel" : "travel";
  if (t.kind == "relevel") t.from_floor = t.to_floor;
  t.arrived = roll < 98;
  t.cause = t.arrived ? "arrived" : (roll == 98 ? "link_down" : "stop_requested");
  if (t.arrived) {
    t.end_floor = t.to_floor;
    t.stop_error_mm = static_cast<std::int64_t>(std::lround(error(random)));
  }
  t.top_speed_mm_s = 1000;
  return t;
}

bool fill(const std::string& path, std::int64_t travels, std::mt19937& random) {
  StoreError error;
  auto store = Store::open(path, StoreOptions{}, kYearStart, error);
  if (!store) {
    std::fprintf(stderr, "record-bench: cannot create %s: %s: %s\n", path.c_str(),
                 error.doing.c_str(), error.detail.c_str());
    return false;
  }
  Counters counters;
  const std::int64_t spacing = kYearMs / travels;
  std::vector<Travel> batch;
  const auto start = Clock::now();
  for (std::int64_t i = 0; i < travels; ++i) {
    batch.push_back(random_travel(random, kYearStart + i * spacing, i * spacing));
    counters.count_travel(batch.back());
    // One transaction per 10 000 travels: the filling is the benchmark's, not the daemon's way.
    if (batch.size() == 10'000 || i + 1 == travels) {
      if (!store->write_travels(batch, counters, error)) {
        std::fprintf(stderr, "record-bench: filling failed: %s: %s\n", error.doing.c_str(),
                     error.detail.c_str());
        return false;
      }
      batch.clear();
    }
  }
  std::printf("filled:   %lld travels in %.1f s\n", static_cast<long long>(travels),
              ms_since(start) / 1000.0);
  return true;
}

std::int64_t file_size(const std::string& path) {
  struct stat info {};
  return ::stat(path.c_str(), &info) == 0 ? static_cast<std::int64_t>(info.st_size) : 0;
}

}  // namespace

int main(int argc, char** argv) {
  std::string base =
      std::getenv("TMPDIR") && *std::getenv("TMPDIR") ? std::getenv("TMPDIR") : "/tmp";
  std::int64_t travels = 1'000'000;
  bool keep = false;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--dir" && i + 1 < argc) {
      base = argv[++i];
    } else if (arg == "--travels" && i + 1 < argc) {
      travels = std::atoll(argv[++i]);
    } else if (arg == "--keep") {
      keep = true;
    } else {
      std::fprintf(stderr, "usage: record-bench [--dir DIR] [--travels N] [--keep]\n");
      return arg == "--help" ? 0 : 2;
    }
  }
  if (travels < 1000) {
    std::fprintf(stderr, "record-bench: --travels must be at least 1000\n");
    return 2;
  }
  std::string dir = base + "/record-bench-XXXXXX";
  if (::mkdtemp(dir.data()) == nullptr) {
    std::fprintf(stderr, "record-bench: cannot make a directory under %s: %s\n", base.c_str(),
                 std::strerror(errno));
    return 2;
  }
  const std::string path = dir + "/record.db";
  std::mt19937 random(20260101);
  bool ok = fill(path, travels, random);

  if (ok) {
    std::printf("file:     %.1f MB (%.0f bytes a travel)\n",
                static_cast<double>(file_size(path)) / 1e6,
                static_cast<double>(file_size(path)) / static_cast<double>(travels));
    const std::int64_t mono0 = 0;
    const std::int64_t now = kYearStart + kYearMs;
    auto start = Clock::now();
    Options options;
    options.path = path;
    auto record = std::make_unique<LiftRecord>(options, mono0, now);
    std::printf("open:     %.0f ms (with PRAGMA quick_check of the whole file)\n", ms_since(start));
    if (!record->on()) {
      std::fprintf(stderr, "record-bench: the record is off: %s\n",
                   record->status_json().dump().c_str());
      return 1;
    }

    // One floor in one month: the sixth month of the year.
    const std::int64_t month_from = kYearStart + 5 * kMonthMs;
    HistoryQuery history;
    history.from_unix_ms = month_from;
    history.to_unix_ms = month_from + kMonthMs;
    history.floor = 3;
    std::size_t count = 0;
    bool truncated = false;
    const double history_ms = median_ms([&] {
      const auto answer = record->history_json(history);
      count = answer["count"].get<std::size_t>();
      truncated = answer["truncated"].get<bool>();
    });
    std::printf(
        "history:  %.2f ms median of %d, one floor, one month, limit %zu (%zu travels%s); "
        "bound %.0f ms\n",
        history_ms, kRuns, history.limit, count, truncated ? ", more matched" : "",
        kHistoryBoundMs);
    ok = ok && history_ms < kHistoryBoundMs && count == history.limit;
    history.limit = kMaxHistoryLimit;
    const double history_max_ms =
        median_ms([&] { count = record->history_json(history)["count"].get<std::size_t>(); });
    std::printf("          %.2f ms with the largest limit (%zu travels; not bounded)\n",
                history_max_ms, count);

    TrendQuery trend;
    trend.from_unix_ms = month_from;
    trend.to_unix_ms = month_from + kMonthMs;
    std::size_t days = 0;
    const double trend_ms = median_ms([&] { days = record->trend_json(trend)["days"].size(); });
    std::printf(
        "trend:    %.2f ms median of %d, one month (%zu rows of day and floor); bound "
        "%.0f ms\n",
        trend_ms, kRuns, days, kTrendBoundMs);
    ok = ok && trend_ms < kTrendBoundMs && days > 0;

    // Normal operation: one travel every 30 s, each its own transaction with its curve, and the
    // io thread's tick between them (which writes nothing: a travel wrote the counters).
    const std::string curve = typical_curve(random);
    const std::int64_t wchar_before = proc_io("wchar");
    const std::int64_t disk_before = proc_io("write_bytes");
    std::vector<double> travel_times;
    std::int64_t mono = 1000;
    for (int i = 0; i < 1000; ++i) {
      Travel t = random_travel(random, now + mono, mono);
      t.curve_json = curve;
      mono += 30'000;
      start = Clock::now();
      record->travel(std::move(t), mono, now + mono);
      travel_times.push_back(ms_since(start));
      record->tick(mono + 15'000, now + mono + 15'000);
    }
    const std::int64_t wchar = proc_io("wchar") - wchar_before;
    const std::int64_t disk = proc_io("write_bytes") - disk_before;
    std::sort(travel_times.begin(), travel_times.end());
    std::printf(
        "writes:   %.1f MB written() per 1000 travels (curve %zu bytes; %.1f kB a travel), "
        "%.1f MB reached the disk (/proc/self/io write_bytes)\n",
        static_cast<double>(wchar) / 1e6, curve.size(), static_cast<double>(wchar) / 1000.0 / 1e3,
        static_cast<double>(disk) / 1e6);
    std::printf("          a travel's transaction: %.2f ms median, %.2f ms p99, %.2f ms worst\n",
                travel_times[500], travel_times[990], travel_times.back());

    // The same without curves: what the travel row, its indexes, the counters and the daily
    // aggregates cost alone.
    const std::int64_t bare_before = proc_io("wchar");
    for (int i = 0; i < 1000; ++i) {
      Travel t = random_travel(random, now + mono, mono);
      mono += 30'000;
      record->travel(std::move(t), mono, now + mono);
      record->tick(mono + 15'000, now + mono + 15'000);
    }
    std::printf("          %.1f MB written() per 1000 travels without a curve\n",
                static_cast<double>(proc_io("wchar") - bare_before) / 1e6);

    // An idle hour: a tick a second writes the changed counters once a minute.
    const std::int64_t idle_before = proc_io("wchar");
    for (int s = 1; s <= 3600; ++s) record->tick(mono + s * 1000, now + mono + s * 1000);
    std::printf("idle:     %.1f kB written() in an hour of ticks (counters once a minute)\n",
                static_cast<double>(proc_io("wchar") - idle_before) / 1e3);
    if (!record->on()) {
      std::fprintf(stderr, "record-bench: the record turned off: %s\n",
                   record->status_json().dump().c_str());
      ok = false;
    }
    record.reset();
  }

  if (keep) {
    std::printf("kept:     %s\n", path.c_str());
  } else {
    std::error_code ignored;
    std::filesystem::remove_all(dir, ignored);
  }
  std::printf("%s\n", ok ? "record-bench: within the bounds" : "record-bench: a bound was missed");
  return ok ? 0 : 1;
}
