// The USS lift's own commands (lib/uss/host/commands.*) through the request handler, without a
// socket: their arguments and what reaches the USS lift's backend, on a dispatcher built as the
// daemon builds a USS lift's (the common commands, then the registry's).
#include <gtest/gtest.h>

#include <string>

#include "api/dispatcher_fixture.hpp"
#include "uss/api/fake_uss_backend.hpp"

namespace liftd::api {
namespace {

using nlohmann::json;
using testing::FakeUssBackend;

// A USS lift: the parameter commands reach the backend with their arguments as given (the
// element index unchanged, USS C 4.2.2), values that fit no word are refused unless the width is
// dword, and the DCP-only commands are not offered.
class UssDriveKindTest : public testing::DispatcherFixture<FakeUssBackend> {};

TEST_F(UssDriveKindTest, ParameterCommandsReachTheBackendWithTheirArguments) {
  struct Case {
    const char* request;
    const char* call;
  };
  for (
      const Case& c : {
          Case{R"({"cmd":"uss_read","pnu":52})", "parameter -1 52 value 0"},
          Case{R"({"cmd":"uss_read","pnu":7,"target":"text","index":3,"address":5})",
               "parameter 5 7 text 3"},
          Case{R"({"cmd":"uss_read","pnu":4,"target":"description","index":255})",
               "parameter -1 4 description 255"},
          Case{
              R"({"cmd":"uss_write","pnu":4,"target":"array","index":2,"value":-1,"width":"dword"})",
              "parameter -1 4 array 2 write -1 dword"},
          Case{R"({"cmd":"uss_write","pnu":1000,"value":65535,"eeprom":true})",
               "parameter -1 1000 value 0 write 65535 eeprom"},
          Case{R"({"cmd":"uss_mirror"})", "mirror -1"},
          Case{R"({"cmd":"uss_mirror","address":31})", "mirror 31"},
          Case{R"({"cmd":"drive_reset"})", "drive_reset"},
      }) {
    backend_.requests_seen.clear();
    const json reply = handle(c.request);
    EXPECT_TRUE(reply.at("ok").get<bool>()) << c.request << " " << reply.dump();
    ASSERT_EQ(backend_.requests_seen.size(), 1U) << c.request;
    EXPECT_EQ(backend_.requests_seen[0], c.call);
  }
}

TEST_F(UssDriveKindTest, BadParameterRequestsChangeNothing) {
  struct Case {
    const char* request;
    const char* field;
  };
  for (const Case& c :
       {Case{R"({"cmd":"uss_read"})", "pnu"}, Case{R"({"cmd":"uss_read","pnu":2048})", "pnu"},
        Case{R"({"cmd":"uss_read","pnu":1,"address":32})", "address"},
        Case{R"({"cmd":"uss_read","pnu":1,"index":256})", "index"},
        Case{R"({"cmd":"uss_read","pnu":1,"target":"bits"})", "target"},
        Case{R"({"cmd":"uss_write","pnu":1})", "value"},
        Case{R"({"cmd":"uss_write","pnu":1,"value":65536})", "value"},
        Case{R"({"cmd":"uss_write","pnu":1,"value":-32769})", "value"},
        Case{R"({"cmd":"uss_write","pnu":1,"value":4294967296,"width":"dword"})", "value"},
        Case{R"({"cmd":"uss_write","pnu":1,"value":1,"target":"text"})", "target"}}) {
    const json reply = handle(c.request);
    EXPECT_EQ(code_of(reply), "bad_request") << c.request;
    EXPECT_EQ(reply.at("error").at("field"), c.field) << c.request;
  }
  EXPECT_TRUE(backend_.requests_seen.empty()) << "a refused request reached the backend";
  for (const char* request : {R"({"cmd":"key","key":1})", R"({"cmd":"fast_stop"})"}) {
    EXPECT_EQ(code_of(handle(request)), "not_offered") << request;
  }
}

// The registry (lib/kinds) gives a USS lift's backend its own commands to serve, and answers
// another kind's `not_offered` (the other kinds' lifts: tests/daemon/drive_commands_test.cpp).
TEST_F(UssDriveKindTest, TheLiftsOwnKindServesItsCommands) {
  expect_only_own_kind_served(R"({"cmd":"uss_mirror","address":3})", R"({"cmd":"fast_stop"})",
                              "mirror 3");
}

}  // namespace
}  // namespace liftd::api
