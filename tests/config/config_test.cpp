// The configuration schema: defaults, every kind of problem, the example file, the generated
// reference in docs/config.md.
#include "config/config.hpp"
#include "config/schema.hpp"
#include "kinds/config_schema.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <fstream>
#include <future>
#include <sstream>
#include <string>
#include <vector>

namespace liftd::config {
namespace {

using nlohmann::json;
using ::testing::HasSubstr;

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  std::ostringstream out;
  out << in.rdbuf();
  return out.str();
}

const Schema& schema() {
  return kinds::config_schema();
}

std::string all_problems(const LoadResult& result) {
  std::string out;
  for (const auto& p : result.problems) out += to_string(p) + "\n";
  return out;
}

TEST(ConfigDefaults, EmptyObjectGivesTheDocumentedDefaults) {
  // Legend: key path -> the default the later issues rely on (from the task's key list).
  const std::vector<std::pair<std::string, json>> expected = {
      {"/log/level", "info"},
      {"/drive/kind", "dcp"},
      {"/drive/device", "/dev/ttyS1"},
      {"/drive/rs485", "auto"},
      {"/drive/echo", "auto"},
      {"/rt/priority", 80},
      {"/rt/require_realtime", true},
      {"/rt/cpu", -1},
      {"/rt/lock_memory", true},
      {"/rt/flight_recorder_s", 30},
      {"/rt/trace_files_kept", 10},
      {"/rt/send_window_us", 1375},
      {"/api/socket", "/run/liftd/api.sock"},
      {"/api/socket_group", "liftd"},
      {"/api/read_group", "liftd"},
      {"/api/control_group", "liftd-control"},
      {"/api/inputs_group", "liftd-io"},
      {"/api/max_clients", 32},
      {"/api/max_requests_per_s", 5000},
      {"/api/max_clients_per_uid", 8},
      {"/api/reserved_clients", 4},
      {"/api/stalled_reader_timeout_s", 30},
      {"/api/idle_timeout_s", 0},
      {"/api/state_rate_hz", 10},
      {"/api/car_name", ""},
      {"/inputs/timeout_ms", 500},
      {"/record/enabled", true},
      {"/record/path", ""},
      {"/record/max_travels", 1000000},
      {"/record/curves_kept", 100},
      {"/eta/speed_mm_s", 1000},
      {"/eta/acceleration_mm_s2", 600},
      {"/eta/start_ms", 2000},
      {"/eta/stop_ms", 1000},
      {"/position/source", "api"},
      {"/position/can_id", 400},
      {"/position/can_offset", 0},
      {"/position/can_length", 4},
      {"/position/can_byte_order", "little"},
      {"/position/can_signed", false},
      {"/position/can_um_per_count", 1000},
      {"/position/can_offset_mm", 0},
      {"/position/can_timeout_ms", 100},
      {"/travel/level_tolerance_mm", 5},
      {"/travel/relevel_threshold_mm", 15},
      {"/travel/relevel_with_doors", "both"},
      {"/travel/relevel_electric_stop", false},
      {"/travel/use_start_parameters", true},
      {"/travel/fast_start_timeout_ms", 3000},
      {"/travel/call_stop_ms", 1500},
      {"/travel/inspection_hold_ms", 500},
      {"/travel/dcp3_stop_lead_mm", 8},
      {"/travel/dcp3_speed_count", 2},
      {"/travel/dcp3_reference", "position"},
      {"/travel/dcp3_decel_distance_mm", {{"V4", 2500}, {"V3", 1200}}},
      {"/can/interface", "can0"},
      {"/sim/dcp", 4},
      {"/sim/shaft_levels_mm", json::array()},
      {"/sim/level_zone_mm", 100},
      {"/sim/slow_mm_per_s", 50},
  };
  const LoadResult result = kinds::parse_config("{}", "test");
  ASSERT_TRUE(result.ok()) << all_problems(result);
  const json dumped = to_json(result.config, schema());
  for (const auto& [pointer, value] : expected) {
    EXPECT_EQ(dumped.at(json::json_pointer(pointer)), value) << pointer;
  }
  EXPECT_EQ(dumped.at("floors").size(), 6U);
  EXPECT_EQ(dumped.at("floors")[5], (json{{"name", "5"}, {"level_mm", 15000}}));
  // Every key of the shared sections has a default in the dump (each drive kind's section is
  // its own test's: tests/<kind>/host/defaults_test.cpp).
  std::size_t leaves = 0;
  for (const auto& path : key_paths(schema())) {
    const std::string section = path.substr(0, path.find('.'));
    if (drive::parse_kind(section)) continue;
    std::string pointer = "/" + path;
    std::replace(pointer.begin(), pointer.end(), '.', '/');
    EXPECT_TRUE(dumped.contains(json::json_pointer(pointer))) << path;
    ++leaves;
  }
  EXPECT_EQ(leaves, expected.size() + 1);  // + floors
}

TEST(ConfigDefaults, DefaultConstructedConfigMatchesParsedDefaults) {
  EXPECT_EQ(to_json(Config{}, schema()),
            to_json(kinds::parse_config("{}", "test").config, schema()));
}

TEST(ConfigExample, ShippedExampleIsValidCompleteAndAtDefaults) {
  const std::string path = std::string(LIFTD_SOURCE_DIR) + "/config/liftd.json";
  const LoadResult result = kinds::load_config(path);
  ASSERT_TRUE(result.ok()) << all_problems(result);
  const json file = json::parse(read_text(path));
  // Every shared key and every key of the example's own drive kind; another kind's section is
  // that kind's own example's (config/hydraulic.json, ...), and where this file keeps one it is
  // at its defaults (below), so a new kind does not edit this file.
  const std::string kind = file.at("drive").at("kind").get<std::string>();
  for (const auto& key : key_paths(schema())) {
    const std::string section = key.substr(0, key.find('.'));
    if (drive::parse_kind(section) && section != kind) continue;
    std::string pointer = "/" + key;
    std::replace(pointer.begin(), pointer.end(), '.', '/');
    EXPECT_TRUE(file.contains(json::json_pointer(pointer))) << key << " missing from the example";
  }
  EXPECT_EQ(to_json(result.config, schema()), to_json(Config{}, schema()));
}

// Every sample in config/ is a file the daemon accepts as it stands, for its drive kind.
TEST(ConfigExample, EverySampleConfigurationIsValid) {
  for (const auto& [file, kind] :
       {std::pair{"liftd.json", DriveKind::Dcp}, std::pair{"hydraulic.json", DriveKind::Sch001},
        std::pair{"uss.json", DriveKind::Uss}}) {
    const LoadResult result = kinds::load_config(std::string(LIFTD_SOURCE_DIR) + "/config/" + file);
    EXPECT_TRUE(result.ok()) << file << ": " << all_problems(result);
    EXPECT_EQ(result.config.drive.kind, kind) << file;
  }
}

TEST(ConfigValues, EveryKeyReachesTheTypedStruct) {
  const std::string text = R"({
    "log": {"level": "debug"},
    "drive": {"kind": "uss", "device": "/dev/ttyUSB0", "rs485": "required"},
    "dcp": {"manufacturer": "QX", "language": "DE", "data_info_type": "3",
            "extended_position": false, "link_fault_frames": 20, "link_recover_frames": 5,
            "request_timeout_ms": 100},
    "rt": {"priority": 99, "require_realtime": false, "cpu": 1023, "lock_memory": false,
           "flight_recorder_s": 300, "trace_files_kept": 100},
    "api": {"socket": "/tmp/x.sock", "socket_group": "a", "read_group": "b",
            "control_group": "c_d", "inputs_group": "e-f", "max_clients": 256,
            "max_clients_per_uid": 3, "reserved_clients": 255, "stalled_reader_timeout_s": 3600,
            "idle_timeout_s": 86400},
    "inputs": {"timeout_ms": 50},
    "floors": [{"name": "UG", "level_mm": -2800}, {"name": "EG", "level_mm": 0}],
    "position": {"source": "sim"},
    "travel": {"level_tolerance_mm": 1, "relevel_threshold_mm": 2,
               "relevel_with_doors": "never", "relevel_electric_stop": true,
               "use_start_parameters": false, "fast_start_timeout_ms": 10000,
               "inspection_hold_ms": 100, "dcp3_speed_count": 3,
               "dcp3_decel_distance_mm": {"V4": 2000, "V3": 1000, "V2": 600}},
    "uss": {"baud": 187500, "drive_address": 7, "drive_pkw": "variable", "drive_pzd_words": 4,
            "slaves": [{"address": 12, "pkw": "3", "pzd_words": 0}, {"address": 31}],
            "polling_list": [7, 12, 7, 31], "reply_delay_ms": 5, "cycle_time_ms": 100,
            "telegram_failures": 7, "pkw_repeat_limit": 50, "mirror_at_start": false,
            "full_scale_raw": 8192, "full_scale": 50, "profile_timeout_ms": 500,
            "speeds": {"V0": 2.5, "VN": 1, "VI": 15, "V2": 20, "V3": 40, "V4": 99.9}},
    "sim": {"dcp": 3}
  })";
  const LoadResult r = kinds::parse_config(text, "test");
  ASSERT_TRUE(r.ok()) << all_problems(r);
  const Config& c = r.config;
  EXPECT_EQ(c.log.level, LogLevel::debug);
  EXPECT_EQ(c.drive.kind, DriveKind::Uss);
  EXPECT_EQ(c.drive.device, "/dev/ttyUSB0");
  EXPECT_EQ(c.drive.rs485, Rs485Mode::required);
  EXPECT_EQ(c.rt.priority, 99);
  EXPECT_EQ(c.rt.cpu, 1023);
  EXPECT_FALSE(c.rt.lock_memory);
  EXPECT_EQ(c.rt.flight_recorder_s, 300);
  EXPECT_FALSE(c.rt.require_realtime);
  EXPECT_EQ(c.rt.trace_files_kept, 100);
  EXPECT_EQ(c.api.max_clients_per_uid, 3);
  EXPECT_EQ(c.api.reserved_clients, 255);
  EXPECT_EQ(c.api.stalled_reader_timeout_s, 3600);
  EXPECT_EQ(c.api.socket, "/tmp/x.sock");
  EXPECT_EQ(c.api.socket_group, "a");
  EXPECT_EQ(c.api.read_group, "b");
  EXPECT_EQ(c.api.control_group, "c_d");
  EXPECT_EQ(c.api.inputs_group, "e-f");
  EXPECT_EQ(c.api.max_clients, 256);
  EXPECT_EQ(c.api.idle_timeout_s, 86400);
  EXPECT_EQ(c.inputs.timeout_ms, 50);
  EXPECT_EQ(c.floors, (std::vector<Floor>{{"UG", -2800}, {"EG", 0}}));
  EXPECT_EQ(c.position.source, PositionSource::sim);
  EXPECT_EQ(c.travel.level_tolerance_mm, 1);
  EXPECT_EQ(c.travel.relevel_threshold_mm, 2);
  EXPECT_EQ(c.travel.relevel_with_doors, RelevelDoors::never);
  EXPECT_TRUE(c.travel.relevel_electric_stop);
  EXPECT_FALSE(c.travel.use_start_parameters);
  EXPECT_EQ(c.travel.fast_start_timeout_ms, 10000);
  EXPECT_EQ(c.travel.inspection_hold_ms, 100);
  EXPECT_EQ(c.travel.dcp3_speed_count, 3);
  EXPECT_EQ(c.travel.dcp3_decel_distance_mm,
            (std::map<std::string, int>{{"V4", 2000}, {"V3", 1000}, {"V2", 600}}));
  EXPECT_EQ(c.sim.dcp, 3);
  // (The dcp and uss sections' members: tests/dcp/host and tests/uss/host.)
  // The dump reads back to the same configuration.
  const LoadResult again = from_json(to_json(c, schema()), schema());
  EXPECT_EQ(all_problems(again), all_problems(r));  // the same two refusals, nothing else
  EXPECT_EQ(to_json(again.config, schema()), to_json(c, schema()));
}

