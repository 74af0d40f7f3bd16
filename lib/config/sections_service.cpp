// The shared sections about the daemon itself: log, drive, rt, api, inputs and sim.
#include <algorithm>
#include <array>

#include "config/schema.hpp"

namespace liftd::config {
namespace {

using nlohmann::json;

constexpr std::array<std::string_view, 5> kLogLevelNames{"trace", "debug", "info", "warn", "error"};
constexpr std::array<std::string_view, 3> kRs485Names{"auto", "required", "off"};
constexpr std::array<std::string_view, 3> kEchoNames{"auto", "on", "off"};

// sockaddr_un::sun_path is 108 bytes on Linux, including the terminating NUL.
constexpr std::int64_t kMaxSocketPathLength = 107;
// useradd/groupadd: names are at most 32 characters.
constexpr std::int64_t kMaxGroupNameLength = 32;

std::string group_name_rule(const std::string& text) {
  if (text.empty()) return {};  // no group: root and the daemon's own user only
  // shadow-utils' default rule: a lower-case letter or _, then letters, digits, _ or -.
  const auto ok_first = [](char c) { return (c >= 'a' && c <= 'z') || c == '_'; };
  const auto ok_rest = [&](char c) { return ok_first(c) || (c >= '0' && c <= '9') || c == '-'; };
  if (text.empty() || !ok_first(text.front()) ||
      !std::all_of(text.begin() + 1, text.end(), ok_rest)) {
    return "is not a valid group name ([a-z_][a-z0-9_-]*)";
  }
  return {};
}

}  // namespace

std::vector<Key> log_keys() {
  return {enum_key("log.level", kLogLevelNames,
                   "least severe message logged (--log-level overrides it)", &Config::log,
                   &LogConfig::level)};
}

std::vector<Key> drive_keys() {
  std::vector<Key> t;
  t.push_back(enum_key("drive.kind", drive::kKindNames,
                       "protocol of the drive: DCP over RS485, SCH001 hydraulic card over CAN, or "
                       "Siemens USS over RS485",
                       &Config::drive, &DriveConfig::kind));
  t.push_back(string_key("drive.device", 1, 4096, "absolute path", absolute_path_rule,
                         "serial port of the drive link", &Config::drive, &DriveConfig::device));
  t.push_back(enum_key("drive.rs485", kRs485Names,
                       "kernel RS485 mode: auto = use where supported and warn where not; "
                       "required = refuse to start without it; off = never",
                       &Config::drive, &DriveConfig::rs485));
  t.push_back(enum_key("drive.echo", kEchoNames,
                       "whether the serial line (DCP link, USS bus) gives our own bytes back, as "
                       "transceivers with the receiver on while sending and most USB-RS485 "
                       "adapters do: auto = find out at each port open (journal, status "
                       "line_echo); on = read back exactly the bytes sent before the reply, a "
                       "difference is a collision (a bad reply); off = no echo",
                       &Config::drive, &DriveConfig::echo));
  return t;
}

std::vector<Key> rt_keys() {
  std::vector<Key> t;
  t.push_back(int_key("rt.priority", 1, 99, "SCHED_FIFO priority of the cycle thread", &Config::rt,
                      &RtConfig::priority));
  t.push_back(bool_key("rt.require_realtime",
                       "refuse to start (exit 2) when the cycle thread cannot get SCHED_FIFO at "
                       "rt.priority; false = run with normal scheduling and warn (--simulate "
                       "always runs)",
                       &Config::rt, &RtConfig::require_realtime));
  t.push_back(int_key("rt.cpu", -1, 1023,
                      "CPU the cycle thread is pinned to; -1 = none; must be online and "
                      "allowed for the daemon",
                      &Config::rt, &RtConfig::cpu));
  t.push_back(bool_key("rt.lock_memory", "lock all memory (mlockall) so the cycle never pages",
                       &Config::rt, &RtConfig::lock_memory));
  t.push_back(int_key("rt.flight_recorder_s", 1, 300,
                      "seconds of link traffic kept in memory for fault analysis", &Config::rt,
                      &RtConfig::flight_recorder_s));
  t.push_back(int_key("rt.trace_files_kept", 1, 100,
                      "flight-recorder files (liftd-trace-*.txt) kept in the runtime directory; "
                      "the oldest are removed beyond it",
                      &Config::rt, &RtConfig::trace_files_kept));
  // DCP 7.2: the drive's reply ends by 13.625 ms, the next master frame starts at 15 ms.
  t.push_back(int_key("rt.send_window_us", 0, 1375,
                      "a cycle that wakes up at most this late still sends (counted as a late "
                      "send above 500 us); later wake-ups skip the cycle. DCP 7.2 allows at "
                      "most 15 ms - 13.625 ms = 1375 us",
                      &Config::rt, &RtConfig::send_window_us));
  return t;
}

std::vector<Key> api_keys() {
  std::vector<Key> t;
  t.push_back(string_key("api.socket", 1, kMaxSocketPathLength, "absolute path, at most 107 bytes",
                         absolute_path_rule, "Unix socket of the JSON API", &Config::api,
                         &ApiConfig::socket));
  t.push_back(string_key("api.socket_group", 0, kMaxGroupNameLength, "group name", group_name_rule,
                         "group owning the API socket (empty: the daemon's own group)",
                         &Config::api, &ApiConfig::socket_group));
  t.push_back(string_key(
      "api.read_group", 0, kMaxGroupNameLength, "group name", group_name_rule,
      "members may read state and watch events (empty: nobody but root and the daemon's user)",
      &Config::api, &ApiConfig::read_group));
  t.push_back(
      string_key("api.control_group", 0, kMaxGroupNameLength, "group name", group_name_rule,
                 "members may send calls, travels and resets (empty: root and the daemon's user)",
                 &Config::api, &ApiConfig::control_group));
  t.push_back(string_key("api.inputs_group", 0, kMaxGroupNameLength, "group name", group_name_rule,
                         "members may send machine inputs, the I/O board's daemon (empty: root "
                         "and the daemon's user)",
                         &Config::api, &ApiConfig::inputs_group));
  t.push_back(int_key("api.max_clients", 1, 256, "API connections served at once", &Config::api,
                      &ApiConfig::max_clients));
  t.push_back(int_key("api.max_requests_per_s", 0, 1000000,
                      "requests answered per second over all clients; beyond it they wait their "
                      "turn (none is refused), every client an equal share; bounds the CPU the "
                      "API takes from the rest of the board; 0 = no limit",
                      &Config::api, &ApiConfig::max_requests_per_s));
  t.push_back(int_key("api.max_clients_per_uid", 1, 256,
                      "API connections one user (uid) may hold at once; root is exempt",
                      &Config::api, &ApiConfig::max_clients_per_uid));
  t.push_back(int_key("api.reserved_clients", 0, 255,
                      "of api.max_clients, this many are kept for clients with control access "
                      "(api.control_group, root, the daemon's user); less than api.max_clients",
                      &Config::api, &ApiConfig::reserved_clients));
  t.push_back(int_key("api.stalled_reader_timeout_s", 1, 3600,
                      "drop a client whose replies have waited unread this long (a pipelining "
                      "client that reads is never dropped: liftd stops reading from it instead)",
                      &Config::api, &ApiConfig::stalled_reader_timeout_s));
  t.push_back(int_key("api.idle_timeout_s", 0, 86400, "close a client silent this long; 0 = never",
                      &Config::api, &ApiConfig::idle_timeout_s));
  // 66 Hz is one event per 15 ms cycle (DCP 7.2).
  t.push_back(int_key("api.state_rate_hz", 1, 66,
                      "`state` watch events that only carry new position or speed go out at "
                      "most this often; discrete changes (drive status, link, travel, faults, "
                      "calls) go out from the cycle that saw them",
                      &Config::api, &ApiConfig::state_rate_hz));
  // The display's 20 characters (DCP 5.7), enough for a name a person reads on a panel.
  t.push_back(string_key("api.car_name", 0, 20, "0..20 characters, no control character",
                         control_rule,
                         "the car's name in a group (\"A\", \"Lift 2\"), told in the API's "
                         "hello with the drive kind and the floors; empty: none",
                         &Config::api, &ApiConfig::car_name));
  return t;
}

std::vector<Key> inputs_keys() {
  return {int_key("inputs.timeout_ms", 50, 10000,
                  "machine inputs older than this count as lost (safe stop)", &Config::inputs,
                  &InputsConfig::timeout_ms)};
}

std::vector<Key> record_keys() {
  std::vector<Key> t;
  t.push_back(bool_key("record.enabled",
                       "keep the lift's record (lifetime counters, every travel) on the board's "
                       "storage; false = counters from zero at each start, no history",
                       &Config::record, &RecordConfig::enabled));
  t.push_back(string_key(
      "record.path", 0, 4096, "empty or an absolute path",
      [](const std::string& text) {
        return text.empty() ? std::string() : absolute_path_rule(text);
      },
      "the record's SQLite file; empty = record.db in the unit's StateDirectory "
      "(/var/lib/liftd), with --simulate in the runtime directory, else /var/lib/liftd/record.db",
      &Config::record, &RecordConfig::path));
  // Issue #42's benchmark holds a million travels; ten million is about 2 GB of rows.
  t.push_back(int_key("record.max_travels", 1000, 10000000,
                      "travels the record keeps; beyond it the oldest go first", &Config::record,
                      &RecordConfig::max_travels));
  t.push_back(int_key("record.curves_kept", 0, 10000,
                      "of the travels kept, the newest this many keep their curve (position, "
                      "speed, the drive's bits: tens of kB each)",
                      &Config::record, &RecordConfig::curves_kept));
  return t;
}

// Until the car measured travels of its own, `eta` (docs/api.md "Arrival times") uses these.
std::vector<Key> eta_keys() {
  std::vector<Key> t;
  t.push_back(int_key("eta.speed_mm_s", 50, 20000,
                      "the rated speed the arrival times assume until the car measured its own",
                      &Config::eta, &EtaConfig::speed_mm_s));
  t.push_back(int_key("eta.acceleration_mm_s2", 50, 5000,
                      "the acceleration (and deceleration) the arrival times assume until the car "
                      "measured its own",
                      &Config::eta, &EtaConfig::acceleration_mm_s2));
  t.push_back(int_key("eta.start_ms", 0, 60000,
                      "a travel's time beyond its motion (start, levelling, stop) until the car "
                      "measured its own",
                      &Config::eta, &EtaConfig::start_ms));
  t.push_back(int_key("eta.stop_ms", 0, 300000,
                      "how long the car stands at a queued stop before it travels on, until it "
                      "measured that itself",
                      &Config::eta, &EtaConfig::stop_ms));
  return t;
}

// The simulated shaft's levels: at most as many as floors may be configured, each within the
// range of a floor's level (I9's six digits, DCP 5.12.9), strictly increasing.
void apply_shaft_levels(const json& value, const std::string& where, Config& cfg,
                        Problems& problems) {
  constexpr std::int64_t kMaxShaftLevels = 128;
  constexpr std::int64_t kMaxLevelMm = 999999;
  if (!value.is_array() || value.size() > static_cast<std::size_t>(kMaxShaftLevels)) {
    problems.push_back({where, "expected an array of at most " + std::to_string(kMaxShaftLevels) +
                                   " levels in mm, got " + show(value)});
    return;
  }
  std::vector<std::int64_t> levels;
  bool good = true;
  for (std::size_t i = 0; i < value.size(); ++i) {
    const std::string at = where + "[" + std::to_string(i) + "]";
    if (!check_integer(value[i], at, -kMaxLevelMm, kMaxLevelMm, problems)) {
      good = false;
      continue;
    }
    const std::int64_t level = value[i].get<std::int64_t>();
    if (!levels.empty() && level <= levels.back()) {
      problems.push_back({at, "must be above the level before it"});
      good = false;
    }
    levels.push_back(level);
  }
  if (good) cfg.sim.shaft_levels_mm = std::move(levels);
}

std::vector<Key> sim_keys() {
  return {
      int_key("sim.dcp", 3, 4, "DCP version the simulated drive speaks (--simulate)", &Config::sim,
              &SimConfig::dcp),
      custom_key("sim.shaft_levels_mm", "array of integers",
                 "at most 128 levels in mm, strictly increasing; [] = the floors' levels",
                 "the simulated shaft's true level of each floor, where its level zone is "
                 "centred (--simulate; the learning travel finds them)",
                 apply_shaft_levels, [](const Config& c) { return json(c.sim.shaft_levels_mm); }),
      int_key("sim.level_zone_mm", 10, 1000,
              "length of each simulated level zone, centred on its true level (--simulate)",
              &Config::sim, &SimConfig::level_zone_mm),
      int_key("sim.slow_mm_per_s", 10, 500,
              "the simulated drive's slowest travel speed (--simulate): the DCP drive's crawl V0 "
              "(DCP 10.3), the hydraulic unit's slow (levelling) speed, the direction signal "
              "alone (card document 1.4); a USS drive crawls at uss.speeds V0",
              &Config::sim, &SimConfig::slow_mm_per_s)};
}

std::string_view to_string(LogLevel value) {
  return enum_name(value, kLogLevelNames);
}

std::string_view to_string(Rs485Mode value) {
  return enum_name(value, kRs485Names);
}

std::string_view to_string(EchoMode value) {
  return enum_name(value, kEchoNames);
}

std::optional<LogLevel> parse_log_level(std::string_view name) {
  return enum_from<LogLevel>(name, kLogLevelNames);
}

}  // namespace liftd::config
