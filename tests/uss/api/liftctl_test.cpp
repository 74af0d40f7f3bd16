// The USS lift's own commands from liftctl (uss-read, uss-write, uss-mirror) against the
// in-process server with the USS fake: what reaches the lift's backend, and the usage errors.
#include <string>
#include <vector>

#include "api/test_support.hpp"
#include "uss/api/fake_uss_backend.hpp"

namespace liftd::api::testing {
namespace {

class UssLiftctl : public BasicLiftctlFixture<FakeUssBackend> {};

TEST_F(UssLiftctl, UssParameterCommandsReachTheBackend) {
  backend_.status_snapshot.drive_kind = drive::Kind::Uss;
  start_server();
  for (const char* args : {"uss-read 52", "uss-read 7 text 3 @5", "uss-read 4 description 255",
                           "uss-write 4 -1 dword array 2", "uss-write 1000 300 eeprom @31",
                           "uss-mirror", "uss-mirror 12"}) {
    const RunResult r = run_command(liftctl(args));
    EXPECT_EQ(r.exit_code, 0) << args << ": " << r.output;
  }
  EXPECT_EQ(on_io([this] { return backend_.requests_seen; }),
            (std::vector<std::string>{
                "parameter -1 52 value 0", "parameter 5 7 text 3", "parameter -1 4 description 255",
                "parameter -1 4 array 2 write -1 dword",
                "parameter 31 1000 value 0 write 300 eeprom", "mirror -1", "mirror 12"}));
  for (const char* args : {"uss-read", "uss-read x", "uss-read 5 text", "uss-read 5 dword",
                           "uss-write 5", "uss-write 5 1 text 3", "uss-mirror a", "uss-read 5 @"}) {
    EXPECT_EQ(run_command(liftctl(args)).exit_code, 2) << args;
  }
}

}  // namespace
}  // namespace liftd::api::testing