struct BadCase {
  const char* legend;
  const char* json_text;
  const char* where;    // expected Problem::where
  const char* message;  // expected substring of Problem::message
};

TEST(ConfigProblems, NameTheKeyTheValueAndWhatIsAllowed) {
  const std::vector<BadCase> cases = {
      {"integer below range", R"({"dcp": {"link_fault_frames": 0}})", "dcp.link_fault_frames",
       "0 is out of range: allowed 1..100"},
      {"integer above range", R"({"rt": {"priority": 100}})", "rt.priority",
       "100 is out of range: allowed 1..99"},
      {"send window beyond the DCP 7.2 slack", R"({"rt": {"send_window_us": 1376}})",
       "rt.send_window_us", "1376 is out of range: allowed 0..1375"},
      {"state rate above one per cycle", R"({"api": {"state_rate_hz": 67}})", "api.state_rate_hz",
       "67 is out of range: allowed 1..66"},
      {"huge unsigned", R"({"rt": {"cpu": 18446744073709551615}})", "rt.cpu",
       "out of range: allowed -1..1023"},
      {"integer given as string", R"({"api": {"max_clients": "32"}})", "api.max_clients",
       "expected an integer 1..256, got \"32\""},
      {"integer given as float", R"({"inputs": {"timeout_ms": 500.5}})", "inputs.timeout_ms",
       "expected an integer 50..10000, got 500.5"},
      {"bool given as number", R"({"rt": {"lock_memory": 1}})", "rt.lock_memory",
       "expected true or false, got 1"},
      {"choice not allowed, with suggestion", R"({"log": {"level": "warning"}})", "log.level",
       "\"warning\" is not allowed: use one of \"trace\", \"debug\", \"info\", \"warn\", "
       "\"error\" (did you mean \"warn\"?)"},
      {"choice given as number", R"({"sim": {"dcp": "4"}})", "sim.dcp",
       "expected an integer 3..4, got \"4\""},
      {"another company's I0 maker code", R"({"dcp": {"manufacturer": "LI"}})", "dcp.manufacturer",
       "is Schneider Steuerungstechnik's code in the DCP 5.12.2.3 table"},
      {"a drive maker's code", R"({"dcp": {"manufacturer": "ZA"}})", "dcp.manufacturer",
       "is Ziehl-Abegg's code"},
      {"data info type out of set", R"({"dcp": {"data_info_type": "5"}})", "dcp.data_info_type",
       "\"5\" is not allowed"},
      {"manufacturer lower case", R"({"dcp": {"manufacturer": "li"}})", "dcp.manufacturer",
       "must be exactly two capital letters A-Z"},
      {"language too long", R"({"dcp": {"language": "ENG"}})", "dcp.language",
       "\"ENG\" has 3 bytes: allowed 2..2"},
      {"relative device path", R"({"drive": {"device": "ttyS1"}})", "drive.device",
       "must be an absolute path"},
      {"socket path too long for sun_path",
       R"({"api": {"socket": "/run/liftd/aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa"}})",
       "api.socket", "allowed 1..107"},
      {"bad group name", R"({"api": {"control_group": "Lift Control"}})", "api.control_group",
       "is not a valid group name"},
      {"unknown key with suggestion", R"({"dcp": {"link_falt_frames": 10}})",
       "dcp.link_falt_frames", "unknown key (did you mean \"dcp.link_fault_frames\"?)"},
      {"unknown section with suggestion", R"({"travl": {}})", "travl",
       "unknown key (did you mean \"travel\"?)"},
      {"unknown key without suggestion", R"({"colour": "red"})", "colour", "unknown key"},
      {"section that is not an object", R"({"rt": 5})", "rt",
       "expected an object (a section), got 5"},
      {"top level not an object", R"([1, 2])", "(top level)", "expected a JSON object"},
      {"floors not an array", R"({"floors": {"name": "0"}})", "floors", "expected an array"},
      {"one floor only", R"({"floors": [{"name": "0", "level_mm": 0}]})", "floors",
       "has 1 entries: allowed 2..64"},
      {"floor name too long",
       R"({"floors": [{"name": "0", "level_mm": 0}, {"name": "seventeen chars!!", "level_mm": 1}]})",
       "floors[1].name", "1..16 printable characters"},
      {"floor name empty",
       R"({"floors": [{"name": "", "level_mm": 0}, {"name": "1", "level_mm": 1}]})",
       "floors[0].name", "1..16 printable characters"},
      {"floor level missing", R"({"floors": [{"name": "0", "level_mm": 0}, {"name": "1"}]})",
       "floors[1]", "missing \"level_mm\""},
      {"floor unknown member",
       R"({"floors": [{"name": "0", "level_mm": 0}, {"name": "1", "levl_mm": 1, "level_mm": 2}]})",
       "floors[1].levl_mm", "unknown key (did you mean \"level_mm\"?)"},
      {"floor levels not increasing",
       R"({"floors": [{"name": "0", "level_mm": 3000}, {"name": "1", "level_mm": 3000}]})",
       "floors[1].level_mm", "3000 is not above the previous floor's 3000"},
      {"floor names not unique",
       R"({"floors": [{"name": "A", "level_mm": 0}, {"name": "A", "level_mm": 10}]})",
       "floors[1].name", "\"A\" is already the name of floors[0]"},
      {"floor level beyond I9's six digits",
       R"({"floors": [{"name": "0", "level_mm": 0}, {"name": "1", "level_mm": 1000000}]})",
       "floors[1].level_mm", "allowed -999999..999999"},
      {"decel distance for a speed not in use", R"({"travel": {"dcp3_decel_distance_mm":
        {"V4": 2500, "V3": 1200, "V2": 800}}})",
       "travel.dcp3_decel_distance_mm.V2", "is not used with travel.dcp3_speed_count 2"},
      {"decel distance for a non-speed", R"({"travel": {"dcp3_decel_distance_mm":
        {"V4": 2500, "V33": 1200}}})",
       "travel.dcp3_decel_distance_mm.V33", "is not a DCP3 travelling speed"},
      {"decel distance missing for a speed in use", R"({"travel": {"dcp3_speed_count": 3}})",
       "travel.dcp3_decel_distance_mm", "has no distance for V2"},
      {"decel distance zero", R"({"travel": {"dcp3_decel_distance_mm": {"V4": 0, "V3": 1200}}})",
       "travel.dcp3_decel_distance_mm.V4", "allowed 1..32766"},
      {"relevel threshold inside the tolerance", R"({"travel": {"relevel_threshold_mm": 5}})",
       "travel.relevel_threshold_mm", "must be greater than level_tolerance_mm (5)"},
      {"duplicate key", R"({"log": {"level": "info", "level": "debug"}})", "log.level",
       "duplicate key"},
  };
  for (const auto& c : cases) {
    const LoadResult r = kinds::parse_config(c.json_text, "test.json");
    ASSERT_FALSE(r.ok()) << c.legend;
    bool found = false;
    for (const auto& p : r.problems) {
      if (p.where == c.where && p.message.find(c.message) != std::string::npos) found = true;
    }
    EXPECT_TRUE(found) << c.legend << "\nexpected " << c.where << ": " << c.message << "\ngot\n"
                       << all_problems(r);
  }
}

