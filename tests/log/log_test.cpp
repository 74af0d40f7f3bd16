// Logging: journal field building and encoding (pure), the native-protocol send path against a
// socket bound by the test, the text format, and backend selection.
#include "log/log.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdlib>
#include <ctime>
#include <map>
#include <string>
#include <vector>

#include "daemon/test_socket.hpp"
#include "log/journal.hpp"

namespace liftd::log {
namespace {

using namespace std::chrono_literals;
using ::testing::HasSubstr;
using testing::TestSocket;

std::map<std::string, std::string> as_map(const std::vector<JournalField>& fields) {
  std::map<std::string, std::string> out;
  for (const auto& [k, v] : fields) out[k] = v;
  return out;
}

std::map<std::string, std::string> decode(const std::string& datagram) {
  std::vector<JournalField> fields;
  EXPECT_TRUE(decode_journal_datagram(datagram, fields)) << datagram;
  return as_map(fields);
}

TEST(JournalPriority, FollowsSyslogLevels) {
  // Legend: our level -> syslog priority (LOG_ERR 3, LOG_WARNING 4, LOG_INFO 6, LOG_DEBUG 7).
  const std::vector<std::pair<Level, int>> cases = {
      {Level::error, 3}, {Level::warn, 4}, {Level::info, 6}, {Level::debug, 7}, {Level::trace, 7}};
  for (const auto& [level, priority] : cases) {
    EXPECT_EQ(journal_priority(level), priority) << to_string(level);
  }
}

TEST(JournalFieldName, PrefixesUpperCasesAndSanitises) {
  // Legend: extra field key -> journal field name.
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"cause", "LIFTD_CAUSE"},
      {"lost_frames", "LIFTD_LOST_FRAMES"},
      {"lost-frames", "LIFTD_LOST_FRAMES"},
      {"Speed2", "LIFTD_SPEED2"},
      {"a b.c", "LIFTD_A_B_C"},
      {std::string(80, 'x'), "LIFTD_" + std::string(58, 'X')},  // journald: 64 characters max
  };
  for (const auto& [key, name] : cases) EXPECT_EQ(journal_field_name(key), name) << key;
}

TEST(JournalFields, EventRecordCarriesComponentEventFieldsAndCode) {
  const Fields extra{{"cause", "10 lost frames"}, {"frames", "10"}};
  Record record;
  record.level = Level::warn;
  record.component = "dcp";
  record.event = "link_fault";
  record.fields = &extra;
  record.text = "drive link lost";
  record.file = "lib/dcp/link.cpp";
  record.line = 42;
  record.function = "on_timeout";
  const std::vector<JournalField> expected = {
      {"MESSAGE", "drive link lost"},
      {"PRIORITY", "4"},
      {"SYSLOG_IDENTIFIER", "liftd"},
      {"LIFTD_COMPONENT", "dcp"},
      {"LIFTD_EVENT", "link_fault"},
      {"LIFTD_CAUSE", "10 lost frames"},
      {"LIFTD_FRAMES", "10"},
      {"CODE_FILE", "lib/dcp/link.cpp"},
      {"CODE_LINE", "42"},
      {"CODE_FUNC", "on_timeout"},
  };
  EXPECT_EQ(journal_fields(record, "liftd"), expected);
}

TEST(JournalFields, PlainRecordHasNoEventOrCodeFields) {
  Record record;
  record.level = Level::info;
  record.component = "api";
  record.text = "3 clients";
  const std::vector<JournalField> expected = {{"MESSAGE", "3 clients"},
                                              {"PRIORITY", "6"},
                                              {"SYSLOG_IDENTIFIER", "liftd"},
                                              {"LIFTD_COMPONENT", "api"}};
  EXPECT_EQ(journal_fields(record, "liftd"), expected);
}

TEST(JournalDatagram, EncodesPlainAndBinaryForms) {
  // Plain form: NAME=value\n. A value with a newline: NAME\n, 64-bit LE length, value, \n.
  const std::string plain = encode_journal_datagram({{"MESSAGE", "hi"}, {"PRIORITY", "6"}});
  EXPECT_EQ(plain, "MESSAGE=hi\nPRIORITY=6\n");
  const std::string binary = encode_journal_datagram({{"MESSAGE", "a\nbc"}, {"X", ""}});
  const std::string expected =
      std::string("MESSAGE\n") + std::string("\x04\0\0\0\0\0\0\0", 8) + "a\nbc\n" + "X=\n";
  EXPECT_EQ(binary, expected);
}

