// The request handler without a socket: parsing, ids, schema validation, access, error codes.
#include <gtest/gtest.h>

#include <stdexcept>
#include <string>
#include <vector>

#include "api/commands.hpp"
#include "api/dispatcher.hpp"
#include "api/dispatcher_fixture.hpp"
#include "api/fake_backend.hpp"
#include "common/version.hpp"

namespace liftd::api {
namespace {

using nlohmann::json;
using testing::FakeBackend;
using testing::RefusedRequest;

/// The dispatcher with every command of the daemon, served by the shared fake: the common
/// commands' arguments, access and replies, and every kind's commands known. A kind's own
/// commands served: tests/<kind>/api/dispatcher_test.cpp.
class DispatcherTest : public testing::DispatcherFixture<FakeBackend> {};

TEST_F(DispatcherTest, EchoesIdsOfEveryJsonType) {
  // Legend: the id given in the request, and what the reply's id must be.
  const std::vector<std::pair<std::string, json>> cases = {
      {R"({"cmd":"version","id":7})", 7},
      {R"({"cmd":"version","id":-1.5})", -1.5},
      {R"({"cmd":"version","id":"abc"})", "abc"},
      {R"({"cmd":"version","id":{"a":[1,2]}})", json{{"a", {1, 2}}}},
      {R"({"cmd":"version","id":[1,"x"]})", json::array({1, "x"})},
      {R"({"cmd":"version","id":null})", nullptr},
      {R"({"cmd":"version"})", nullptr},
      {R"({"cmd":"nope","id":"err-id"})", "err-id"},  // echoed on errors too
  };
  for (const auto& [line, id] : cases) {
    const json reply = handle(line);
    EXPECT_EQ(reply.at("id"), id) << line;
  }
}

TEST_F(DispatcherTest, VersionReportsDaemonAndApiVersion) {
  const json reply = handle(R"({"cmd":"version","id":1})");
  ASSERT_TRUE(reply.at("ok").get<bool>());
  EXPECT_EQ(reply.at("result").at("api"), kApiVersion);
  EXPECT_EQ(reply.at("result").at("version"), std::string(kVersion));
}

TEST_F(DispatcherTest, RejectsMalformedRequestsWithTheRightCode) {
  // Legend: request line, expected error code, expected field named ("" = none). The DCP
  // commands' arguments: tests/dcp/api/dispatcher_test.cpp.
  const RefusedRequest cases[] = {
      {"{", "bad_json", ""},                                             // truncated object
      {"cmd=status", "bad_json", ""},                                    // not JSON at all
      {"{\"cmd\":\"status\"} x", "bad_json", ""},                        // trailing garbage
      {"\"\xff\xfe\"", "bad_json", ""},                                  // invalid UTF-8
      {"[1,2]", "bad_request", ""},                                      // array, not object
      {"42", "bad_request", ""},                                         // number, not object
      {"{}", "bad_request", "cmd"},                                      // no cmd
      {R"({"cmd":5})", "bad_request", "cmd"},                            // cmd not a string
      {R"({"cmd":"frobnicate"})", "unknown_cmd", "cmd"},                 // no such command
      {R"({"cmd":"status","verbose":true})", "bad_request", "verbose"},  // unknown field
      {R"({"cmd":"watch"})", "bad_request", "enable"},                   // missing required field
      {R"({"cmd":"watch","enable":1})", "bad_request", "enable"},        // int for bool
      {R"({"cmd":"trace","count":"50"})", "bad_request", "count"},       // string for int
      {R"({"cmd":"trace","count":50.5})", "bad_request", "count"},       // fraction
      {R"({"cmd":"trace","count":18446744073709551615})", "bad_request", "count"},
      {R"({"cmd":"inspection","mode":"sideways"})", "bad_request", "mode"},  // not a choice
      {R"({"cmd":"trace","count":0})", "bad_request", "count"},
      {R"({"cmd":"trace","count":1001})", "bad_request", "count"},
      {R"({"cmd":"travels","last":0})", "bad_request", "last"},
      {R"({"cmd":"travels","last":17})", "bad_request", "last"},
      {R"({"cmd":"travels","last":"5"})", "bad_request", "last"},
      {R"({"cmd":"inputs","doors_open":true})", "bad_request", "doors_open"},
      {R"({"cmd":"inputs","safety_chain":"yes"})", "bad_request", "safety_chain"},
      {R"({"cmd":"inputs","position_mm":1000000})", "bad_request", "position_mm"},
  };
  expect_refused(cases);
}

TEST_F(DispatcherTest, BadRequestMessageSaysWhatIsAllowed) {
  EXPECT_EQ(handle(R"({"cmd":"trace","count":1001})").at("error").at("message"),
            "field \"count\" must be an integer 1..1000");
  EXPECT_EQ(handle(R"({"cmd":"inspection","mode":"x"})").at("error").at("message"),
            "field \"mode\" must be one of \"on\", \"off\"");
  EXPECT_EQ(handle(R"({"cmd":"status","x":1})").at("error").at("message"),
            "unknown field \"x\" (this command takes no arguments)");
}

TEST_F(DispatcherTest, RejectsNestingDeeperThanTheLimit) {
  std::string deep = R"({"cmd":"status","id":)" + std::string(40, '[') + std::string(40, ']') + "}";
  EXPECT_EQ(code_of(handle(deep)), "bad_json");
  // Brackets inside strings do not count.
  std::string in_string = R"({"cmd":"version","id":")" + std::string(100, '[') + "\"}";
  EXPECT_TRUE(handle(in_string).at("ok").get<bool>());
}

TEST_F(DispatcherTest, ChecksAccessPerCommandLevel) {
  // Legend: command line, access level it needs. The DCP commands':
  // tests/dcp/api/dispatcher_test.cpp.
  expect_access_levels({
      {R"({"cmd":"status"})", Access::Read},
      {R"({"cmd":"watch","enable":false})", Access::Read},
      {R"({"cmd":"stats"})", Access::Read},
      {R"({"cmd":"trace"})", Access::Read},
      {R"({"cmd":"travels"})", Access::Read},
      {R"({"cmd":"config"})", Access::Read},
      {R"({"cmd":"version"})", Access::Read},
      {R"({"cmd":"drive_reset"})", Access::Control},
      {R"({"cmd":"inputs","safety_chain":true})", Access::Inputs},
  });
}

TEST_F(DispatcherTest, ForbiddenIsCheckedBeforeArguments) {
  // A peer without access learns nothing about argument rules.
  EXPECT_EQ(code_of(handle(R"({"cmd":"travel","floor":"x"})", AccessSet{true, false, false})),
            "forbidden");
}

TEST_F(DispatcherTest, PassesBackendErrorsThrough) {
  // Legend: the backend's error code, as the client must see it.
  for (const auto code : {ErrorCode::NotReady, ErrorCode::Busy, ErrorCode::Fault}) {
    backend_.control_result = Result::fail(code, "drive says no");
    const json reply = handle(R"({"cmd":"drive_reset","id":3})");
    EXPECT_EQ(code_of(reply), to_string(code));
    EXPECT_EQ(reply.at("error").at("message"), "drive says no");
    EXPECT_EQ(reply.at("id"), 3);
  }
}

TEST_F(DispatcherTest, InputsKeepOmittedFields) {
  handle(R"({"cmd":"inputs","safety_chain":true,"doors_closed":true,"position_mm":1200})");
  const json reply = handle(R"({"cmd":"inputs","doors_closed":false})");
  ASSERT_TRUE(reply.at("ok").get<bool>());
  EXPECT_EQ(reply.at("result").at("safety_chain"), true);
  EXPECT_EQ(reply.at("result").at("doors_closed"), false);
  EXPECT_EQ(reply.at("result").at("position_mm"), 1200);
  EXPECT_EQ(reply.at("result").at("zone_level"), false);
  EXPECT_EQ(reply.at("result").size(), kInputFlags.size() + 1);
}

// status drive.state from the facts every drive kind has, in the order docs/api.md gives:
// `ready` only when the drive lets a travel start (its controller's own check of a start).
TEST(DriveState, IsReadyOnlyWhenTheDriveLetsATravelStart) {
  struct Case {
    const char* legend;
    bool link_up, travelling, any_fault, drive_allows_travel;
    const char* state;
  };
  const Case cases[] = {
      {"no link", false, false, false, true, "offline"},
      {"no link, whatever else", false, true, true, false, "offline"},
      {"a travel runs, even with a fault and S0 = 0", true, true, true, false, "travelling"},
      {"an active fault", true, false, true, true, "fault"},
      {"an active fault and a drive not ready", true, false, true, false, "fault"},
      {"the drive lets no travel start (S0 = 0, RDY = 0, USS local control)", true, false, false,
       false, "not_ready"},
      {"the drive lets a travel start", true, false, false, true, "ready"},
  };
  for (const Case& c : cases) {
    EXPECT_EQ(drive::to_string(
                  drive::state_of(c.link_up, c.travelling, c.any_fault, c.drive_allows_travel)),
              c.state)
        << c.legend;
  }
}

TEST_F(DispatcherTest, StatusSaysNotReady) {
  backend_.status_snapshot.drive_state = drive::State::NotReady;
  const json r = handle(R"({"cmd":"status"})").at("result");
  EXPECT_EQ(r.at("drive").at("state"), "not_ready");
}

TEST_F(DispatcherTest, StatusNamesEveryField) {
  backend_.status_snapshot.details.edit()["status"]["advance_warning"] = true;
  backend_.status_snapshot.faults.push_back(
      {"link_timeout", "no reply for 150 ms", std::chrono::system_clock::time_point{}});
  const json r = handle(R"({"cmd":"status"})").at("result");
  EXPECT_EQ(r.at("drive").at("kind"), "dcp");
  EXPECT_EQ(r.at("drive").at("state"), "ready");
  EXPECT_EQ(r.at("link").at("state"), "up");
  // The drive kind's own object, under its name.
  EXPECT_EQ(r.at("dcp"), *backend_.status_snapshot.details);
  EXPECT_EQ(r.at("dcp").at("status").at("advance_warning"), true);
  EXPECT_EQ(r.at("car"), (json{{"position_mm", 3000},
                               {"floor", 1},
                               {"next_possible_stop", nullptr},
                               {"brake_open", false},
                               {"contactors_on", false},
                               {"doors", nullptr},
                               {"motion", "standing"}}));
  EXPECT_EQ(r.at("service"), (json{{"in_service", true}, {"reason", nullptr}}));
  EXPECT_EQ(r.at("travel").at("state"), "idle");
  EXPECT_EQ(r.at("faults").at(0).at("since"), "1970-01-01T00:00:00.000Z");
  EXPECT_EQ(r.at("rt").at("policy"), "SCHED_FIFO");
}

TEST_F(DispatcherTest, StatusUsesNullForUnknowns) {
  backend_.status_snapshot = StatusSnapshot{};
  const json r = handle(R"({"cmd":"status"})").at("result");
  EXPECT_EQ(r.at("link").at("state"), "down");
  EXPECT_EQ(r.at("drive").at("state"), "offline");
  EXPECT_TRUE(r.at("car").at("position_mm").is_null());
  EXPECT_TRUE(r.at("car").at("floor").is_null());
}

// status serialises an unchanged snapshot once; every change of any field must still show.
// Each fact once: what only one drive kind has is under the kind's name, nowhere else.
TEST_F(DispatcherTest, StatusOfADcpLiftHasItsFactsUnderDcpOnly) {
  const json r = handle(R"({"cmd":"status"})").at("result");
  EXPECT_EQ(r.at("drive"), (json{{"kind", "dcp"}, {"state", "ready"}}));
  EXPECT_EQ(r.at("link"), (json{{"state", "up"}}));
  for (const char* key : {"mode", "status", "extended", "handshake_problem"}) {
    EXPECT_TRUE(r.at("dcp").contains(key)) << key;
  }
}

TEST_F(DispatcherTest, StatsPutTheKindsOwnCountersUnderItsName) {
  for (const std::string_view kind : drive::kKindNames) {  // every registered kind
    const std::string name(kind);
    backend_.stats_snapshot.drive_kind = *drive::parse_kind(kind);
    backend_.stats_snapshot.frames_sent = 7;
    backend_.stats_snapshot.cycles = 9;
    backend_.stats_snapshot.dropped_events = 1;
    backend_.stats_snapshot.dropped_travel_samples = 2;
    backend_.stats_snapshot.details = {{"own_counter", 3}};
    const json r = handle(R"({"cmd":"stats"})").at("result");
    EXPECT_EQ(r.at("link"), (json{{"frames_sent", 7}})) << name;
    EXPECT_EQ(r.at("cycle"),
              (json{{"cycles", 9}, {"dropped_events", 1}, {"dropped_travel_samples", 2}}))
        << name;
    EXPECT_EQ(r.at(name), (json{{"own_counter", 3}})) << name;
    EXPECT_EQ(r.size(), 4U) << r.dump();  // and "api"
  }
}

TEST_F(DispatcherTest, StatusShowsEveryChangeBetweenRequests) {
  const auto position = [this] {
    return handle(R"({"cmd":"status"})").at("result").at("car").at("position_mm");
  };
  EXPECT_EQ(position(), 3000);
  EXPECT_EQ(position(), 3000);  // served from the cache
  backend_.status_snapshot.position_mm = 3001;
  EXPECT_EQ(position(), 3001);
  backend_.status_snapshot.rt.priority = 7;  // a field deep in the snapshot
  EXPECT_EQ(handle(R"({"cmd":"status"})").at("result").at("rt").at("priority"), 7);
  backend_.status_snapshot.faults.push_back(
      {"link_timeout", "no reply", std::chrono::system_clock::time_point{}});
  EXPECT_EQ(handle(R"({"cmd":"status"})").at("result").at("faults").size(), 1u);
  backend_.status_snapshot.faults.back().since += std::chrono::milliseconds(1);
  EXPECT_EQ(handle(R"({"cmd":"status"})").at("result").at("faults").at(0).at("since"),
            "1970-01-01T00:00:00.001Z");
}

TEST(ResultSerialized, ValueParsesTheText) {
  const Result r = Result::ok_serialized(std::make_shared<const std::string>(R"({"a":[1,2]})"));
  EXPECT_TRUE(r.is_ok());
  EXPECT_EQ(r.value(), (json{{"a", {1, 2}}}));
  EXPECT_EQ(reply_line(5, r), "{\"id\":5,\"ok\":true,\"result\":{\"a\":[1,2]}}\n");
}

TEST_F(DispatcherTest, TraceReturnsNewestFramesAsHex) {
  for (int i = 0; i < 5; ++i) {
    TraceEntry e;
    e.at = std::chrono::milliseconds(15 * i);
    e.tx = {0x01, 0x00, 0x00, 0x00, 0x00, 0x01};
    if (i != 4) e.rx = std::vector<std::uint8_t>{0x21, 0x7F, 0xFF, 0x00, 0x00, 0xA1};
    backend_.trace_entries.push_back(e);
  }
  const json frames = handle(R"({"cmd":"trace","count":2})").at("result").at("frames");
  ASSERT_EQ(frames.size(), 2U);
  EXPECT_EQ(frames[0],
            (json{{"t_us", 45000}, {"tx", "01 00 00 00 00 01"}, {"rx", "21 7F FF 00 00 A1"}}));
  EXPECT_TRUE(frames[1].at("rx").is_null());
}

TEST_F(DispatcherTest, TravelsAsksTheBackendForTheLastTravelsFiveByDefault) {
  backend_.travels_result = {{"travels", json::array({{{"id", 3}}})}, {"dropped_samples", 0}};
  EXPECT_EQ(handle(R"({"cmd":"travels"})").at("result"), backend_.travels_result);
  EXPECT_EQ(backend_.travels_asked, 5U);
  EXPECT_TRUE(handle(R"({"cmd":"travels","last":16})").at("ok").get<bool>());
  EXPECT_EQ(backend_.travels_asked, 16U);
}

TEST_F(DispatcherTest, WatchTogglesTheSessionAndSendsCurrentState) {
  EXPECT_EQ(handle(R"({"cmd":"watch","enable":true})").at("result").at("watching"), true);
  EXPECT_TRUE(session_.watching());
  ASSERT_EQ(session_.events.size(), 1U);
  EXPECT_EQ(json::parse(session_.events[0]).at("event"), "state");
  handle(R"({"cmd":"watch","enable":false})");
  EXPECT_FALSE(session_.watching());
  EXPECT_EQ(session_.events.size(), 1U);
}

TEST_F(DispatcherTest, HandlerExceptionBecomesInternal) {
  dispatcher_.add({"explode",
                   Access::Read,
                   {},
                   "throws",
                   [](const Call&, Responder) { throw std::runtime_error("boom"); },
                   kEveryDriveKind});
  const json reply = handle(R"({"cmd":"explode","id":9})");
  EXPECT_EQ(code_of(reply), "internal");
  EXPECT_EQ(reply.at("id"), 9);
}

TEST_F(DispatcherTest, DroppedResponderBecomesInternal) {
  dispatcher_.add({"forget",
                   Access::Read,
                   {},
                   "never answers",
                   [](const Call&, Responder) {},
                   kEveryDriveKind});
  EXPECT_EQ(code_of(handle(R"({"cmd":"forget"})")), "internal");
}

TEST_F(DispatcherTest, TooManyRequestsInFlightIsBusy) {
  session_.in_flight = DispatchLimits{}.max_in_flight + 1;
  EXPECT_EQ(code_of(handle(R"({"cmd":"status"})")), "busy");
}

TEST_F(DispatcherTest, AddingACommandIsOneEntry) {
  ArgSpec floor;
  floor.name = "floor";
  floor.type = ArgType::Integer;
  floor.required = true;
  floor.min = 0;
  floor.max = 63;
  dispatcher_.add({"goto",
                   Access::Control,
                   {floor},
                   "travel to a floor",
                   [](const Call& call, Responder done) {
                     done(Result::ok({{"floor", call.request.at("floor")}}));
                   },
                   kEveryDriveKind});
  EXPECT_EQ(handle(R"({"cmd":"goto","floor":4})").at("result").at("floor"), 4);
  EXPECT_EQ(code_of(handle(R"({"cmd":"goto","floor":64})")), "bad_request");
  EXPECT_EQ(code_of(handle(R"({"cmd":"goto","floor":4})", AccessSet{true, false, false})),
            "forbidden");
  EXPECT_THROW(dispatcher_.add(
                   {"goto", Access::Read, {}, "", [](const Call&, Responder) {}, kEveryDriveKind}),
               std::invalid_argument);
}

TEST(JsonNestingDepth, CountsOutsideStringsOnly) {
  // Legend: text, its nesting depth.
  const std::vector<std::pair<std::string, int>> cases = {
      {"{}", 1},
      {"[[]]", 2},
      {R"({"a":[{"b":1}]})", 3},
      {R"({"a":"[[[["})", 1},
      {R"({"a":"\"[[["})", 1},
      {"1", 0},
      {"]]]]", 0},
  };
  for (const auto& [text, depth] : cases) EXPECT_EQ(json_nesting_depth(text, 32), depth) << text;
  EXPECT_EQ(json_nesting_depth(std::string(100, '['), 32), 33);
}

// Reply and event lines are written without building a whole reply object; their bytes must be
// exactly those of the object dumped compactly (keys in sorted order), for every kind of id.
TEST(ReplyLine, BytesAreThoseOfTheDumpedObject) {
  const json result = {{"floor", 3}, {"name", "Lobby \u00e9"}, {"list", {1, 2.5, nullptr}}};
  for (const json& id :
       {json(nullptr), json(7), json(-1.5), json("a\"b"), json({1, "x"}), json({{"k", true}})}) {
    SCOPED_TRACE(id.dump());
    EXPECT_EQ(reply_line(id, Result::ok(result)),
              json({{"id", id}, {"ok", true}, {"result", result}}).dump() + "\n");
    EXPECT_EQ(reply_line(id, Result::fail(ErrorCode::BadRequest, "no", "cmd")),
              json({{"id", id},
                    {"ok", false},
                    {"error", {{"code", "bad_request"}, {"message", "no"}, {"field", "cmd"}}}})
                      .dump() +
                  "\n");
  }
  EXPECT_EQ(event_line("state", result),
            json({{"event", "state"}, {"data", result}}).dump() + "\n");
  // Invalid UTF-8 is replaced, never thrown, in both halves.
  EXPECT_EQ(event_line("x", json("\xff")), "{\"data\":\"\xef\xbf\xbd\",\"event\":\"x\"}\n");
}

// A lift whose drive kind lacks a capability: its commands are refused before their arguments
// are looked at, the common commands still reach the backend, and status carries the kind's
// own object and none of the API 1 DCP fields.
class OtherDriveKindTest : public DispatcherTest {
 protected:
  OtherDriveKindTest() {
    backend_.status_snapshot.drive_kind = drive::Kind::Sch001;
    backend_.status_snapshot.details = nlohmann::json{{"card", "ok"}};
    dispatcher_ = Dispatcher{};
    add_every_command(dispatcher_, backend_);
  }
};

TEST_F(OtherDriveKindTest, DriveSpecificCommandsAreNotOffered) {
  struct Case {
    const char* request;
    const char* capability;
  };
  for (const Case& c : {Case{R"({"cmd":"key","key":1})", "keypad"},
                        Case{R"({"cmd":"key","key":99})", "keypad"},  // before the range check
                        Case{R"({"cmd":"display"})", "display"},
                        Case{R"({"cmd":"power","supply":"mains"})", "power"},
                        Case{R"({"cmd":"load","percent":50})", "load"},
                        Case{R"({"cmd":"drive_reset"})", "drive_reset"},
                        Case{R"({"cmd":"fast_start","action":"go"})", "fast_start"},
                        Case{R"({"cmd":"fast_stop"})", "fast_stop"},
                        Case{R"({"cmd":"uss_read","pnu":52})", "parameters"},
                        Case{R"({"cmd":"uss_write","pnu":99999,"value":1})", "parameters"},
                        Case{R"({"cmd":"uss_mirror"})", "parameters"}}) {
    const json reply = handle(c.request);
    EXPECT_EQ(code_of(reply), "not_offered") << c.request;
    const std::string name = json::parse(c.request).at("cmd");
    EXPECT_EQ(reply.at("error").at("message"),
              "\"" + name + "\" is not offered by drive kind \"sch001\" (it has no " +
                  c.capability + " function)");
  }
  EXPECT_TRUE(backend_.requests_seen.empty()) << "a refused command reached the backend";
}

TEST_F(OtherDriveKindTest, CommonCommandsStillRun) {
  // The fake has no travel control: the backend's own refusal proves the request reached it.
  for (const char* request :
       {R"({"cmd":"travel","floor":2})", R"({"cmd":"stop"})", R"({"cmd":"relevel"})",
        R"({"cmd":"calls"})", R"({"cmd":"inspection","mode":"on"})"}) {
    EXPECT_EQ(handle(request).at("error").at("message"),
              "this daemon has no travel control for its drive")
        << request;
  }
  EXPECT_TRUE(handle(R"({"cmd":"inputs","safety_chain":true})").at("ok").get<bool>());
  const json r = handle(R"({"cmd":"status"})").at("result");
  EXPECT_EQ(r.at("drive"), (json{{"kind", "sch001"}, {"state", "ready"}}));
  EXPECT_EQ(r.at("sch001"), (json{{"card", "ok"}}));
  EXPECT_FALSE(r.contains("dcp"));
  EXPECT_FALSE(r.at("link").contains("handshake_problem"));
}

}  // namespace
}  // namespace liftd::api