TEST(ConfigProblems, CollectsEveryProblemNotJustTheFirst) {
  const LoadResult r = kinds::parse_config(R"({
    "log": {"levl": "info"},
    "dcp": {"link_fault_frames": 0, "manufacturer": "x"},
    "rt": {"priority": "high"},
    "floors": [{"name": "0", "level_mm": 10}, {"name": "1", "level_mm": 5}]
  })",
                                           "test.json");
  ASSERT_EQ(r.problems.size(), 5U) << all_problems(r);
  EXPECT_EQ(r.problems[0].where, "log.levl");
}

TEST(ConfigProblems, MalformedJsonReportsLineAndColumn) {
  // Legend: text -> "origin:line:column" of the first bad character.
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"{\n  \"log\": {\"level\": \"info\",}\n}", "f.json:2:27"},
      {"{\n\n   \"rt\": [1 2]}", "f.json:3:13"},
      {"", "f.json:1:1"},
      {"{\"a\": tru}", "f.json:1:10"},
  };
  for (const auto& [text, where] : cases) {
    const LoadResult r = kinds::parse_config(text, "f.json");
    ASSERT_EQ(r.problems.size(), 1U) << text;
    EXPECT_EQ(r.problems[0].where, where) << text;
    EXPECT_THAT(r.problems[0].message, HasSubstr("malformed JSON")) << text;
  }
}