TEST(JournalDatagram, DecodesWhatItEncodesAndRejectsGarbage) {
  const std::vector<JournalField> fields = {
      {"MESSAGE", "line one\nline two"}, {"LIFTD_CAUSE", "x=y"}, {"EMPTY", ""}};
  std::vector<JournalField> back;
  ASSERT_TRUE(decode_journal_datagram(encode_journal_datagram(fields), back));
  EXPECT_EQ(back, fields);
  // Legend: malformed datagrams.
  for (const std::string& bad :
       {std::string("MESSAGE=no newline"), std::string("=x\n"),
        std::string("MESSAGE\n\x05\0\0", 11), std::string("M\n\x09\0\0\0\0\0\0\0abc\n", 14)}) {
    EXPECT_FALSE(decode_journal_datagram(bad, back)) << bad;
  }
}

TEST(TextLine, ShowsTimeLevelComponentTextAndFields) {
  ::setenv("TZ", "UTC", 1);
  ::tzset();
  const Fields extra{{"cause", "10 lost frames"}, {"n", "3"}};
  Record record;
  record.level = Level::warn;
  record.component = "dcp";
  record.event = "link_fault";
  record.fields = &extra;
  record.text = "drive link lost";
  // 2026-11-22 03:00:43.123 UTC
  const auto when = std::chrono::system_clock::time_point(std::chrono::seconds(1795316443)) +
                    std::chrono::milliseconds(123);
  EXPECT_EQ(format_text_line(record, when),
            "2026-11-22 03:00:43.123 WARN  dcp: drive link lost "
            "[event=link_fault cause=\"10 lost frames\" n=3]");
  Record plain;
  plain.level = Level::error;
  plain.component = "api";
  plain.text = "bad";
  EXPECT_EQ(format_text_line(plain, when), "2026-11-22 03:00:43.123 ERROR api: bad");
}

TEST(JournalWriter, SendsOneDatagramToTheConfiguredSocket) {
  TestSocket journal;
  JournalWriter writer(journal.path());
  const std::string datagram = encode_journal_datagram({{"MESSAGE", "hello"}});
  ASSERT_EQ(writer.send(datagram), 0);
  EXPECT_EQ(journal.receive(2s), datagram);
}

TEST(JournalWriter, PassesRecordsTooLargeForADatagramAsMemfd) {
  TestSocket journal;
  JournalWriter writer(journal.path());
  // Larger than the default socket send buffer (net.core.wmem_default, 208 KiB): sendto
  // fails with EMSGSIZE and the writer must hand over a sealed memfd, as journald expects.
  const std::string datagram = encode_journal_datagram({{"MESSAGE", std::string(400000, 'x')}});
  ASSERT_EQ(writer.send(datagram), 0);
  EXPECT_EQ(journal.receive(2s), datagram);
}

TEST(JournalWriter, ReportsAMissingSocket) {
  JournalWriter writer("/nonexistent/journal/socket");
  EXPECT_EQ(writer.send("MESSAGE=x\n"), ENOENT);
}

class LogToJournal : public ::testing::Test {
 protected:
  void SetUp() override { init({Level::info, Backend::journal, journal_.path(), "liftd-test"}); }
  void TearDown() override { init({Level::info, Backend::text, {}, "liftd"}); }
  TestSocket journal_;
};

TEST_F(LogToJournal, EventArrivesWithStructuredFields) {
  event(Level::warn, "dcp", "link_fault", {{"cause", "10 lost frames"}}, "drive link lost");
  const int line = __LINE__ - 1;
  const auto datagram = journal_.receive(2s);
  ASSERT_TRUE(datagram.has_value());
  const auto fields = decode(*datagram);
  EXPECT_EQ(fields.at("MESSAGE"), "drive link lost");
  EXPECT_EQ(fields.at("PRIORITY"), "4");
  EXPECT_EQ(fields.at("SYSLOG_IDENTIFIER"), "liftd-test");
  EXPECT_EQ(fields.at("LIFTD_COMPONENT"), "dcp");
  EXPECT_EQ(fields.at("LIFTD_EVENT"), "link_fault");
  EXPECT_EQ(fields.at("LIFTD_CAUSE"), "10 lost frames");
  EXPECT_THAT(fields.at("CODE_FILE"), HasSubstr("log_test.cpp"));
  EXPECT_EQ(fields.at("CODE_LINE"), std::to_string(line));
}

