// The DCP lift's own commands over the API socket, with the DCP fake: replies that wait on the
// lift's backend, and liftctl's DCP commands (key, power, load) reaching it.
#include <string>
#include <vector>

#include "api/test_support.hpp"
#include "dcp/api/fake_dcp_backend.hpp"

namespace liftd::api::testing {
namespace {

using nlohmann::json;

class DcpApiServer : public BasicServerFixture<FakeDcpBackend> {};

TEST_F(DcpApiServer, AsyncRepliesKeepTheirIds) {
  start_server();
  on_io([this] { backend_.defer = true; });
  auto client = connect();
  ASSERT_TRUE(client->send_json({{"cmd", "drive_reset"}, {"id", "first"}}));
  ASSERT_TRUE(client->send_json({{"cmd", "load"}, {"percent", 40}, {"id", "second"}}));
  ASSERT_TRUE(eventually([this] { return backend_.deferred.size() == 2; }));
  // Requests that do not wait on the backend are answered meanwhile.
  EXPECT_EQ(client->call({{"cmd", "version"}, {"id", "third"}}).at("id"), "third");
  on_io([this] {
    backend_.deferred[1](Result::ok());
    backend_.deferred[0](Result::fail(ErrorCode::NotReady, "link down"));
  });
  EXPECT_EQ(client->read_json()->at("id"), "second");
  const auto first = client->read_json();
  EXPECT_EQ(first->at("id"), "first");
  EXPECT_EQ(first->at("error").at("code"), "not_ready");
}

class DcpLiftctl : public BasicLiftctlFixture<FakeDcpBackend> {};

TEST_F(DcpLiftctl, ControlCommandsReachTheBackend) {
  start_server();
  EXPECT_EQ(run_command(liftctl("key 2")).exit_code, 0);
  EXPECT_EQ(run_command(liftctl("reset")).exit_code, 0);
  EXPECT_EQ(run_command(liftctl("power emergency 1")).exit_code, 0);
  EXPECT_EQ(run_command(liftctl("load 80")).exit_code, 0);
  EXPECT_EQ(on_io([this] { return backend_.requests_seen; }),
            (std::vector<std::string>{"key 2", "drive_reset", "power emergency 1", "load 80"}));
}

TEST_F(DcpLiftctl, ErrorReplyExitsWithOne) {
  start_server();
  const RunResult r = run_command(liftctl("key 9"));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("bad_request: field \"key\" must be an integer 1..5"), std::string::npos)
      << r.output;
}

}  // namespace
}  // namespace liftd::api::testing
