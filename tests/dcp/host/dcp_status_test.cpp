// The `dcp` object of status: every bit of the DCP status byte (DCP 4.1) and of the extended
// status (DCP 4.2.1.1) under its documented name.
#include <gtest/gtest.h>

#include "dcp/host/dcp_status.hpp"

namespace liftd::daemon {
namespace {

using nlohmann::json;

TEST(DcpStatus, EveryStatusBitHasItsName) {
  // Bit n of the status byte is Sn (DCP 4.1).
  const char* names[] = {"ready",           "travel_active", "advance_warning", "general_fault",
                         "below_levelling", "accepted",      "brake_open",      "message_error"};
  for (int bit = 0; bit < 8; ++bit) {
    DcpStatusFacts facts;
    facts.status_byte = static_cast<std::uint8_t>(1U << bit);
    const json status = dcp_status_json(facts).at("status");
    ASSERT_EQ(status.size(), 8U);
    for (int other = 0; other < 8; ++other) {
      EXPECT_EQ(status.at(names[other]), other == bit) << "S" << bit << " read as " << names[other];
    }
  }
}

TEST(DcpStatus, UnknownsAreNullAndAStatusNeverSeenReadsZero) {
  const json j = dcp_status_json({});
  EXPECT_EQ(j, (json{{"mode", nullptr},
                     {"status",
                      {{"ready", false},
                       {"travel_active", false},
                       {"advance_warning", false},
                       {"general_fault", false},
                       {"below_levelling", false},
                       {"accepted", false},
                       {"brake_open", false},
                       {"message_error", false}}},
                     {"extended", nullptr},
                     {"handshake_problem", nullptr},
                     {"line_echo", {{"mode", "off"}, {"state", "absent"}}}}));
}

TEST(DcpStatus, LineEchoSaysTheModeAndWhatTheLinkKnows) {
  DcpStatusFacts facts;
  facts.echo_mode = io::EchoMode::Auto;
  facts.echo_state = io::EchoState::Unknown;
  EXPECT_EQ(dcp_status_json(facts).at("line_echo"), (json{{"mode", "auto"}, {"state", "unknown"}}));
  facts.echo_state = io::EchoState::Present;
  EXPECT_EQ(dcp_status_json(facts).at("line_echo"), (json{{"mode", "auto"}, {"state", "present"}}));
}

TEST(DcpStatus, ModeExtendedAndHandshakeProblem) {
  DcpStatusFacts facts;
  facts.mode = dcp::Protocol::Dcp3;
  dcp::ExtendedStatus extended{};
  extended.motor_temperature_limit = true;
  extended.weight_bits = 5;
  facts.extended = extended;
  facts.handshake_problem = "no reply to I0";
  const json j = dcp_status_json(facts);
  EXPECT_EQ(j.at("mode"), "DCP3");
  EXPECT_EQ(j.at("extended").at("motor_temperature_limit"), true);
  EXPECT_EQ(j.at("extended").at("drive_temperature_limit"), false);
  EXPECT_EQ(j.at("extended").at("weight_bits"), 5);
  EXPECT_EQ(j.at("extended").size(), 8U);
  EXPECT_EQ(j.at("handshake_problem"), "no reply to I0");
  facts.mode = dcp::Protocol::ComChan;
  EXPECT_EQ(dcp_status_json(facts).at("mode"), "ComChan");
}

}  // namespace
}  // namespace liftd::daemon