TEST_F(LogToJournal, ComponentLoggerFormatsAndFiltersByLevel) {
  const Logger api("api");
  api.debug("not written at info: {}", 1);
  api.info("{} clients connected", 3);
  const auto datagram = journal_.receive(2s);
  ASSERT_TRUE(datagram.has_value());
  const auto fields = decode(*datagram);
  EXPECT_EQ(fields.at("MESSAGE"), "3 clients connected");
  EXPECT_EQ(fields.at("LIFTD_COMPONENT"), "api");
  EXPECT_EQ(fields.count("LIFTD_EVENT"), 0U);
  EXPECT_FALSE(journal_.receive(100ms).has_value());

  set_level(Level::trace);
  api.trace("now written");
  ASSERT_EQ(decode(journal_.receive(2s).value_or("")).at("PRIORITY"), "7");
  set_level(Level::error);
  api.warn("dropped");
  EXPECT_FALSE(journal_.receive(100ms).has_value());
}

TEST_F(LogToJournal, MultiLineMessageUsesTheBinaryForm) {
  write(Level::error, "config", "two\nlines");
  const auto fields = decode(journal_.receive(2s).value_or(""));
  EXPECT_EQ(fields.at("MESSAGE"), "two\nlines");
  EXPECT_EQ(fields.at("PRIORITY"), "3");
  // Text is never treated as a format string.
  write(Level::info, "config", "braces {} and {:d} stay");
  EXPECT_EQ(decode(journal_.receive(2s).value_or("")).at("MESSAGE"), "braces {} and {:d} stay");
}

TEST(LogFallback, UnreachableJournalFallsBackToStderr) {
  init({Level::info, Backend::journal, "/nonexistent/journal/socket", "liftd"});
  ::testing::internal::CaptureStderr();
  event(Level::error, "dcp", "link_fault", {{"cause", "x"}}, "first");
  event(Level::error, "dcp", "link_fault", {}, "second");
  const std::string err = ::testing::internal::GetCapturedStderr();
  init({Level::info, Backend::text, {}, "liftd"});
  EXPECT_THAT(err, HasSubstr("cannot write to the journal at /nonexistent/journal/socket"));
  EXPECT_THAT(err, HasSubstr("ERROR dcp: first [event=link_fault cause=x]"));
  EXPECT_THAT(err, HasSubstr("ERROR dcp: second [event=link_fault]"));
}

TEST(LogText, WritesReadableLinesToStderr) {
  init({Level::debug, Backend::text, {}, "liftd"});
  ::testing::internal::CaptureStderr();
  Logger("sim").debug("car at {} mm", 3000);
  event(Level::info, "daemon", "ready", {{"status", "simulated lift"}}, "ready");
  const std::string err = ::testing::internal::GetCapturedStderr();
  init({Level::info, Backend::text, {}, "liftd"});
  EXPECT_THAT(err, HasSubstr("DEBUG sim: car at 3000 mm\n"));
  EXPECT_THAT(err, HasSubstr("INFO  daemon: ready [event=ready status=\"simulated lift\"]\n"));
}

TEST(LogBackend, AutomaticChoosesTheJournalUnderSystemd) {
  // Legend: JOURNAL_STREAM, INVOCATION_ID -> backend `automatic` resolves to.
  struct Case {
    const char* stream;
    const char* invocation;
    Backend expected;
  };
  const std::vector<Case> cases = {
      {nullptr, nullptr, Backend::text},
      {"8:12345", nullptr, Backend::journal},
      {nullptr, "0123456789abcdef0123456789abcdef", Backend::journal},
      {"", "", Backend::text},
  };
  for (const auto& c : cases) {
    c.stream ? ::setenv("JOURNAL_STREAM", c.stream, 1) : ::unsetenv("JOURNAL_STREAM");
    c.invocation ? ::setenv("INVOCATION_ID", c.invocation, 1) : ::unsetenv("INVOCATION_ID");
    EXPECT_EQ(resolve(Backend::automatic), c.expected);
    EXPECT_EQ(resolve(Backend::text), Backend::text);
  }
  ::unsetenv("JOURNAL_STREAM");
  ::unsetenv("INVOCATION_ID");
}

TEST(LogLevel, NamesRoundTrip) {
  for (Level l : {Level::trace, Level::debug, Level::info, Level::warn, Level::error}) {
    EXPECT_EQ(parse_level(to_string(l)), l);
  }
  EXPECT_FALSE(parse_level("warning").has_value());
  EXPECT_FALSE(parse_level("").has_value());
}

}  // namespace
}  // namespace liftd::log