TEST(ConfigProblems, NumberTooLargeIsAProblemNotACrash) {
  // Found by config_fuzz: the JSON library throws out_of_range, not parse_error, for these.
  for (const std::string text : {"1E989299", "{\"rt\": {\"priority\": 1e400}}"}) {
    const LoadResult r = kinds::parse_config(text, "f.json");
    ASSERT_EQ(r.problems.size(), 1U) << text;
    EXPECT_EQ(r.problems[0].where, "f.json") << text;
    EXPECT_EQ(r.problems[0].message, "malformed JSON: a number is too large to represent");
  }
}

TEST(ConfigFile, UnreadableFileNamesThePathAndTheErrnoText) {
  const LoadResult missing = kinds::load_config("/nonexistent/liftd.json");
  ASSERT_EQ(missing.problems.size(), 1U);
  EXPECT_EQ(missing.problems[0].where, "/nonexistent/liftd.json");
  EXPECT_THAT(missing.problems[0].message, HasSubstr("No such file or directory"));

  const LoadResult directory = kinds::load_config("/");
  ASSERT_EQ(directory.problems.size(), 1U);
  EXPECT_EQ(directory.problems[0].where, "/");
  EXPECT_THAT(directory.problems[0].message, HasSubstr("Is a directory"));
}

// Legend: what a file says -> the key refused and why. Every case is something the daemon
// would refuse (or misuse) at start, so --check-config must refuse it too.
TEST(ConfigProblems, WhatTheDaemonCannotRunIsRefused) {
  const std::vector<BadCase> cases = {
      {"USS rate that is none of B 2.4", R"({"drive": {"kind": "uss"}, "uss": {"baud": 12345}})",
       "uss.baud", "12345 is not a USS rate: use one of 300, 600"},
      {"USS slave address beyond ADR bits 0..4", R"({"uss": {"slaves": [{"address": 32}]}})",
       "uss.slaves[0].address", "32 is out of range: allowed 0..31"},
      {"USS slave listed twice",
       R"({"uss": {"slaves": [{"address": 3}, {"address": 3, "pkw": "3"}]}})",
       "uss.slaves[1].address", "3 is already the address of uss.slaves[0]"},
      {"USS PKW length a drive cannot have", R"({"uss": {"slaves": [{"address": 3, "pkw": 5}]}})",
       "uss.slaves[0].pkw", "5 is not allowed: use \"0\", \"3\", \"4\" or \"variable\""},
      {"USS slave that is the drive",
       R"({"drive": {"kind": "uss"}, "uss": {"slaves": [{"address": 0}]}})",
       "uss.slaves[0].address", "0 is uss.drive_address: the drive is not listed again"},
      {"USS polling list with an unknown slave",
       R"({"drive": {"kind": "uss"}, "uss": {"polling_list": [0, 5]}})", "uss.polling_list[1]",
       "5 is neither uss.drive_address nor in uss.slaves"},
      {"USS polling list without the drive",
       R"({"drive": {"kind": "uss"}, "uss": {"slaves": [{"address": 4}], "polling_list": [4]}})",
       "uss.polling_list", "never polls the drive (uss.drive_address 0)"},
      {"USS speeds without a crawl speed",
       R"({"drive": {"kind": "uss"}, "uss": {"speeds": {"VN": 2, "VI": 30, "V3": 63, "V4": 100}}})",
       "uss.speeds", "has no setpoint for V0"},
      {"USS lift with the CAN encoder (no CAN runner beside the USS bus)",
       R"({"drive": {"kind": "uss"}, "position": {"source": "can"}})", "position.source",
       "\"can\" is not available with drive.kind \"uss\""},
      {"USS speed that is no speed name", R"({"uss": {"speeds": {"V9": 2}}})", "uss.speeds.V9",
       "is not a speed name"},
      {"USS speed beyond the signed setpoint word",
       R"({"drive": {"kind": "uss"}, "uss": {"speeds": {"V0": 5, "VN": 2, "VI": 30, "V3": 63, "V4": 200.5}}})",
       "uss.speeds.V4", "200.5 does not fit the signed setpoint word: at most 199.99"},
      {"CAN endpoint that is neither an interface nor unix:PATH",
       R"({"can": {"interface": "can 0"}})", "can.interface",
       "is neither an interface name (letters, digits, _ - .) nor unix:PATH"},
      {"unix: endpoint with a relative path", R"({"can": {"interface": "unix:card.sock"}})",
       "can.interface", "must be an absolute path"},
      {"SCH001 controller node 0 (the card would ignore us)",
       R"({"sch001": {"controller_node": 0}})", "sch001.controller_node", "2..95"},
      {"SCH001 base whose identifiers leave 11 bits", R"({"sch001": {"base": 1953}})",
       "sch001.base", "0..1952"},
      {"CAN encoder value beyond the 8 data bytes",
       R"({"position": {"can_offset": 6, "can_length": 4}})", "position.can_offset",
       "6 + position.can_length 4 must stay within the 8 data bytes of a CAN frame"},
      {"CAN encoder without a scale", R"({"position": {"can_um_per_count": 0}})",
       "position.can_um_per_count", "0 is no scale"},
      {"NUL inside the socket path (bound at the text before it)",
       R"({"api": {"socket": "/run/liftd/api.sock\u0000.evil"}})", "api.socket",
       "contains a control character (byte 0x00 at offset 19): not allowed"},
      {"escape inside the device path", R"({"drive": {"device": "/dev/tty\u001bS1"}})",
       "drive.device", "contains a control character (byte 0x1B at offset 8)"},
      {"DEL inside the device path", R"({"drive": {"device": "/dev/ttyS1\u007f"}})", "drive.device",
       "contains a control character (byte 0x7F at offset 10)"},
      {"C1 control (NEL) inside the socket path", R"({"api": {"socket": "/run/a\u0085b"}})",
       "api.socket", "contains a control character (byte 0xC2 at offset 6)"},
      {"control character in a floor name",
       R"({"floors": [{"name": "0\u0007", "level_mm": 0}, {"name": "1", "level_mm": 1}]})",
       "floors[0].name", "1..16 printable characters of the DCP display character set"},
      {"C1 control in a floor name",
       R"({"floors": [{"name": "0\u0085", "level_mm": 0}, {"name": "1", "level_mm": 1}]})",
       "floors[0].name", "is not allowed"},
      {"reserved API slots leave none for readers",
       R"({"api": {"max_clients": 4, "reserved_clients": 4}})", "api.reserved_clients",
       "4 must be less than api.max_clients (4)"},
  };
  for (const auto& c : cases) {
    const LoadResult r = kinds::parse_config(c.json_text, "test.json");
    ASSERT_FALSE(r.ok()) << c.legend;
    EXPECT_EQ(r.problems[0].where, c.where) << c.legend << "\n" << all_problems(r);
    EXPECT_THAT(r.problems[0].message, HasSubstr(c.message)) << c.legend;
  }
}

