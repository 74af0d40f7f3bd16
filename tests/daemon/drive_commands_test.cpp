// The registry of drive kinds (lib/kinds/lifts.cpp) adds every kind's own API commands to a lift's
// dispatcher: another kind's command is answered `not_offered` with the message every lift gives.
// The lift's kind serving its own, with the kind's fake backend: TheLiftsOwnKindServesItsCommands
// in tests/dcp/api/dispatcher_test.cpp and tests/uss/api/dispatcher_test.cpp.
#include <gtest/gtest.h>

#include <optional>
#include <string>
#include <string_view>

#include "api/commands.hpp"
#include "api/dispatcher.hpp"
#include "api/fake_backend.hpp"
#include "kinds/commands.hpp"

namespace liftd::daemon {
namespace {

using api::testing::FakeBackend;
using api::testing::QuietSession;
using nlohmann::json;

/// A lift's dispatcher as the daemon builds it: the common commands, then the registry's.
class DriveCommandsTest : public ::testing::Test {
 protected:
  void make_lift(drive::Kind kind) {
    backend_.status_snapshot.drive_kind = kind;
    api::add_builtin_commands(dispatcher_, backend_);
    kinds::add_drive_kind_commands(dispatcher_, backend_);
  }
  json handle(std::string_view line) {
    api::Peer peer;
    peer.access = {true, true, true};
    json reply;
    dispatcher_.handle_line(line, peer, session_,
                            [&reply](std::string text, bool) { reply = json::parse(text); });
    return reply;
  }

  FakeBackend backend_;
  api::Dispatcher dispatcher_;
  QuietSession session_;
};

TEST_F(DriveCommandsTest, EveryLiftKnowsEveryKindsCommands) {
  FakeBackend every_kind;
  api::Dispatcher every_command;
  api::testing::add_every_command(every_command, every_kind);
  for (const drive::Kind kind : {drive::Kind::Dcp, drive::Kind::Sch001, drive::Kind::Uss}) {
    dispatcher_ = api::Dispatcher{};
    make_lift(kind);
    EXPECT_EQ(dispatcher_.names(), every_command.names()) << drive::to_string(kind);
    for (const char* name : {"key", "display", "power", "load", "fast_stop", "fast_start",
                             "uss_read", "uss_write", "uss_mirror"}) {
      EXPECT_NE(dispatcher_.find(name), nullptr) << name;
    }
  }
}

TEST_F(DriveCommandsTest, AnotherKindsCommandIsNotOffered) {
  make_lift(drive::Kind::Sch001);
  const json key = handle(R"({"cmd":"key","key":1})");
  EXPECT_EQ(key.at("error").at("code"), "not_offered");
  EXPECT_EQ(key.at("error").at("message"),
            "\"key\" is not offered by drive kind \"sch001\" (it has no keypad function)");
  const json read = handle(R"({"cmd":"uss_read","pnu":52})");
  EXPECT_EQ(read.at("error").at("message"),
            "\"uss_read\" is not offered by drive kind \"sch001\" (it has no parameters function)");
  EXPECT_TRUE(backend_.requests_seen.empty()) << "a refused command reached the backend";
}

}  // namespace
}  // namespace liftd::daemon
