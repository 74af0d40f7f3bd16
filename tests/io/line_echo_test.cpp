// The echo rules of io/line_echo.hpp: how read-back bytes compare with the frame sent, and what
// each drive.echo mode knows about the line at a port open and after a good reply.
#include "io/line_echo.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <vector>

namespace liftd::io {
namespace {

TEST(LineEcho, ComparesTheBytesReadBackWithTheFrameSent) {
  const std::vector<std::uint8_t> sent{0x11, 0x22, 0x33};
  struct Case {
    const char* name;
    std::vector<std::uint8_t> read;
    EchoCheck expected;
  };
  const Case cases[] = {
      {"nothing yet", {}, EchoCheck::Incomplete},
      {"a faithful start", {0x11, 0x22}, EchoCheck::Incomplete},
      {"all of it", {0x11, 0x22, 0x33}, EchoCheck::Match},
      {"all of it and the reply behind", {0x11, 0x22, 0x33, 0x44}, EchoCheck::Match},
      {"first byte changed", {0x10, 0x22, 0x33}, EchoCheck::Collision},
      {"last byte changed", {0x11, 0x22, 0x32}, EchoCheck::Collision},
      {"a change in what came so far", {0x11, 0x23}, EchoCheck::Collision},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    EXPECT_EQ(check_echo(sent, c.read), c.expected);
  }
}

TEST(LineEcho, OnAndOffAreFixedAutoFindsOutOncePerPortOpen) {
  EchoDetector on(EchoMode::On);
  EXPECT_EQ(on.state(), EchoState::Present);
  EXPECT_FALSE(on.good_reply_seen(false));  // fixed: a reply decides nothing
  EXPECT_EQ(on.state(), EchoState::Present);

  EchoDetector off(EchoMode::Off);
  EXPECT_EQ(off.state(), EchoState::Absent);
  EXPECT_FALSE(off.good_reply_seen(true));
  EXPECT_EQ(off.state(), EchoState::Absent);

  EchoDetector automatic(EchoMode::Auto);
  EXPECT_TRUE(automatic.undecided());
  EXPECT_TRUE(automatic.good_reply_seen(true));
  EXPECT_EQ(automatic.state(), EchoState::Present);
  EXPECT_FALSE(automatic.good_reply_seen(false));  // decided once
  EXPECT_EQ(automatic.state(), EchoState::Present);
  automatic.port_opened();  // another adapter may be behind the name now
  EXPECT_EQ(automatic.state(), EchoState::Unknown);
  EXPECT_TRUE(automatic.good_reply_seen(false));
  EXPECT_EQ(automatic.state(), EchoState::Absent);
  EXPECT_EQ(to_string(EchoMode::Auto), "auto");
  EXPECT_EQ(to_string(EchoState::Present), "present");
}

}  // namespace
}  // namespace liftd::io