// Floor names are shown on the drive's display, so they are the display's characters (DCP
// appendix A); every such name is already in Unicode NFC, and names the display shows alike are
// the same name.
TEST(ConfigFloorNames, EqualAfterNormalisationOrOnTheDisplayIsTheSameName) {
  const auto floors = [](const std::string& a, const std::string& b) {
    return R"({"floors": [{"name": ")" + a + R"(", "level_mm": 0}, {"name": ")" + b +
           R"(", "level_mm": 3000}]})";
  };
  struct Case {
    const char* legend;
    std::string text;
    const char* where;    // empty: valid
    const char* message;  // substring
  };
  const std::vector<Case> cases = {
      {"German names with umlauts are fine", floors("Erdgeschoß", "Über"), "", ""},
      {"Greek and signs the display has", floors("α", "±0"), "", ""},
      {"decomposed A + combining diaeresis is refused (NFC would make it \u00c4)",
       floors("\u00c4", "A\u0308"), "floors[1].name", "is not allowed"},
      {"micro sign and Greek mu look alike on the display", floors("\u00b5", "\u03bc"),
       "floors[1].name", "is already the name of floors[0]"},
      {"ohm sign (NFC: capital omega) is refused", floors("\u03a9", "\u2126"), "floors[1].name",
       "is not allowed"},
      {"a character the display lacks", floors("\u00c5", "1"), "floors[0].name",
       "DCP display character set"},
      {"fullwidth digit look-alike", floors("1", "\uff11"), "floors[1].name", "is not allowed"},
      {"leading space", floors(" 1", "2"), "floors[0].name", "no space at either end"},
      {"trailing space", floors("1", "1 "), "floors[1].name", "no space at either end"},
  };
  for (const auto& c : cases) {
    const LoadResult r = kinds::parse_config(c.text, "test.json");
    if (std::string(c.where).empty()) {
      EXPECT_TRUE(r.ok()) << c.legend << "\n" << all_problems(r);
      continue;
    }
    ASSERT_FALSE(r.ok()) << c.legend;
    EXPECT_EQ(r.problems[0].where, c.where) << c.legend << "\n" << all_problems(r);
    EXPECT_THAT(r.problems[0].message, HasSubstr(c.message)) << c.legend;
  }
}

