// docs/api.md and docs/api.schema.json must describe every command, error code, event, fault
// code and travel abort cause the daemon can send.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <optional>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "api/commands.hpp"
#include "api/fake_backend.hpp"

namespace liftd::api {
namespace {

std::string read_docs() {
  std::ifstream in(API_DOCS_PATH);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

TEST(ApiDocs, EveryCommandHasASection) {
  const std::string docs = read_docs();
  ASSERT_FALSE(docs.empty()) << API_DOCS_PATH;
  testing::FakeBackend backend;
  Dispatcher dispatcher;
  add_every_command(dispatcher, backend);
  for (const auto& name : dispatcher.names()) {
    EXPECT_NE(docs.find("### `" + name + "`"), std::string::npos) << name << " is not documented";
  }
}

// The client section tells a client author which version to expect: the one the daemon says.
TEST(ApiDocs, TheClientSectionNamesTheApiVersionTheDaemonSpeaks) {
  const std::string docs = read_docs();
  EXPECT_NE(docs.find("check `api` is `" + std::to_string(kApiVersion) + "`"), std::string::npos);
  EXPECT_NE(docs.find("# liftd JSON API reference (API version " + std::to_string(kApiVersion)),
            std::string::npos);
}

TEST(ApiDocs, EveryErrorCodeIsListed) {
  // Every value to_string() names (it answers "internal" past the last one), so a code added at
  // the end of the enum cannot slip past this test.
  std::set<std::string> codes;
  for (int i = 0; i < 256; ++i) {
    const auto code = static_cast<ErrorCode>(i);
    const auto name = std::string(to_string(code));
    if (name != "internal" || code == ErrorCode::Internal) codes.insert(name);
  }
  EXPECT_TRUE(codes.count("not_offered"));
  const std::string docs = read_docs();
  for (const auto& name : codes) {
    EXPECT_NE(docs.find("| `" + name + "`"), std::string::npos) << name << " is not in the table";
  }
  std::ifstream in(API_SCHEMA_PATH);
  const auto schema = nlohmann::json::parse(in);
  const auto& listed = schema.at("$defs").at("error").at("properties").at("code").at("enum");
  EXPECT_EQ(std::set<std::string>(listed.begin(), listed.end()), codes);
}

TEST(ApiDocs, EveryInputIsListed) {
  const std::string docs = read_docs();
  for (const auto& flag : kInputFlags) {
    EXPECT_NE(docs.find("| `" + std::string(flag.name) + "`"), std::string::npos) << flag.name;
  }
}

TEST(ApiSchema, RequestsMatchTheCommandTable) {
  std::ifstream in(API_SCHEMA_PATH);
  const auto schema = nlohmann::json::parse(in);
  const auto& defs = schema.at("$defs");
  testing::FakeBackend backend;
  Dispatcher dispatcher;
  add_every_command(dispatcher, backend);
  for (const auto& name : dispatcher.names()) {
    const auto it = defs.find("request_" + name);
    ASSERT_NE(it, defs.end()) << name << " has no request schema";
    const auto& props = it->at("properties");
    const CommandSpec& spec = *dispatcher.find(name);
    EXPECT_EQ(props.size(), spec.args.size() + 2) << name << ": fields differ (besides cmd, id)";
    auto required = it->at("required");
    for (const auto& arg : spec.args) {
      ASSERT_TRUE(props.contains(arg.name)) << name << "." << arg.name << " missing in schema";
      const auto& p = props.at(arg.name);
      const bool listed = std::find(required.begin(), required.end(), arg.name) != required.end();
      EXPECT_EQ(listed, arg.required) << name << "." << arg.name;
      switch (arg.type) {
        case ArgType::Bool:
          EXPECT_EQ(p.at("type"), "boolean") << name << "." << arg.name;
          break;
        case ArgType::Integer:
          EXPECT_EQ(p.at("type"), "integer") << name << "." << arg.name;
          EXPECT_EQ(p.at("minimum"), arg.min) << name << "." << arg.name;
          EXPECT_EQ(p.at("maximum"), arg.max) << name << "." << arg.name;
          break;
        case ArgType::String:
          if (arg.choices.empty()) {  // any text the command itself checks (a time, a cause)
            EXPECT_EQ(p.at("type"), "string") << name << "." << arg.name;
          } else {
            EXPECT_EQ(p.at("enum"), nlohmann::json(arg.choices)) << name << "." << arg.name;
          }
          break;
        case ArgType::Any:
          break;
      }
    }
  }
}

// `sim` is served only by liftd --simulate; every other backend refuses it the documented way.
TEST(ApiDocs, SimIsRefusedWithoutASimulatorAsDocumented) {
  testing::FakeBackend backend;
  std::optional<Result> result;
  backend.sim(SimRequest{}, [&](Result r) { result = std::move(r); });
  ASSERT_TRUE(result.has_value());
  ASSERT_FALSE(result->is_ok());
  EXPECT_EQ(result->error().code, ErrorCode::NotReady);
  EXPECT_EQ(result->error().message, "only with liftd --simulate");
  EXPECT_NE(read_docs().find("\"only with liftd --simulate\""), std::string::npos)
      << "docs/api.md, section sim, must name the refusal";
}

// ---- the event stream, fault codes and abort causes ----
//
// The lists below are what a client sees on the wire. Each test checks the list three ways:
// against the daemon's source (so a new name in the code fails here until it is documented),
// against docs/api.md (a table row per name) and against the schema's enums.

/// Root of the source tree: API_DOCS_PATH is "<root>/docs/api.md".
std::string source_root() {
  const std::string docs = API_DOCS_PATH;
  const std::string tail = "docs/api.md";
  return docs.substr(0, docs.size() - tail.size());
}

std::string read_source(const std::string& relative) {
  std::ifstream in(source_root() + relative);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

nlohmann::json read_schema() {
  std::ifstream in(API_SCHEMA_PATH);
  return nlohmann::json::parse(in);
}

/// Every match of the first group of `pattern` in `text`, sorted and without duplicates.
std::set<std::string> matches(const std::string& text, const std::string& pattern) {
  std::set<std::string> out;
  const std::regex re(pattern);
  for (auto it = std::sregex_iterator(text.begin(), text.end(), re); it != std::sregex_iterator();
       ++it) {
    out.insert((*it)[1].str());
  }
  return out;
}

/// The string literals a name function returns: the `return "...";` lines of the function whose
/// definition starts with `signature`, up to its closing brace at column 0, minus `fallbacks`.
std::set<std::string> returned_names(const std::string& relative, const std::string& signature,
                                     const std::set<std::string>& fallbacks) {
  const std::string text = read_source(relative);
  const auto begin = text.find(signature);
  if (begin == std::string::npos) return {};
  const auto end = text.find("\n}\n", begin);
  std::set<std::string> out = matches(text.substr(begin, end - begin), R"re(return "([^"]+)";)re");
  for (const auto& f : fallbacks) out.erase(f);
  return out;
}

std::set<std::string> as_set(const std::vector<std::string>& names) {
  return {names.begin(), names.end()};
}

/// The names of a schema enum, without a null member.
std::set<std::string> schema_enum(const nlohmann::json& values) {
  std::set<std::string> out;
  for (const auto& v : values) {
    if (v.is_string()) out.insert(v.get<std::string>());
  }
  return out;
}

void expect_table_rows(const std::vector<std::string>& names, const char* what) {
  const std::string docs = read_docs();
  for (const auto& name : names) {
    EXPECT_NE(docs.find("| `" + name + "` |"), std::string::npos)
        << what << " \"" << name << "\" has no row in docs/api.md";
  }
}

// Every event the daemon publishes: the server's greeting, the watch start, the lifts.
const std::vector<std::string> kEvents = {
    "hello",    "state",        "display",           "link",   "travel",      "drive_error",
    "fault",    "call_served",  "parameter_changed", "missed", "watch_ended", "learn",
    "stopping", "calls_dropped"};

TEST(ApiDocs, EventListMatchesWhatTheDaemonPublishes) {
  std::set<std::string> published;
  for (const char* lift :
       {"lib/dcp/host/dcp_lift.cpp", "lib/sch001/host/hydraulic_lift.cpp",
        "lib/uss/host/uss_lift.cpp", "lib/host/lift_core.cpp", "lib/host/learn_report.cpp"}) {
    const std::string app = read_source(lift);
    for (const auto& pattern : {R"re(\bname = "([a-z_]+)";)re", R"re(publish\(\s*"([a-z_]+)")re"}) {
      published.merge(matches(app, pattern));
    }
  }
  published.merge(matches(read_source("lib/api/server.cpp"), R"re(event_line\("([a-z_]+)")re"));
  published.merge(
      matches(read_source("lib/host/controller_lift.hpp"), R"re(announce\(\s*"([a-z_]+)")re"));
  published.merge(matches(read_source("lib/api/commands.cpp"), R"re(event_line\("([a-z_]+)")re"));
  EXPECT_EQ(published, as_set(kEvents)) << "update kEvents, docs/api.md section 4 and the schema";
}

TEST(ApiDocs, EveryEventIsDocumentedWithASchema) {
  expect_table_rows(kEvents, "event");
  const auto schema = read_schema();
  std::set<std::string> described;
  for (const auto& branch : schema.at("$defs").at("event").at("allOf")) {
    described.insert(branch.at("if").at("properties").at("event").at("const").get<std::string>());
  }
  EXPECT_EQ(described, as_set(kEvents)) << "every event needs an if/then branch in $defs/event";
}

const std::vector<std::string> kFaultCodes = {"link_fault",  "drive_fault",   "safety_chain_open",
                                              "inputs_lost", "position_lost", "advance_warning"};

TEST(ApiDocs, FaultCodesMatchTheController) {
  EXPECT_EQ(
      returned_names("lib/lift/faults.cpp", "std::string_view fault_code_name(", {"internal"}),
      as_set(kFaultCodes));
  expect_table_rows(kFaultCodes, "fault code");
  const auto schema = read_schema();
  const auto& defs = schema.at("$defs");
  EXPECT_EQ(schema_enum(defs.at("fault").at("properties").at("code").at("enum")),
            as_set(kFaultCodes));
  EXPECT_EQ(schema_enum(defs.at("event_fault").at("properties").at("code").at("enum")),
            as_set(kFaultCodes));
}

const std::vector<std::string> kAbortCauses = {
    "link_down",           "no_handshake",       "drive_not_ready",     "advance_warning",
    "drive_fault",         "safety_chain_open",  "doors_not_locked",    "position_lost",
    "inputs_lost",         "door_reversal",      "fast_start_timeout",  "stop_requested",
    "drive_did_not_start", "drive_did_not_stop", "mode_changed",        "stopped_off_level",
    "level_not_reached",   "target_refused",     "shutting_down",       "card_silent",
    "bus_fault",           "travel_timeout",     "speed_not_configured"};

TEST(ApiDocs, AbortCausesMatchTheTravelLibrary) {
  // Every drive kind's causes: one enum, one name table (lib/lift/cause).
  const std::set<std::string> causes =
      returned_names("lib/lift/cause.cpp", "to_string(Cause cause)", {"none"});
  EXPECT_EQ(causes, as_set(kAbortCauses));
  expect_table_rows(kAbortCauses, "abort cause");
  const auto schema = read_schema();
  const auto& travel = schema.at("$defs").at("event_travel").at("properties");
  EXPECT_EQ(schema_enum(travel.at("cause").at("enum")), as_set(kAbortCauses));
  EXPECT_TRUE(travel.at("cause").at("enum").back().is_null()) << "cause is null unless aborted";
}

const std::vector<std::string> kTravelEvents = {
    "started",        "finished",         "aborted",     "target_extended",
    "target_refused", "fast_start_armed", "drive_fault", "drive_fault_cleared"};

TEST(ApiDocs, TravelEventTypesMatchTheTravelLibrary) {
  EXPECT_EQ(returned_names("lib/dcp/travel/types.cpp", "to_string(Event::Type type)", {}),
            as_set(kTravelEvents));
  expect_table_rows(kTravelEvents, "travel event");
  const auto schema = read_schema();
  const auto& travel = schema.at("$defs").at("event_travel").at("properties");
  EXPECT_EQ(schema_enum(travel.at("event").at("enum")), as_set(kTravelEvents));
}

// Travel kinds as status.travel.state and the travel event's kind ("none" only in events).
const std::vector<std::string> kTravelKinds = {"distance", "relevel_distance", "speed",
                                               "crawl",    "inspection",       "recall",
                                               "relevel",  "hydraulic",        "learn"};

TEST(ApiDocs, TravelKindsMatchTheTravelLibrary) {
  std::set<std::string> named =
      returned_names("lib/dcp/travel/types.cpp", "to_string(TravelKind kind)", {"none"});
  // The kinds of the travels that run through the lift core: lift's, and each sequencer's own
  // name of a travel to a floor, wherever in lib/ it gives one.
  named.merge(
      returned_names("lib/lift/travel_event.hpp", "std::string_view travel_kind_name(", {"idle"}));
  for (const auto& entry : std::filesystem::recursive_directory_iterator(source_root() + "lib")) {
    if (entry.path().extension() != ".hpp") continue;
    const std::string relative = entry.path().string().substr(source_root().size());
    named.merge(matches(read_source(relative), R"re(travel_kind_name\(kind, "([^"]+)"\))re"));
  }
  EXPECT_EQ(named, as_set(kTravelKinds));
  expect_table_rows(kTravelKinds, "travel kind");
  const auto schema = read_schema();
  const auto& defs = schema.at("$defs");
  std::set<std::string> states = as_set(kTravelKinds);
  states.insert({"idle", "fast_start"});
  EXPECT_EQ(schema_enum(defs.at("result_status")
                            .at("properties")
                            .at("travel")
                            .at("properties")
                            .at("state")
                            .at("enum")),
            states);
  std::set<std::string> kinds = as_set(kTravelKinds);
  kinds.insert("none");
  EXPECT_EQ(schema_enum(defs.at("event_travel").at("properties").at("kind").at("enum")), kinds);
}

const std::vector<std::string> kLinkEventKinds = {
    "state changed",   "channel reset",  "channel error",     "decode error", "request timeout",
    "unmatched reply", "date/time sent", "handshake problem", "tolerated"};

TEST(ApiDocs, LinkEventsMatchTheMasterLink) {
  EXPECT_EQ(returned_names("lib/dcp/master_link.cpp", "to_string(LinkEventKind kind)", {"unknown"}),
            as_set(kLinkEventKinds));
  expect_table_rows(kLinkEventKinds, "link event kind");
  const auto schema = read_schema();
  const auto& link = schema.at("$defs").at("event_link").at("properties");
  EXPECT_EQ(schema_enum(link.at("kind").at("enum")), as_set(kLinkEventKinds));
  EXPECT_EQ(schema_enum(link.at("state").at("enum")),
            returned_names("lib/dcp/master_link.cpp", "to_string(LinkState state)", {"unknown"}));
}

}  // namespace
}  // namespace liftd::api
