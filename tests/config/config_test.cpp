// The configuration schema: defaults, every kind of problem, the example file, the generated
// reference in docs/config.md.
#include "config/config.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>
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
      {"/dcp/manufacturer", "LI"},
      {"/dcp/language", "EN"},
      {"/dcp/data_info_type", "0"},
      {"/dcp/extended_position", true},
      {"/dcp/link_fault_frames", 10},
      {"/dcp/link_recover_frames", 10},
      {"/dcp/request_timeout_ms", 2000},
      {"/rt/priority", 80},
      {"/rt/cpu", -1},
      {"/rt/lock_memory", true},
      {"/rt/flight_recorder_s", 30},
      {"/rt/send_window_us", 1375},
      {"/api/socket", "/run/liftd/api.sock"},
      {"/api/socket_group", "liftd"},
      {"/api/read_group", "liftd"},
      {"/api/control_group", "liftd-control"},
      {"/api/inputs_group", "liftd-io"},
      {"/api/max_clients", 32},
      {"/api/idle_timeout_s", 0},
      {"/api/state_rate_hz", 10},
      {"/inputs/timeout_ms", 500},
      {"/position/source", "api"},
      {"/travel/level_tolerance_mm", 5},
      {"/travel/relevel_threshold_mm", 15},
      {"/travel/relevel_with_doors", "both"},
      {"/travel/relevel_electric_stop", false},
      {"/travel/use_start_parameters", true},
      {"/travel/fast_start_timeout_ms", 3000},
      {"/travel/inspection_hold_ms", 500},
      {"/travel/dcp3_stop_lead_mm", 0},
      {"/travel/dcp3_speed_count", 2},
      {"/travel/dcp3_decel_distance_mm", {{"V4", 2500}, {"V3", 1200}}},
      {"/sim/dcp", 4},
  };
  const LoadResult result = parse("{}", "test");
  ASSERT_TRUE(result.ok()) << all_problems(result);
  const json dumped = to_json(result.config);
  for (const auto& [pointer, value] : expected) {
    EXPECT_EQ(dumped.at(json::json_pointer(pointer)), value) << pointer;
  }
  EXPECT_EQ(dumped.at("floors").size(), 6U);
  EXPECT_EQ(dumped.at("floors")[5], (json{{"name", "5"}, {"level_mm", 15000}}));
  // Every schema key has a default in the dump, and nothing else is there.
  std::size_t leaves = 0;
  for (const auto& path : key_paths()) {
    std::string pointer = "/" + path;
    std::replace(pointer.begin(), pointer.end(), '.', '/');
    EXPECT_TRUE(dumped.contains(json::json_pointer(pointer))) << path;
    ++leaves;
  }
  EXPECT_EQ(leaves, expected.size() + 1);  // + floors
}

TEST(ConfigDefaults, DefaultConstructedConfigMatchesParsedDefaults) {
  EXPECT_EQ(to_json(Config{}), to_json(parse("{}", "test").config));
}

TEST(ConfigExample, ShippedExampleIsValidCompleteAndAtDefaults) {
  const std::string path = std::string(LIFTD_SOURCE_DIR) + "/config/liftd.json";
  const LoadResult result = load_file(path);
  ASSERT_TRUE(result.ok()) << all_problems(result);
  const json file = json::parse(read_text(path));
  for (const auto& key : key_paths()) {
    std::string pointer = "/" + key;
    std::replace(pointer.begin(), pointer.end(), '.', '/');
    EXPECT_TRUE(file.contains(json::json_pointer(pointer))) << key << " missing from the example";
  }
  EXPECT_EQ(to_json(result.config), to_json(Config{}));
}

