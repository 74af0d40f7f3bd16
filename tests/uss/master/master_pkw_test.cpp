// The USS master's PKW channel (C 4.2.1): repeats, timeouts, errors and spontaneous reports.
#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

#include "bus_harness.hpp"
#include "master_fixture.hpp"
#include "uss/pzd.hpp"
#include "uss/receiver.hpp"

namespace liftd::uss {
namespace {

// ---------------------------------------------------------------------------------------------
// PKW channel (C 4.2.1)

TEST(UssMasterPkw, RequestIsRepeatedUntilTheMatchingReplyStaleRepliesIgnored) {
  Bus bus(one_slave());
  ASSERT_TRUE(bus.master.submit_pkw(5, read_request(52), 77));
  EXPECT_TRUE(bus.master.slave(5).pkw_busy);
  EXPECT_FALSE(bus.master.submit_pkw(5, read_request(53), 78)) << "one request per slave";
  // C 8 example 2: read parameter 52; the slave first still answers the old request (PNU 51),
  // then "keine Antwort", then the value 4000 hex.
  const Pkw replies[] = {reply_pkw(reply::kValueWord, 51, PkwLength::Three, 0x1234),
                         reply_pkw(reply::kNone, 0, PkwLength::Three, 0),
                         reply_pkw(reply::kValueWord, 52, PkwLength::Three, 0x4000)};
  PkwResult result;
  for (const Pkw& r : replies) {
    EXPECT_FALSE(bus.master.poll_pkw_result(result));
    const auto req = parse_request(bus.send().bytes, PkwLength::Three, 2);
    ASSERT_TRUE(req.ok);
    EXPECT_EQ(req.pkw.id, request::kReadValue);  // the same request every time
    EXPECT_EQ(req.pkw.pnu, 52);
    bus.reply(make_reply(5, r, PkwLength::Three, {0, 0}));
  }
  ASSERT_TRUE(bus.master.poll_pkw_result(result));
  EXPECT_EQ(result.tag, 77U);
  EXPECT_EQ(result.address, 5);
  EXPECT_EQ(result.outcome, PkwResult::Outcome::Done);
  EXPECT_EQ(value(result.reply, PkwLength::Three, PkwWidth::Word), 0x4000U);
  EXPECT_EQ(bus.master.counters().pkw_stale_replies, 2U);
  EXPECT_FALSE(bus.master.slave(5).pkw_busy);
  // Done: the next poll carries "kein Auftrag" again, and a new request can start.
  EXPECT_EQ(parse_request(bus.send().bytes, PkwLength::Three, 2).pkw.id, request::kNone);
  bus.reply(idle_reply(5));
  EXPECT_TRUE(bus.master.submit_pkw(5, read_request(53), 78));
}

TEST(UssMasterPkw, TimeoutsCountAsRepeatsAndTheRequestEndsUnanswered) {
  MasterConfig c = one_slave();
  c.pkw_repeat_limit = 3;
  Bus bus(c);
  ASSERT_TRUE(bus.master.submit_pkw(5, read_request(52), 1));
  PkwResult result;
  bus.send();
  bus.timeout();
  bus.send();
  bus.reply(make_reply(5, reply_pkw(reply::kValueWord, 51, PkwLength::Three, 1), PkwLength::Three,
                       {0, 0}));
  EXPECT_FALSE(bus.master.poll_pkw_result(result));
  bus.send();
  bus.timeout();
  ASSERT_TRUE(bus.master.poll_pkw_result(result));
  EXPECT_EQ(result.outcome, PkwResult::Outcome::Unanswered);
  EXPECT_EQ(bus.master.counters().pkw_unanswered, 1U);
}

TEST(UssMasterPkw, ErrorAndNoAuthorityEndTheRequest) {
  // C 4.2.1.1: AK 7 with the error number in PWE (with 4 words in PWE2), AK 8 to a change.
  for (const PkwLength len : {PkwLength::Three, PkwLength::Four}) {
    Bus bus(one_slave(38400, len));
    Pkw write;
    write.id = request::kWriteWord;
    write.pnu = 18;
    set_value(write, len, PkwWidth::Word, 0x7000);
    ASSERT_TRUE(bus.master.submit_pkw(5, write, 9));
    const auto req = parse_request(bus.send().bytes, len, 2);
    EXPECT_EQ(req.pkw.pke(), 0x2012);  // AK 2, PNU 18
    bus.reply(make_reply(5, reply_pkw(reply::kError, 18, len, 2), len, {0, 0}));
    PkwResult result;
    ASSERT_TRUE(bus.master.poll_pkw_result(result));
    EXPECT_EQ(result.outcome, PkwResult::Outcome::Error);
    EXPECT_EQ(result.error_number, 2);  // "Wertgrenze überschritten"

    ASSERT_TRUE(bus.master.submit_pkw(5, write, 10));
    bus.send();
    bus.reply(make_reply(5, reply_pkw(reply::kNoAuthority, 18, len, 0), len, {0, 0}));
    ASSERT_TRUE(bus.master.poll_pkw_result(result));
    EXPECT_EQ(result.outcome, PkwResult::Outcome::NoAuthority);
    EXPECT_EQ(result.tag, 10U);
  }
}

TEST(UssMasterPkw, RequestsThatDoNotFitAreRefused) {
  Bus bus(one_slave(38400, PkwLength::Three));
  Pkw dword;
  dword.id = request::kWriteDword;
  dword.pnu = 4;
  set_value(dword, PkwLength::Three, PkwWidth::Dword, 0x40000000);
  EXPECT_FALSE(bus.master.submit_pkw(5, dword, 1)) << "C 7: a double word needs 4 PKW words";
  EXPECT_FALSE(bus.master.submit_pkw(5, Pkw{}, 1)) << "'kein Auftrag' is no request";
  EXPECT_FALSE(bus.master.submit_pkw(6, read_request(1), 1)) << "not configured";
  Bus none(one_slave(38400, PkwLength::None));
  EXPECT_FALSE(none.master.submit_pkw(5, read_request(1), 1)) << "no PKW area";
}

TEST(UssMasterPkw, SpontaneousReportIsSurfacedOnceAndAcknowledgedByTogglingBit11) {
  Bus bus(one_slave());
  // First contact: "keine Antwort" with bit 11 = 0.
  bus.send();
  bus.reply(idle_reply(5));
  ASSERT_TRUE(bus.master.submit_pkw(5, read_request(52), 3));

  auto poll = [&bus](const Pkw& reply) {
    const auto req = parse_request(bus.send().bytes, PkwLength::Three, 2);
    bus.reply(make_reply(5, reply, PkwLength::Three, {0, 0}));
    return req.pkw;
  };
  // C 4.2.1.2: the slave interrupts with a report and changes bit 11 (0 -> 1).
  const Pkw report1 = reply_pkw(reply::kSpontaneousWord, 100, PkwLength::Three, 5, true);
  Pkw sent = poll(report1);
  EXPECT_FALSE(sent.toggle);
  SpontaneousReport r;
  ASSERT_TRUE(bus.master.poll_spontaneous(r));
  EXPECT_EQ(r.address, 5);
  EXPECT_EQ(r.report.pnu, 100);
  EXPECT_EQ(value(r.report, PkwLength::Three, PkwWidth::Word), 5U);
  // The master acknowledges by changing its bit 11; the slave may repeat the report until it
  // has seen that: not surfaced again.
  sent = poll(report1);
  EXPECT_TRUE(sent.toggle) << "acknowledged with bit 11 = 1";
  EXPECT_EQ(sent.id, request::kReadValue) << "our request keeps being repeated";
  EXPECT_EQ(sent.pnu, 52);
  EXPECT_FALSE(bus.master.poll_spontaneous(r));
  EXPECT_EQ(bus.master.counters().spontaneous_repeats, 1U);
  // A second report: the slave changes bit 11 again (1 -> 0).
  const Pkw report2 = reply_pkw(reply::kSpontaneousArrayWord, 101, PkwLength::Three, 7, false, 3);
  sent = poll(report2);
  EXPECT_TRUE(sent.toggle);
  ASSERT_TRUE(bus.master.poll_spontaneous(r));
  EXPECT_EQ(r.report.pnu, 101);
  EXPECT_EQ(r.report.ind, 3);
  // Then the slave answers our request, with its current bit 11 (0).
  sent = poll(reply_pkw(reply::kValueWord, 52, PkwLength::Three, 0x4000, false));
  EXPECT_FALSE(sent.toggle) << "second acknowledgement: bit 11 back to 0";
  PkwResult result;
  ASSERT_TRUE(bus.master.poll_pkw_result(result));
  EXPECT_EQ(result.outcome, PkwResult::Outcome::Done);
  EXPECT_EQ(bus.master.counters().spontaneous, 2U);
}

TEST(UssMasterPkw, ReportsDoNotCountAgainstTheRepeatLimit) {
  MasterConfig c = one_slave();
  c.pkw_repeat_limit = 2;
  Bus bus(c);
  ASSERT_TRUE(bus.master.submit_pkw(5, read_request(52), 3));
  bool toggle = false;
  for (int i = 0; i < 4; ++i) {
    toggle = !toggle;
    bus.send();
    bus.reply(make_reply(5, reply_pkw(reply::kSpontaneousWord, 100, PkwLength::Three, 1, toggle),
                         PkwLength::Three, {0, 0}));
  }
  PkwResult result;
  EXPECT_FALSE(bus.master.poll_pkw_result(result));
  EXPECT_EQ(bus.master.counters().spontaneous, 4U);
}

TEST(UssMasterPkw, TheToggleOfARestartedSlaveIsAdoptedWhenItIsHeardAgain) {
  Bus bus(one_slave());
  bus.send();
  bus.reply(make_reply(5, reply_pkw(reply::kSpontaneousWord, 100, PkwLength::Three, 1, true),
                       PkwLength::Three, {0, 0}));
  SpontaneousReport r;
  ASSERT_TRUE(bus.master.poll_spontaneous(r));
  EXPECT_TRUE(parse_request(bus.send().bytes, PkwLength::Three, 2).pkw.toggle);
  bus.timeout();  // the slave restarts; its bit 11 is 0 again
  bus.send();
  bus.reply(idle_reply(5));
  EXPECT_FALSE(parse_request(bus.send().bytes, PkwLength::Three, 2).pkw.toggle);
  // Its next report (bit 11 -> 1) is new.
  bus.reply(make_reply(5, reply_pkw(reply::kSpontaneousWord, 100, PkwLength::Three, 2, true),
                       PkwLength::Three, {0, 0}));
  ASSERT_TRUE(bus.master.poll_spontaneous(r));
  EXPECT_EQ(value(r.report, PkwLength::Three, PkwWidth::Word), 2U);
}

TEST(UssMasterPkw, VariableLengthReplyWithText) {
  // C 8 example 7 shape: PKW_ANZ 127, no PZD; the reply carries 8 PWE words of text.
  MasterConfig c = one_slave(38400, PkwLength::Variable, 0);
  Bus bus(c);
  Pkw text;
  text.id = request::kText;
  text.pnu = 7;
  text.ind = make_text_ind(3, false);
  text.pwe_count = 1;
  ASSERT_TRUE(bus.master.submit_pkw(5, text, 1));
  const Sent s = bus.send();
  EXPECT_EQ(s.bytes.size(), 4U + 6U);  // PKE IND PWE1
  Pkw reply;
  reply.id = reply::kText;
  reply.pnu = 7;
  reply.ind = text.ind;
  reply.pwe_count = 8;
  const char* chars = "300 BAUD        ";
  for (int i = 0; i < 8; ++i) {
    reply.pwe[static_cast<std::size_t>(i)] =
        static_cast<std::uint16_t>((static_cast<unsigned char>(chars[2 * i]) << 8) |
                                   static_cast<unsigned char>(chars[2 * i + 1]));
  }
  bus.reply(make_reply(5, reply, PkwLength::Variable, {}));
  PkwResult result;
  ASSERT_TRUE(bus.master.poll_pkw_result(result));
  EXPECT_EQ(result.outcome, PkwResult::Outcome::Done);
  EXPECT_EQ(result.reply.pwe_count, 8);
  EXPECT_EQ(result.reply.pwe[0], 0x3330);  // "30"
}

}  // namespace
}  // namespace liftd::uss
