// liftctl against the in-process server: output, exit codes, and its messages when the daemon
// is missing.

#include "api/test_support.hpp"
#include "format.hpp"

namespace liftd::api::testing {
namespace {

class Liftctl : public LiftctlFixture {};

TEST_F(Liftctl, StatusPrintsASummary) {
  start_server();
  const RunResult r = run_command(liftctl("status"));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("link:     up"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("drive:    dcp, ready"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("dcp:      DCP4, status: ready"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("car:      floor 1, position 3000 mm"), std::string::npos) << r.output;
}

TEST_F(Liftctl, StatusSaysWhatOfTheDriveHoldsATravelBack) {
  backend_.status_snapshot.drive_kind = drive::Kind::Sch001;
  backend_.status_snapshot.drive_state = drive::State::NotReady;
  start_server();
  const RunResult r = run_command(liftctl("status"));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("drive:    sch001, not_ready (the card reports RDY = 0: no travel "
                          "starts)"),
            std::string::npos)
      << r.output;
}

TEST_F(Liftctl, JsonPrintsTheRawResult) {
  start_server();
  const RunResult r = run_command(liftctl("--json status"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(nlohmann::json::parse(r.output).at("dcp").at("mode"), "DCP4");
}

TEST_F(Liftctl, SocketComesFromTheEnvironment) {
  start_server();
  const RunResult r =
      run_command("LIFTD_SOCKET=" + socket_path() + " " + LIFTCTL_PATH + " version");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("api: 3"), std::string::npos) << r.output;
}

TEST_F(Liftctl, StatsPrintTheNeutralCountersThenTheDriveKinds) {
  backend_.stats_snapshot.frames_sent = 24000;
  backend_.stats_snapshot.details = {{"missing_replies", 6}, {"reply_p99_us", 2210.0}};
  start_server();
  const RunResult r = run_command(liftctl("stats"));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("link:\n  frames_sent: 24000\n"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("dcp:\n  missing_replies: 6\n  reply_p99_us: 2210.0\n"),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("api:\n"), std::string::npos) << r.output;
}

TEST_F(Liftctl, StatsOfAUssLiftPrintTheBussNestedFiguresByPath) {
  backend_.status_snapshot.drive_kind = drive::Kind::Uss;
  backend_.stats_snapshot.drive_kind = drive::Kind::Uss;
  backend_.stats_snapshot.details = {{"receive", {{"bcc", 2}}}};
  start_server();
  const RunResult r = run_command(liftctl("stats"));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("uss:\n  receive.bcc: 2\n"), std::string::npos) << r.output;
}

// A drive kind this liftctl was built without (a fourth kind, a newer daemon): its `stats` and
// `status` objects are printed all the same, under their own name.
TEST(LiftctlFormat, PrintsAnyDriveKindsObjectsWithoutKnowingTheKind) {
  const nlohmann::json stats = {{"link", {{"frames_sent", 5}}},
                                {"cycle", {{"cycles", 5}}},
                                {"canopen", {{"sync_sent", 7}, {"pdo", {{"tx", 3}}}}},
                                {"api", {{"requests", 1}}}};
  EXPECT_EQ(liftctl::format_stats(stats),
            "link:\n  frames_sent: 5\ncycle:\n  cycles: 5\ncanopen:\n  pdo.tx: 3\n  "
            "sync_sent: 7\napi:\n  requests: 1\n");
  const nlohmann::json status = {{"link", {{"state", "up"}}},
                                 {"drive", {{"kind", "canopen"}, {"state", "not_ready"}}},
                                 {"canopen", {{"nmt", "operational"}}}};
  const std::string text = liftctl::format_status(status);
  EXPECT_NE(text.find("drive:    canopen, not_ready (the drive is not ready: no travel starts)"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("canopen:  nmt: operational\n"), std::string::npos) << text;
  EXPECT_EQ(text.find("dcp:"), std::string::npos) << text;
}

TEST_F(Liftctl, CallsCommandsReachTheBackend) {
  backend_.control_result = Result::ok();
  start_server();
  for (const char* args : {"calls add 2", "calls cancel 2", "calls insert 3", "calls insert 1 0",
                           "calls set 0 1 0", "calls set"}) {
    const RunResult r = run_command(liftctl(args));
    EXPECT_EQ(r.exit_code, 0) << args << ": " << r.output;
  }
  EXPECT_EQ(on_io([this] { return backend_.requests_seen; }),
            (std::vector<std::string>{"calls add 2", "calls cancel 2", "calls insert 3",
                                      "calls insert 1 @0", "calls set 0 1 0", "calls set"}));
  for (const char* args : {"calls add", "calls add x", "calls insert", "calls insert 1 2 3",
                           "calls set 1 x", "calls drop 1"}) {
    EXPECT_EQ(run_command(liftctl(args)).exit_code, 2) << args;
  }
}

TEST_F(Liftctl, StatusOfAUssLiftShowsTheDriveProfile) {
  backend_.status_snapshot.drive_kind = drive::Kind::Uss;
  backend_.status_snapshot.details = {
      {"drive_address", 0},
      {"profile_state", "operation_enabled"},
      {"wish", "run"},
      {"phase", "run"},
      {"control_bits", {{"on", true}, {"enable_operation", true}}},
      {"status_bits", {{"ready", true}, {"fault", false}}},
      {"setpoint", {{"raw", 16384}, {"percent", 100.0}}},
      {"actual", {{"raw", 8192}, {"percent", 50.0}}},
      {"slaves",
       {{{"address", 0}, {"responding", true}}, {{"address", 5}, {"responding", false}}}}};
  start_server();
  const RunResult r = run_command(liftctl("status"));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("uss:      drive 0 operation_enabled (asked: run), phase run"),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("words:    control enable_operation on; status ready"), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("speed:    setpoint 100.0 %, actual 50.0 %"), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("slaves:   2 on the bus, not sending: 5"), std::string::npos) << r.output;
}

TEST_F(Liftctl, ErrorReplyExitsWithOne) {
  start_server();
  const RunResult r = run_command(liftctl("travel 99"));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("bad_request: field \"floor\" must be an integer 0..63"),
            std::string::npos)
      << r.output;
}

TEST_F(Liftctl, RawSendsAnyRequest) {
  start_server();
  const RunResult r =
      run_command(liftctl(R"(raw '{"cmd":"inputs","doors_closed":true,"id":"io"}')"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto reply = nlohmann::json::parse(r.output);
  EXPECT_EQ(reply.at("id"), "io");
  EXPECT_EQ(reply.at("result").at("doors_closed"), true);
}

TEST_F(Liftctl, WatchPrintsPlainLinesWhenNotATerminal) {
  start_server();
  // stdout is a pipe here: one plain line per event; SIGINT after a second ends it.
  const RunResult r = run_command("timeout -s INT 1 " + liftctl("watch"));
  EXPECT_NE(r.output.find("state link=up drive=ready mode=DCP4"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("\x1b["), std::string::npos) << "no terminal escapes into a pipe";
}

TEST_F(Liftctl, SaysWhenTheSocketIsMissing) {
  const RunResult r = run_command(liftctl("status"));
  EXPECT_EQ(r.exit_code, 3);
  EXPECT_NE(r.output.find("liftd is not running"), std::string::npos) << r.output;
}

TEST_F(Liftctl, SaysWhenNothingListens) {
  {
    asio::io_context other;
    asio::local::stream_protocol::acceptor stale(
        other, asio::local::stream_protocol::endpoint(socket_path()));
  }
  const RunResult r = run_command(liftctl("status"));
  EXPECT_EQ(r.exit_code, 3);
  EXPECT_NE(r.output.find("nothing listens"), std::string::npos) << r.output;
}

TEST_F(Liftctl, RejectsBadUsage) {
  EXPECT_EQ(run_command(liftctl("")).exit_code, 2);
  EXPECT_EQ(run_command(liftctl("frobnicate")).exit_code, 2);
  EXPECT_EQ(run_command(liftctl("key")).exit_code, 2);
  EXPECT_EQ(run_command(liftctl("raw 'not json'")).exit_code, 2);
}

TEST_F(Liftctl, SocketWithoutAValueSaysWhatIsMissing) {
  const RunResult bare = run_command(std::string(LIFTCTL_PATH) + " --socket");
  EXPECT_EQ(bare.exit_code, 2);
  EXPECT_EQ(bare.output,
            "liftctl: --socket needs a PATH (the API socket, e.g. /run/liftd/api.sock)\n");
  const RunResult empty = run_command(std::string(LIFTCTL_PATH) + " --socket= status");
  EXPECT_EQ(empty.exit_code, 2);
  EXPECT_EQ(empty.output, "liftctl: --socket needs a PATH, got an empty one\n");
}

}  // namespace
}  // namespace liftd::api::testing