TEST(ConfigHost, RtCpuMustBeAUsableCpu) {
  Config config;
  const HostFacts two_cpus{{0, 1}};
  EXPECT_TRUE(check_host(config, two_cpus).empty());  // -1: no pinning
  config.rt.cpu = 1;
  EXPECT_TRUE(check_host(config, two_cpus).empty());
  config.rt.cpu = 2;
  auto problems = check_host(config, two_cpus);
  ASSERT_EQ(problems.size(), 1U);
  EXPECT_EQ(to_string(problems[0]),
            "rt.cpu: 2 is not a CPU this machine lets liftd run on: use -1 or one of 0-1");
  problems = check_host(config, HostFacts{{0, 1, 3, 4, 5, 7}});
  ASSERT_EQ(problems.size(), 1U);
  EXPECT_THAT(problems[0].message, HasSubstr("one of 0-1,3-5,7"));
  // This machine has fewer than 1024 CPUs: load_file (what both --check-config and the daemon
  // use) refuses the last allowed value.
  EXPECT_THAT(HostFacts::current().usable_cpus, ::testing::Not(::testing::IsEmpty()));
  const std::string path = ::testing::TempDir() + "/cpu1023.json";
  std::ofstream(path) << R"({"rt": {"cpu": 1023}})";
  const LoadResult loaded = kinds::load_config(path);
  ASSERT_EQ(loaded.problems.size(), 1U) << all_problems(loaded);
  EXPECT_EQ(loaded.problems[0].where, "rt.cpu");
}

