// The DCP lift's own commands (lib/dcp/host/commands.*) through the request handler, without a
// socket: their arguments, access levels and what reaches the DCP lift's backend, on a dispatcher
// built as the daemon builds a DCP lift's (the common commands, then the registry's).
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "api/dispatcher_fixture.hpp"
#include "dcp/api/fake_dcp_backend.hpp"

namespace liftd::api {
namespace {

using nlohmann::json;
using testing::FakeDcpBackend;
using testing::RefusedRequest;

class DcpDispatcherTest : public testing::DispatcherFixture<FakeDcpBackend> {};

TEST_F(DcpDispatcherTest, RejectsMalformedRequestsWithTheRightCode) {
  // Legend: request line, expected error code, expected field named.
  const RefusedRequest cases[] = {
      {R"({"cmd":"load","percent":"50"})", "bad_request", "percent"},  // string for int
      {R"({"cmd":"load","percent":50.5})", "bad_request", "percent"},  // fraction
      {R"({"cmd":"load","percent":1000})", "bad_request", "percent"},  // above 999
      {R"({"cmd":"load","percent":-1})", "bad_request", "percent"},    // below 0
      {R"({"cmd":"load","percent":18446744073709551615})", "bad_request", "percent"},
      {R"({"cmd":"key","key":0})", "bad_request", "key"},  // buttons are 1..5
      {R"({"cmd":"key","key":6})", "bad_request", "key"},
      {R"({"cmd":"power","supply":"battery"})", "bad_request", "supply"},  // not a choice
      {R"({"cmd":"power","supply":"mains","saving":3})", "bad_request", "saving"},
  };
  expect_refused(cases);
}

TEST_F(DcpDispatcherTest, BadRequestMessageSaysWhatIsAllowed) {
  EXPECT_EQ(handle(R"({"cmd":"load","percent":1000})").at("error").at("message"),
            "field \"percent\" must be an integer 0..999");
  EXPECT_EQ(handle(R"({"cmd":"power","supply":"x"})").at("error").at("message"),
            "field \"supply\" must be one of \"mains\", \"emergency\"");
}

TEST_F(DcpDispatcherTest, ChecksAccessPerCommandLevel) {
  // Legend: command line, access level it needs.
  expect_access_levels({
      {R"({"cmd":"display"})", Access::Read},
      {R"({"cmd":"key","key":1})", Access::Control},
      {R"({"cmd":"power","supply":"mains"})", Access::Control},
      {R"({"cmd":"load","percent":10})", Access::Control},
  });
}

TEST_F(DcpDispatcherTest, ForbiddenIsCheckedBeforeArguments) {
  // A peer without access learns nothing about argument rules.
  EXPECT_EQ(code_of(handle(R"({"cmd":"load","percent":"x"})", AccessSet{true, false, false})),
            "forbidden");
}

TEST_F(DcpDispatcherTest, ForwardsControlArgumentsToTheBackend) {
  handle(R"({"cmd":"key","key":3})");
  handle(R"({"cmd":"drive_reset"})");
  handle(R"({"cmd":"power","supply":"emergency","saving":2})");
  handle(R"({"cmd":"power","supply":"mains"})");
  handle(R"({"cmd":"load","percent":75})");
  EXPECT_EQ(backend_.requests_seen,
            (std::vector<std::string>{"key 3", "drive_reset", "power emergency 2", "power mains 0",
                                      "load 75"}));
}

TEST_F(DcpDispatcherTest, AnswersLaterForAsynchronousHandlers) {
  backend_.defer = true;
  json reply = handle(R"({"cmd":"load","percent":5,"id":"later"})");
  EXPECT_TRUE(reply.is_null());
  ASSERT_EQ(backend_.deferred.size(), 1U);
  int sends = 0;
  Peer peer;
  peer.access = {true, true, true};
  dispatcher_.handle_line(R"({"cmd":"drive_reset","id":2})", peer, session_,
                          [&](std::string text, bool) {
                            ++sends;
                            reply = json::parse(text);
                          });
  backend_.deferred[1](Result::ok({{"done", true}}));
  backend_.deferred[1](Result::ok());  // a second answer is ignored
  EXPECT_EQ(sends, 1);
  EXPECT_EQ(reply.at("id"), 2);
  EXPECT_EQ(reply.at("result").at("done"), true);
  // A responder dropped unanswered still replies (internal), so no client waits forever.
  backend_.deferred.clear();
  EXPECT_EQ(code_of(reply_), "internal");
  EXPECT_EQ(reply_.at("id"), "later");
}

// The registry (lib/kinds) gives a DCP lift's backend its own commands to serve, and answers
// another kind's `not_offered` (the other kinds' lifts: tests/daemon/drive_commands_test.cpp).
TEST_F(DcpDispatcherTest, TheLiftsOwnKindServesItsCommands) {
  expect_only_own_kind_served(R"({"cmd":"key","key":3})", R"({"cmd":"uss_mirror"})", "key 3");
}

}  // namespace
}  // namespace liftd::api
