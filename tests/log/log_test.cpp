// Logging: journal field building (pure), the MESSAGE_ID catalog by key, the stderr line forms,
// backend selection, and the send itself through libsystemd. sd_journal_sendv(3) always writes to
// /run/systemd/journal/socket; the send tests give a child process its own mount namespace with a
// socket of ours at that path (root only; elsewhere they print why they skip).
#include "log/log.hpp"

#include <fcntl.h>
#include <sched.h>
#include <sys/mount.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdlib>
#include <ctime>
#include <fstream>
#include <functional>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "daemon/test_socket.hpp"
#include "log/catalog.hpp"
#include "log/journal.hpp"

namespace liftd::log {
namespace {

using namespace std::chrono_literals;
using ::testing::HasSubstr;
using testing::TestSocket;

using FieldMap = std::map<std::string, std::string>;

// journald's native protocol as journald reads it: "NAME=value\n", or for binary values
// "NAME\n" + 64-bit little-endian length + value + "\n". Test-side only.
bool decode_native(std::string_view datagram, FieldMap& out) {
  out.clear();
  std::size_t pos = 0;
  while (pos < datagram.size()) {
    const std::size_t end = datagram.find_first_of("=\n", pos);
    if (end == std::string_view::npos || end == pos) return false;
    std::string name(datagram.substr(pos, end - pos));
    if (datagram[end] == '=') {
      const std::size_t newline = datagram.find('\n', end + 1);
      if (newline == std::string_view::npos) return false;
      out[name] = std::string(datagram.substr(end + 1, newline - end - 1));
      pos = newline + 1;
      continue;
    }
    if (datagram.size() - end - 1 < 8) return false;
    std::uint64_t length = 0;
    for (std::size_t i = 0; i < 8; ++i) {
      length |= static_cast<std::uint64_t>(static_cast<unsigned char>(datagram[end + 1 + i]))
                << (8U * i);
    }
    const std::size_t start = end + 1 + 8;
    if (length >= datagram.size() - start || datagram[start + length] != '\n') return false;
    out[name] = std::string(datagram.substr(start, length));
    pos = start + length + 1;
  }
  return true;
}

// Runs `body` in a child process whose /run is a private tmpfs with our datagram socket at
// /run/systemd/journal/socket, and returns every entry it sent, decoded. nullopt (with `why`)
// when this machine does not allow a private mount namespace.
std::optional<std::vector<FieldMap>> capture_journal(const std::function<void()>& body,
                                                     std::string& why) {
  int pipe_fds[2];
  if (::pipe(pipe_fds) != 0) {
    why = "pipe failed";
    return std::nullopt;
  }
  const pid_t child = ::fork();
  if (child == 0) {
    ::close(pipe_fds[0]);
    const auto fail = [&](const char* what) {
      const std::string line = std::string("!") + what + ": " + std::strerror(errno);
      (void)!::write(pipe_fds[1], line.data(), line.size());
      ::_exit(1);
    };
    if (::unshare(CLONE_NEWNS) != 0) fail("unshare(CLONE_NEWNS)");
    if (::mount(nullptr, "/", nullptr, MS_REC | MS_PRIVATE, nullptr) != 0)
      fail("mount --make-rprivate /");
    if (::mount("tmpfs", "/run", "tmpfs", 0, "mode=0755") != 0) fail("mount tmpfs on /run");
    ::mkdir("/run/systemd", 0755);
    ::mkdir("/run/systemd/journal", 0755);
    const int fd = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    sockaddr_un address{};
    address.sun_family = AF_UNIX;
    std::strcpy(address.sun_path, "/run/systemd/journal/socket");
    if (::bind(fd, reinterpret_cast<const sockaddr*>(&address), sizeof(address)) != 0) fail("bind");
    body();
    std::string out;
    while (true) {
      pollfd p{fd, POLLIN, 0};
      if (::poll(&p, 1, 200) <= 0) break;
      std::vector<char> buffer(1U << 20U);
      iovec io{buffer.data(), buffer.size()};
      alignas(cmsghdr) char control[CMSG_SPACE(sizeof(int))] = {};
      msghdr message{};
      message.msg_iov = &io;
      message.msg_iovlen = 1;
      message.msg_control = control;
      message.msg_controllen = sizeof(control);
      const ssize_t n = ::recvmsg(fd, &message, 0);
      if (n < 0) break;
      std::string entry(buffer.data(), static_cast<std::size_t>(n));
      for (cmsghdr* h = CMSG_FIRSTHDR(&message); h != nullptr; h = CMSG_NXTHDR(&message, h)) {
        if (h->cmsg_level == SOL_SOCKET && h->cmsg_type == SCM_RIGHTS) {  // a memfd
          int passed = -1;
          std::memcpy(&passed, CMSG_DATA(h), sizeof(int));
          entry.clear();
          char chunk[65536];
          ssize_t got = 0;
          while ((got = ::pread(passed, chunk, sizeof(chunk), static_cast<off_t>(entry.size()))) >
                 0) {
            entry.append(chunk, static_cast<std::size_t>(got));
          }
          ::close(passed);
        }
      }
      const std::uint64_t size = entry.size();
      out.append(reinterpret_cast<const char*>(&size), sizeof(size));
      out += entry;
    }
    std::size_t written = 0;
    while (written < out.size()) {
      const ssize_t n = ::write(pipe_fds[1], out.data() + written, out.size() - written);
      if (n <= 0) break;
      written += static_cast<std::size_t>(n);
    }
    ::_exit(0);
  }
  ::close(pipe_fds[1]);
  std::string data;
  char chunk[65536];
  ssize_t n = 0;
  while ((n = ::read(pipe_fds[0], chunk, sizeof(chunk))) > 0)
    data.append(chunk, static_cast<std::size_t>(n));
  ::close(pipe_fds[0]);
  int status = 0;
  ::waitpid(child, &status, 0);
  if (!data.empty() && data[0] == '!') {
    why = data.substr(1);
    return std::nullopt;
  }
  std::vector<FieldMap> entries;
  std::size_t pos = 0;
  while (pos + 8 <= data.size()) {
    std::uint64_t size = 0;
    std::memcpy(&size, data.data() + pos, sizeof(size));
    pos += 8;
    FieldMap fields;
    if (!decode_native(std::string_view(data).substr(pos, size), fields)) {
      why = "malformed entry";
      return std::nullopt;
    }
    entries.push_back(std::move(fields));
    pos += size;
  }
  return entries;
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

TEST(JournalFields, CataloguedEventCarriesItsMessageId) {
  const Fields extra{{"code", "drive_fault"}};
  Record record;
  record.level = Level::warn;
  record.component = "safety";
  record.event = "fault_raised";
  record.fields = &extra;
  record.text = "fault: drive fault";
  record.catalogued = Catalogued::DriveFault;
  const std::vector<JournalField> expected = {
      {"MESSAGE", "fault: drive fault"},
      {"PRIORITY", "4"},
      {"MESSAGE_ID", "3a5f987995d8489ab4d2924e22af2290"},
      {"SYSLOG_IDENTIFIER", "liftd"},
      {"LIFTD_COMPONENT", "safety"},
      {"LIFTD_EVENT", "fault_raised"},
      {"LIFTD_CODE", "drive_fault"},
  };
  EXPECT_EQ(journal_fields(record, "liftd"), expected);
}

TEST(JournalFields, MessageIdFollowsTheKeyNeverTheText) {
  // Legend: LIFTD_EVENT, one extra field, catalog key -> catalog entry name ("" = no MESSAGE_ID).
  struct Case {
    const char* event;
    Fields fields;
    std::optional<Catalogued> key;
    const char* expected;
  };
  const std::vector<Case> cases = {
      {"fault_raised", {{"code", "link_fault"}}, Catalogued::LinkLost, "link_lost"},
      {"fault_raised", {{"code", "renamed_link_fault"}}, Catalogued::LinkLost, "link_lost"},
      {"renamed_fault_raised", {{"code", "link_fault"}}, Catalogued::LinkLost, "link_lost"},
      {"", {}, Catalogued::Started, "started"},
      {"fault_raised", {{"code", "link_fault"}}, std::nullopt, ""},
      {"travel_aborted", {{"cause", "safety_chain_open"}}, std::nullopt, ""},
      {"ready", {}, std::nullopt, ""},
      {"ready", {}, Catalogued::kCount, ""},
  };
  for (const auto& c : cases) {
    Record record;
    record.event = c.event;
    record.fields = &c.fields;
    record.text = "x";
    record.catalogued = c.key;
    std::vector<std::string> names;
    for (const auto& [field, value] : journal_fields(record, "liftd")) {
      if (field != "MESSAGE_ID") continue;
      for (const auto& entry : catalog()) {
        if (entry.id == value) names.emplace_back(entry.name);
      }
    }
    EXPECT_EQ(names, c.expected[0] == '\0' ? std::vector<std::string>{}
                                           : std::vector<std::string>{c.expected})
        << c.event;
  }
}

TEST(Catalog, EveryKeyHasItsNameAndId) {
  // Legend: key -> catalog entry name and MESSAGE_ID, as systemd/liftd.catalog and the saved
  // queries of technicians know them; every key in declaration order.
  struct Row {
    Catalogued key;
    const char* name;
    const char* id;
  };
  const std::vector<Row> rows = {
      {Catalogued::Started, "started", "0f2a19dbd8a64ea99e54148dc512defd"},
      {Catalogued::Stopped, "stopped", "52edbf52818f43d4bd48bfa2a7c4e429"},
      {Catalogued::StartFailed, "start_failed", "2c13340a9417459f846a681157696589"},
      {Catalogued::ConfigRefused, "config_refused", "4ab90acd59804c488255bbfdafff0567"},
      {Catalogued::ReloadRefused, "reload_refused", "fe421f6e61e74b048f764a419cf18ed7"},
      {Catalogued::ReloadNeedsRestart, "reload_needs_restart", "758f5b15d4794881bdd6f4f14cb21111"},
      {Catalogued::WatchdogWithheld, "watchdog_withheld", "53798ea0112d4e99bf4e2245cbb7117d"},
      {Catalogued::LinkLost, "link_lost", "91c498ffaa7944c9a9ac4f8ca304a670"},
      {Catalogued::LinkRestored, "link_restored", "847992ef8a0147b888c1e99373159da8"},
      {Catalogued::SerialPortLost, "serial_port_lost", "7a709f3db0e847e587c4a3f5373882ea"},
      {Catalogued::DriveFault, "drive_fault", "3a5f987995d8489ab4d2924e22af2290"},
      {Catalogued::DriveErrorLog, "drive_error_log", "310ba254364441ef9e4f291611ca8724"},
      {Catalogued::DriveAdvanceWarning, "drive_advance_warning",
       "b8923085dc4d4978b87d0e769e5807f6"},
      {Catalogued::SafetyChainOpen, "safety_chain_open", "a24d5247030f433d990dd88d17eddc66"},
      {Catalogued::SafetyChainOpenedMidTravel, "safety_chain_opened_mid_travel",
       "ce1139c89ae344019ff1b085dbe3478a"},
      {Catalogued::TravelAborted, "travel_aborted", "aead774b70ba409fbc70c9f8ee6890af"},
      {Catalogued::PositionLost, "position_lost", "c76df52c044d40f6a05d28aabccedd45"},
      {Catalogued::InputsLost, "inputs_lost", "f9209d2c1374471fa1cdca417d350e8c"},
      {Catalogued::CardFault, "card_fault", "747a03af540d46ba85f3190021b6809f"},
      {Catalogued::CanOwnIdInUse, "can_own_id_in_use", "2f12340309554c1dbc6ad2ed1abc8d9c"},
      {Catalogued::UssSlaveFault, "uss_slave_fault", "dce538ec71c248bebd75a1de4dcdb397"},
      {Catalogued::RecordOff, "record_off", "ba707342f0964343abf3310a4b757142"},
  };
  ASSERT_EQ(rows.size(), static_cast<std::size_t>(Catalogued::kCount))
      << "a key without a row here";
  for (std::size_t i = 0; i < rows.size(); ++i) {
    EXPECT_EQ(static_cast<std::size_t>(rows[i].key), i) << rows[i].name << ": rows out of order";
    EXPECT_EQ(message_id(rows[i].key), rows[i].id) << rows[i].name;
  }
  EXPECT_EQ(message_id(Catalogued::kCount), "");
}

TEST(Catalog, OneEntryPerKeyWithWellFormedUniqueIds) {
  ASSERT_EQ(catalog().size(), static_cast<std::size_t>(Catalogued::kCount));
  std::set<std::string_view> names;
  std::set<std::string_view> ids;
  for (std::size_t i = 0; i < catalog().size(); ++i) {
    const CatalogEntry& entry = catalog()[i];
    EXPECT_EQ(static_cast<std::size_t>(entry.key), i) << entry.name << ": not indexed by its key";
    EXPECT_EQ(message_id(entry.key), entry.id) << entry.name;
    ASSERT_EQ(entry.id.size(), 32U) << entry.name;
    for (char c : entry.id) {
      EXPECT_TRUE((c >= '0' && c <= '9') || (c >= 'a' && c <= 'f')) << entry.name;
    }
    EXPECT_TRUE(names.insert(entry.name).second) << "name twice: " << entry.name;
    EXPECT_TRUE(ids.insert(entry.id).second) << "id twice: " << entry.id;
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

TEST(StreamLine, CarriesThePriorityPrefixAndStaysOneLine) {
  const Fields extra{{"cause", "10 lost frames"}};
  // Legend: level, component, event, text -> the stderr line journald's stream reader parses.
  struct Case {
    Level level;
    const char* component;
    const char* event;
    const char* text;
    const Fields* fields;
    const char* expected;
  };
  const std::vector<Case> cases = {
      {Level::error, "dcp", "link_fault", "drive link lost", &extra,
       "<3>dcp: drive link lost [event=link_fault cause=\"10 lost frames\"]"},
      {Level::warn, "api", "", "slow client", nullptr, "<4>api: slow client"},
      {Level::info, "", "", "hello", nullptr, "<6>liftd: hello"},
      {Level::debug, "sim", "", "two\nlines", nullptr, "<7>sim: two lines"},
      {Level::trace, "rt", "", "x", nullptr, "<7>rt: x"},
  };
  for (const auto& c : cases) {
    Record record;
    record.level = c.level;
    record.component = c.component;
    record.event = c.event;
    record.text = c.text;
    record.fields = c.fields;
    EXPECT_EQ(format_stream_line(record), c.expected) << c.text;
  }
}

TEST(JournalSend, EntryArrivesWithStructuredFieldsAndMessageId) {
  std::string why;
  const auto entries = capture_journal(
      [&] {
        init({Level::info, Backend::journal, "liftd-test"});
        event(Level::warn, "safety", "fault_raised", {{"code", "link_fault"}}, "fault: link lost",
              Catalogued::LinkLost);
        write(Level::error, "config", "two\nlines");
        Logger("api").debug("not written at info");
        event(Level::info, "dcp", "big", {}, std::string(300000, 'x'));  // passed as a memfd
      },
      why);
  if (!entries) GTEST_SKIP() << "no private journal socket possible here (" << why << ")";
  ASSERT_EQ(entries->size(), 3U);
  const FieldMap& first = (*entries)[0];
  EXPECT_EQ(first.at("MESSAGE"), "fault: link lost");
  EXPECT_EQ(first.at("PRIORITY"), "4");
  EXPECT_EQ(first.at("MESSAGE_ID"), "91c498ffaa7944c9a9ac4f8ca304a670");
  EXPECT_EQ(first.at("SYSLOG_IDENTIFIER"), "liftd-test");
  EXPECT_EQ(first.at("LIFTD_COMPONENT"), "safety");
  EXPECT_EQ(first.at("LIFTD_EVENT"), "fault_raised");
  EXPECT_EQ(first.at("LIFTD_CODE"), "link_fault");
  EXPECT_THAT(first.at("CODE_FILE"), HasSubstr("log_test.cpp"));
  EXPECT_GT(std::stoi(first.at("CODE_LINE")), 0);
  EXPECT_THAT(first.at("CODE_FUNC"), HasSubstr("EntryArrivesWithStructuredFieldsAndMessageId"));
  EXPECT_EQ((*entries)[1].at("MESSAGE"), "two\nlines");
  EXPECT_EQ((*entries)[1].at("PRIORITY"), "3");
  EXPECT_EQ((*entries)[1].count("MESSAGE_ID"), 0U);
  EXPECT_EQ((*entries)[2].at("MESSAGE").size(), 300000U);
}

TEST(JournalSend, MessageIdComesFromTheKeyNotTheRecordText) {
  std::string why;
  const auto entries = capture_journal(
      [&] {
        init({Level::info, Backend::journal, "liftd-test"});
        // A lift fault record whose event and code texts were renamed keeps its id ...
        event(Level::warn, "safety", "fault_raised_renamed", {{"code", "lost_link"}},
              "fault: link lost", Catalogued::LinkLost);
        // ... and the old texts without the key get none.
        event(Level::warn, "safety", "fault_raised", {{"code", "link_fault"}}, "fault: link lost");
        Logger("travel").event(Level::warn, "travel_aborted", {{"cause", "x"}}, "travel aborted",
                               Catalogued::SafetyChainOpenedMidTravel);
      },
      why);
  if (!entries) GTEST_SKIP() << "no private journal socket possible here (" << why << ")";
  ASSERT_EQ(entries->size(), 3U);
  EXPECT_EQ((*entries)[0].at("MESSAGE_ID"), "91c498ffaa7944c9a9ac4f8ca304a670");
  EXPECT_EQ((*entries)[0].at("LIFTD_CODE"), "lost_link");
  EXPECT_EQ((*entries)[1].count("MESSAGE_ID"), 0U);
  EXPECT_EQ((*entries)[1].at("LIFTD_CODE"), "link_fault");
  EXPECT_EQ((*entries)[2].at("MESSAGE_ID"), "ce1139c89ae344019ff1b085dbe3478a");
  EXPECT_THAT((*entries)[2].at("CODE_FUNC"), HasSubstr("MessageIdComesFromTheKeyNotTheRecordText"));
}

TEST(JournalSend, FallsBackToPrefixedStderrLinesWhereNoJournalListens) {
  std::string why;
  const auto entries = capture_journal(
      [] {
        // journald gone: the socket path is empty while liftd logs, stderr goes to a file.
        ::rename("/run/systemd/journal/socket", "/run/systemd/journal/hidden");
        init({Level::info, Backend::journal, "liftd"});
        const int fd = ::open("/run/err.txt", O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
        ::dup2(fd, 2);
        event(Level::error, "dcp", "link_fault", {{"cause", "x"}}, "first");
        event(Level::warn, "dcp", "link_fault", {}, "second");
        std::fflush(stderr);
        std::ifstream in("/run/err.txt");
        std::ostringstream text;
        text << in.rdbuf();
        // Back again: hand what stderr got to the test as one entry.
        ::rename("/run/systemd/journal/hidden", "/run/systemd/journal/socket");
        send_to_journal({{"MESSAGE", text.str()}});
      },
      why);
  if (!entries) GTEST_SKIP() << "no private journal socket possible here (" << why << ")";
  ASSERT_EQ(entries->size(), 1U);
  EXPECT_EQ((*entries)[0].at("MESSAGE"),
            "<4>liftd: cannot write to the journal: No such file or directory; logging to stderr\n"
            "<3>dcp: first [event=link_fault cause=x]\n"
            "<4>dcp: second [event=link_fault]\n");
}

TEST(JournalSend, ReportsAMissingJournal) {
  std::string why;
  const auto entries = capture_journal(
      [] {
        ::rename("/run/systemd/journal/socket", "/run/systemd/journal/hidden");
        const int error = send_to_journal({{"MESSAGE", "x"}});
        ::rename("/run/systemd/journal/hidden", "/run/systemd/journal/socket");
        send_to_journal({{"MESSAGE", std::to_string(error)}});
      },
      why);
  if (!entries) GTEST_SKIP() << "no private journal socket possible here (" << why << ")";
  ASSERT_EQ(entries->size(), 1U);
  EXPECT_EQ((*entries)[0].at("MESSAGE"), std::to_string(ENOENT));
}

TEST(LogText, WritesReadableLinesToStderr) {
  init({Level::debug, Backend::text, "liftd"});
  ::testing::internal::CaptureStderr();
  Logger("sim").debug("car at {} mm", 3000);
  event(Level::info, "daemon", "ready", {{"status", "simulated lift"}}, "ready");
  const std::string err = ::testing::internal::GetCapturedStderr();
  init({Level::info, Backend::text, "liftd"});
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