TEST(ConfigValues, EveryKeyReachesTheTypedStruct) {
  const std::string text = R"({
    "log": {"level": "debug"},
    "drive": {"kind": "uss", "device": "/dev/ttyUSB0", "rs485": "required"},
    "dcp": {"manufacturer": "KN", "language": "DE", "data_info_type": "3",
            "extended_position": false, "link_fault_frames": 20, "link_recover_frames": 5,
            "request_timeout_ms": 100},
    "rt": {"priority": 99, "cpu": 1023, "lock_memory": false, "flight_recorder_s": 300},
    "api": {"socket": "/tmp/x.sock", "socket_group": "a", "read_group": "b",
            "control_group": "c_d", "inputs_group": "e-f", "max_clients": 256,
            "idle_timeout_s": 86400},
    "inputs": {"timeout_ms": 50},
    "floors": [{"name": "UG", "level_mm": -2800}, {"name": "EG", "level_mm": 0}],
    "position": {"source": "can"},
    "travel": {"level_tolerance_mm": 1, "relevel_threshold_mm": 2,
               "relevel_with_doors": "never", "relevel_electric_stop": true,
               "use_start_parameters": false, "fast_start_timeout_ms": 10000,
               "inspection_hold_ms": 100, "dcp3_speed_count": 3,
               "dcp3_decel_distance_mm": {"V4": 2000, "V3": 1000, "V2": 600}},
    "sim": {"dcp": 3}
  })";
  const LoadResult r = parse(text, "test");
  ASSERT_TRUE(r.ok()) << all_problems(r);
  const Config& c = r.config;
  EXPECT_EQ(c.log.level, LogLevel::debug);
  EXPECT_EQ(c.drive.kind, DriveKind::uss);
  EXPECT_EQ(c.drive.device, "/dev/ttyUSB0");
  EXPECT_EQ(c.drive.rs485, Rs485Mode::required);
  EXPECT_EQ(c.dcp.manufacturer, "KN");
  EXPECT_EQ(c.dcp.language, "DE");
  EXPECT_EQ(c.dcp.data_info_type, '3');
  EXPECT_FALSE(c.dcp.extended_position);
  EXPECT_EQ(c.dcp.link_fault_frames, 20);
  EXPECT_EQ(c.dcp.link_recover_frames, 5);
  EXPECT_EQ(c.dcp.request_timeout_ms, 100);
  EXPECT_EQ(c.rt.priority, 99);
  EXPECT_EQ(c.rt.cpu, 1023);
  EXPECT_FALSE(c.rt.lock_memory);
  EXPECT_EQ(c.rt.flight_recorder_s, 300);
  EXPECT_EQ(c.api.socket, "/tmp/x.sock");
  EXPECT_EQ(c.api.socket_group, "a");
  EXPECT_EQ(c.api.read_group, "b");
  EXPECT_EQ(c.api.control_group, "c_d");
  EXPECT_EQ(c.api.inputs_group, "e-f");
  EXPECT_EQ(c.api.max_clients, 256);
  EXPECT_EQ(c.api.idle_timeout_s, 86400);
  EXPECT_EQ(c.inputs.timeout_ms, 50);
  EXPECT_EQ(c.floors, (std::vector<Floor>{{"UG", -2800}, {"EG", 0}}));
  EXPECT_EQ(c.position.source, PositionSource::can);
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
  // The dump reads back to the same configuration.
  const LoadResult again = from_json(to_json(c));
  ASSERT_TRUE(again.ok()) << all_problems(again);
  EXPECT_EQ(to_json(again.config), to_json(c));
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
    const LoadResult r = parse(c.json_text, "test.json");
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
  const LoadResult r = parse(R"({
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
    const LoadResult r = parse(text, "f.json");
    ASSERT_EQ(r.problems.size(), 1U) << text;
    EXPECT_EQ(r.problems[0].where, where) << text;
    EXPECT_THAT(r.problems[0].message, HasSubstr("malformed JSON")) << text;
  }
}

TEST(ConfigProblems, NumberTooLargeIsAProblemNotACrash) {
  // Found by config_fuzz: the JSON library throws out_of_range, not parse_error, for these.
  for (const std::string text : {"1E989299", "{\"rt\": {\"priority\": 1e400}}"}) {
    const LoadResult r = parse(text, "f.json");
    ASSERT_EQ(r.problems.size(), 1U) << text;
    EXPECT_EQ(r.problems[0].where, "f.json") << text;
    EXPECT_EQ(r.problems[0].message, "malformed JSON: a number is too large to represent");
  }
}

TEST(ConfigFile, UnreadableFileNamesThePathAndTheErrnoText) {
  const LoadResult missing = load_file("/nonexistent/liftd.json");
  ASSERT_EQ(missing.problems.size(), 1U);
  EXPECT_EQ(missing.problems[0].where, "/nonexistent/liftd.json");
  EXPECT_THAT(missing.problems[0].message, HasSubstr("No such file or directory"));

  const LoadResult directory = load_file("/");
  ASSERT_EQ(directory.problems.size(), 1U);
  EXPECT_EQ(directory.problems[0].where, "/");
  EXPECT_THAT(directory.problems[0].message, HasSubstr("Is a directory"));
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
  const std::string table = reference_markdown();
  for (const auto& key : key_paths()) {
    EXPECT_THAT(table, HasSubstr("| `" + key + "` |")) << key;
  }
  EXPECT_EQ(static_cast<std::size_t>(std::count(table.begin(), table.end(), '\n')),
            key_paths().size() + 2);
}

TEST(ConfigReference, DocsMatchSchema) {
  const std::string doc = read_text(std::string(LIFTD_SOURCE_DIR) + "/docs/config.md");
  const std::string begin = "<!-- BEGIN liftd --print-config-reference -->\n";
  const std::string end = "<!-- END liftd --print-config-reference -->";
  const auto from = doc.find(begin);
  const auto to = doc.find(end);
  ASSERT_NE(from, std::string::npos);
  ASSERT_NE(to, std::string::npos);
  EXPECT_EQ(doc.substr(from + begin.size(), to - from - begin.size()), reference_markdown())
      << "docs/config.md is stale: regenerate it with liftd --print-config-reference";
}

TEST(ConfigSummary, NamesDriveFloorsAndSocket) {
  const std::string text = summary(Config{});
  EXPECT_THAT(text, HasSubstr("dcp on /dev/ttyS1"));
  EXPECT_THAT(text, HasSubstr("6, \"0\" at 0 mm to \"5\" at 15000 mm"));
  EXPECT_THAT(text, HasSubstr("/run/liftd/api.sock"));
}

}  // namespace
}  // namespace liftd::config