TEST(ConfigFile, OnlyRegularFilesAreReadAndNeverBlock) {
  // A FIFO nobody writes to would block open() and read() forever. The guard thread waits
  // 10 s, then opens the FIFO's write end and closes it, so a blocked reader gets EOF.
  const std::string fifo = ::testing::TempDir() + "/liftd-config-fifo";
  ::unlink(fifo.c_str());
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  auto loading = std::async(std::launch::async, [&] { return kinds::load_config(fifo); });
  if (loading.wait_for(std::chrono::seconds(10)) != std::future_status::ready) {
    const int fd = ::open(fifo.c_str(), O_WRONLY | O_NONBLOCK);
    if (fd >= 0) ::close(fd);
    ADD_FAILURE() << "load_file blocked on a FIFO";
  }
  const LoadResult from_fifo = loading.get();
  ::unlink(fifo.c_str());
  ASSERT_EQ(from_fifo.problems.size(), 1U) << all_problems(from_fifo);
  EXPECT_EQ(to_string(from_fifo.problems[0]),
            fifo + ": cannot read the config file: it is a FIFO; only a regular file is read");

  // A character device is never opened: /dev/zero would be read until memory runs out (that
  // one is tested on the liftd process, under a memory limit, in tests/daemon); /dev/null shows
  // the rule here without the risk.
  const LoadResult null_device = kinds::load_config("/dev/null");
  ASSERT_EQ(null_device.problems.size(), 1U);
  EXPECT_EQ(to_string(null_device.problems[0]),
            "/dev/null: cannot read the config file: it is a character device; only a regular "
            "file is read");
}

TEST(ConfigFile, SizeLimitAndSymlinks) {
  const std::string dir = ::testing::TempDir();
  const std::string at_limit = dir + "/liftd-at-limit.json";
  std::ofstream(at_limit) << "{}" << std::string(kMaxFileBytes - 2, ' ');
  EXPECT_TRUE(kinds::load_config(at_limit).ok()) << all_problems(kinds::load_config(at_limit));

  const std::string over = dir + "/liftd-over-limit.json";
  std::ofstream(over) << "{}" << std::string(kMaxFileBytes - 1, ' ');
  const LoadResult too_big = kinds::load_config(over);
  ASSERT_EQ(too_big.problems.size(), 1U);
  EXPECT_EQ(to_string(too_big.problems[0]),
            over + ": cannot read the config file: it is larger than 1048576 bytes");

  // A configuration under /etc may be a symbolic link to the real file: followed.
  const std::string target = dir + "/liftd-target.json";
  std::ofstream(target) << R"({"sim": {"dcp": 3}})";
  const std::string link = dir + "/liftd-link.json";
  ::unlink(link.c_str());
  ASSERT_EQ(::symlink(target.c_str(), link.c_str()), 0);
  const LoadResult via_link = kinds::load_config(link);
  ASSERT_TRUE(via_link.ok()) << all_problems(via_link);
  EXPECT_EQ(via_link.config.sim.dcp, 3);
  // ... but a link to a device is refused like the device.
  const std::string to_device = dir + "/liftd-link-null.json";
  ::unlink(to_device.c_str());
  ASSERT_EQ(::symlink("/dev/null", to_device.c_str()), 0);
  EXPECT_THAT(all_problems(kinds::load_config(to_device)), HasSubstr("it is a character device"));
  for (const auto& p : {at_limit, over, target, link, to_device}) ::unlink(p.c_str());
}

TEST(ConfigSpeeds, Dcp3SpeedsFollowTheSpecTable) {
  // DCP 3.5.3.7: speeds in use for 1..7 travelling speeds.
  const std::vector<std::vector<std::string>> expected = {
      {"V4"},
      {"V4", "V3"},
      {"V4", "V3", "V2"},
      {"V4", "V3", "V2", "V1"},
      {"V4", "V3", "V2", "V1", "V7"},
      {"V4", "V3", "V2", "V1", "V7", "V6"},
      {"V4", "V3", "V2", "V1", "V7", "V6", "V5"},
  };
  for (std::size_t i = 0; i < expected.size(); ++i) {
    EXPECT_EQ(dcp3_speeds(static_cast<int>(i + 1)), expected[i]) << i + 1;
  }
}

TEST(ConfigSuggestions, EditDistanceCountsInsertionsDeletionsAndSubstitutions) {
  EXPECT_EQ(edit_distance("", ""), 0U);
  EXPECT_EQ(edit_distance("abc", ""), 3U);
  EXPECT_EQ(edit_distance("level", "levl"), 1U);
  EXPECT_EQ(edit_distance("kitten", "sitting"), 3U);
  EXPECT_EQ(edit_distance("warn", "warning"), 3U);
}

TEST(ConfigReference, HasOneRowPerKey) {
  const std::string table = reference_markdown(schema());
  for (const auto& key : key_paths(schema())) {
    EXPECT_THAT(table, HasSubstr("| `" + key + "` |")) << key;
  }
  EXPECT_EQ(static_cast<std::size_t>(std::count(table.begin(), table.end(), '\n')),
            key_paths(schema()).size() + 2);
}

TEST(ConfigReference, DocsMatchSchema) {
  const std::string doc = read_text(std::string(LIFTD_SOURCE_DIR) + "/docs/config.md");
  const std::string begin = "<!-- BEGIN liftd --print-config-reference -->\n";
  const std::string end = "<!-- END liftd --print-config-reference -->";
  const auto from = doc.find(begin);
  const auto to = doc.find(end);
  ASSERT_NE(from, std::string::npos);
  ASSERT_NE(to, std::string::npos);
  EXPECT_EQ(doc.substr(from + begin.size(), to - from - begin.size()), reference_markdown(schema()))
      << "docs/config.md is stale: regenerate it with liftd --print-config-reference";
}

TEST(ConfigSummary, NamesDriveFloorsAndSocket) {
  const std::string text = summary(Config{}, schema());
  EXPECT_THAT(text, HasSubstr("dcp on /dev/ttyS1"));
  EXPECT_THAT(text, HasSubstr("6, \"0\" at 0 mm to \"5\" at 15000 mm"));
  EXPECT_THAT(text, HasSubstr("/run/liftd/api.sock"));
}

}  // namespace
}  // namespace liftd::config
