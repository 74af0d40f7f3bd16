// API abuse and access: duplicate keys, raw NULs, capped echoes, half-close, backpressure for
// pipelining clients, per-uid limits and slots kept for control access, trace saving rights.
#include <grp.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <thread>
#include <vector>

#include "api/test_support.hpp"

namespace liftd::api::testing {
namespace {

using nlohmann::json;

class ApiAbuse : public ServerFixture {};

std::string error_code(const std::optional<json>& reply) {
  if (!reply) return "(no reply)";
  return reply->at("ok").get<bool>() ? "ok" : reply->at("error").at("code").get<std::string>();
}

TEST_F(ApiAbuse, DuplicateKeysAreBadJsonAndRunNothing) {
  start_server();
  auto client = connect();
  // Legend: a request with a key twice, at the top or nested; none may run.
  const std::vector<std::string> lines = {
      R"({"cmd":"status","cmd":"drive_reset"})",
      R"({"cmd":"drive_reset","id":1,"id":2})",
      R"({"cmd":"load","percent":10,"percent":90})",
      R"({"cmd":"inputs","x":{"a":1,"a":2}})",
  };
  for (const auto& line : lines) {
    ASSERT_TRUE(client->send(line + "\n"));
    const auto reply = client->read_json();
    ASSERT_EQ(error_code(reply), "bad_json") << line;
    EXPECT_NE(reply->at("error").at("message").get<std::string>().find("duplicate key"),
              std::string::npos)
        << line;
    EXPECT_TRUE(reply->at("id").is_null()) << line;
  }
  EXPECT_TRUE(on_io([this] { return backend_.requests_seen.empty(); }));
  // The same key in two different objects is fine.
  EXPECT_EQ(client->call(json::parse(R"({"cmd":"version","id":{"id":1}})")).at("ok"), true);
}

TEST_F(ApiAbuse, RawNulInALineIsBadJsonNotTheEndOfTheLine) {
  start_server();
  auto client = connect();
  std::string line = R"({"cmd":"drive_reset"})";
  line += '\0';
  line += "trailing\n";
  ASSERT_TRUE(client->send(line));
  const auto reply = client->read_json();
  ASSERT_EQ(error_code(reply), "bad_json");
  EXPECT_EQ(reply->at("error").at("message"),
            "raw NUL byte at offset 21: JSON text cannot contain one (inside a string write "
            "\\u0000)");
  EXPECT_TRUE(on_io([this] { return backend_.requests_seen.empty(); }));
  // An escaped NUL inside a string is just a character.
  EXPECT_EQ(client->call(json::parse(R"({"cmd":"version","id":"a\u0000b"})")).at("id"),
            std::string("a\0b", 3));
}

TEST_F(ApiAbuse, ErrorMessagesEchoAtMost64BytesOfInput) {
  start_server();
  auto client = connect();
  const std::string long_name(60000, 'k');
  const json unknown_cmd = client->call({{"cmd", long_name}});
  const auto message = unknown_cmd.at("error").at("message").get<std::string>();
  EXPECT_EQ(message, "unknown command \"" + std::string(64, 'k') + "... (60000 bytes)\"");
  const json unknown_field = client->call({{"cmd", "status"}, {long_name, 1}});
  EXPECT_LT(unknown_field.dump().size(), 400U);
  EXPECT_EQ(unknown_field.at("error").at("field"), std::string(64, 'k') + "... (60000 bytes)");
  // A cut never splits a UTF-8 character: 63 ASCII bytes then a 2-byte character.
  EXPECT_EQ(capped(std::string(63, 'a') + "\u00e4" + std::string(10, 'b')),
            std::string(63, 'a') + "... (75 bytes)");
}

TEST_F(ApiAbuse, IdsComeBackAsTheSameValueByTheDocumentedRule) {
  start_server();
  auto client = connect();
  // Legend: id as sent -> id as echoed (docs/api.md: the value, re-serialised).
  const std::vector<std::pair<std::string, std::string>> cases = {
      {R"("req-7")", R"("req-7")"},
      {"42", "42"},
      {"-3", "-3"},
      {"1e2", "100.0"},
      {"2.50", "2.5"},
      {R"({"a":[1,true]})", R"({"a":[1,true]})"},
  };
  for (const auto& [sent, echoed] : cases) {
    ASSERT_TRUE(client->send(R"({"cmd":"version","id":)" + sent + "}\n"));
    const auto line = client->read_line();
    ASSERT_TRUE(line) << sent;
    EXPECT_EQ(line->substr(0, 7 + echoed.size()), R"({"id":)" + echoed + ",") << sent;
  }
}

TEST_F(ApiAbuse, HalfClosedClientGetsItsRepliesThenTheClose) {
  start_server();
  on_io([this] { backend_.defer = true; });
  auto client = connect();
  // A travel-like command answered later, then a last line without a newline, then "that was
  // all" (shutdown for writing).
  ASSERT_TRUE(client->send(R"({"cmd":"drive_reset","id":1})"
                           "\n"
                           R"({"cmd":"version","id":2})"));
  ASSERT_EQ(::shutdown(client->fd(), SHUT_WR), 0);
  const auto version = client->read_json();
  ASSERT_TRUE(version) << "no reply after the half-close";
  EXPECT_EQ(version->at("id"), 2);
  ASSERT_TRUE(eventually([this] { return backend_.deferred.size() == 1; }));
  on_io([this] { backend_.deferred[0](Result::ok()); });
  const auto reset = client->read_json();
  ASSERT_TRUE(reset) << "the command ran but its reply was lost";
  EXPECT_EQ(reset->at("id"), 1);
  EXPECT_EQ(reset->at("ok"), true);
  EXPECT_TRUE(client->wait_closed());
  EXPECT_TRUE(eventually([this] { return server_->counters().clients == 0; }));
}

TEST_F(ApiAbuse, PipeliningClientGetsEveryReply) {
  ServerConfig config = default_config();
  config.write_queue_max_messages = 64;  // small, so the backlog is reached at once
  start_server(config);
  auto client = connect();
  constexpr int kRequests = 20000;
  std::atomic<bool> sent_all{false};
  // The sender pushes every request without waiting; the reader starts late and reads slowly
  // at first, so the replies back up in the socket and the server's queue.
  std::thread sender([&] {
    std::string batch;
    for (int i = 0; i < kRequests; ++i) batch += json{{"cmd", "version"}, {"id", i}}.dump() + "\n";
    sent_all = client->send(batch);
  });
  std::this_thread::sleep_for(300ms);
  int next = 0;
  for (; next < kRequests; ++next) {
    const auto reply = client->read_json(10s);
    if (!reply) break;
    ASSERT_EQ(reply->at("id"), next);
  }
  sender.join();
  EXPECT_TRUE(sent_all);
  EXPECT_EQ(next, kRequests) << "replies stopped at " << next;
  EXPECT_EQ(counters().dropped, 0U);
}

TEST_F(ApiAbuse, ClientThatStopsReadingIsDroppedAfterTheStallTimeout) {
  ServerConfig config = default_config();
  config.write_queue_max_bytes = 16 * 1024;
  config.stalled_reader_timeout = 300ms;
  start_server(config);
  auto hog = connect();
  auto other = connect();
  std::thread sender([&] {
    const std::string request = json{{"cmd", "status"}}.dump() + "\n";
    std::string many;
    for (int i = 0; i < 200; ++i) many += request;
    for (int i = 0; i < 1000; ++i) {
      if (!hog->send(many)) break;  // blocks while the server does not read; fails once dropped
    }
  });
  ASSERT_TRUE(eventually([this] { return server_->counters().dropped == 1; }, 10s));
  sender.join();
  EXPECT_EQ(other->call({{"cmd", "version"}, {"id", 5}}).at("id"), 5);
}

// Switches this process's effective user and groups (every thread: glibc does that) so that the
// connections made meanwhile carry those credentials; restores root on destruction.
class AsUser {
 public:
  AsUser(uid_t uid, gid_t gid) {
    ok_ = ::setgroups(1, &gid) == 0 && ::setegid(gid) == 0 && ::seteuid(uid) == 0;
  }
  ~AsUser() {
    (void)!::seteuid(0);
    (void)!::setegid(0);
    const gid_t root = 0;
    (void)!::setgroups(1, &root);
  }
  AsUser(const AsUser&) = delete;
  AsUser& operator=(const AsUser&) = delete;
  bool ok() const { return ok_; }

 private:
  bool ok_ = false;
};

class ApiLimits : public ServerFixture {
 protected:
  static constexpr uid_t kNobody = 65534;
  void SetUp() override {
    if (::geteuid() != 0) GTEST_SKIP() << "needs root to connect as other users";
    const group* nogroup = ::getgrnam("nogroup");
    if (nogroup == nullptr) GTEST_SKIP() << "needs the group nogroup";
    nogroup_ = nogroup->gr_gid;
  }
  ServerConfig limited(std::size_t max_clients, std::size_t reserved, std::size_t per_uid) {
    ServerConfig config = default_config();
    config.socket_group = "nogroup";
    config.read_group = "nogroup";
    config.max_clients = max_clients;
    config.reserved_clients = reserved;
    config.max_clients_per_uid = per_uid;
    return config;
  }
  /// Connects as nobody (read access only) and returns the client and its greeting.
  std::pair<std::unique_ptr<Client>, std::optional<json>> connect_as_reader() {
    std::unique_ptr<Client> client;
    {
      AsUser as(kNobody, nogroup_);
      EXPECT_TRUE(as.ok());
      client = std::make_unique<Client>(socket_path());
    }
    auto first = client->read_json();
    return {std::move(client), first};
  }
  gid_t nogroup_ = 0;
};

TEST_F(ApiLimits, OneUserCannotTakeMoreThanItsShare) {
  start_server(limited(32, 4, 3));
  std::vector<std::unique_ptr<Client>> held;
  for (int i = 0; i < 3; ++i) {
    auto [client, hello] = connect_as_reader();
    ASSERT_TRUE(hello && hello->contains("event")) << i;
    held.push_back(std::move(client));
  }
  auto [fourth, refusal] = connect_as_reader();
  ASSERT_EQ(error_code(refusal), "busy");
  EXPECT_EQ(refusal->at("error").at("message"),
            "uid 65534 already has 3 connections (limit 3 per user); close one first");
  EXPECT_TRUE(fourth->wait_closed());
  // Root is not limited per user.
  std::vector<std::unique_ptr<Client>> roots;
  for (int i = 0; i < 5; ++i) {
    roots.push_back(connect());
    EXPECT_EQ(roots.back()->call({{"cmd", "version"}}).at("ok"), true);
  }
}

TEST_F(ApiLimits, ReservedSlotsKeepRoomForControlAccess) {
  start_server(limited(4, 2, 8));
  std::vector<std::unique_ptr<Client>> held;
  for (int i = 0; i < 2; ++i) {
    auto [client, hello] = connect_as_reader();
    ASSERT_TRUE(hello && hello->contains("event")) << i;
    held.push_back(std::move(client));
  }
  auto [third, refusal] = connect_as_reader();
  ASSERT_EQ(error_code(refusal), "busy");
  EXPECT_EQ(refusal->at("error").at("message"),
            "too many clients: the last 2 of 4 connections are kept for control access; try later");
  // The dispatcher (root here) still gets in, twice; then the server is full for everyone.
  auto dispatcher = connect();
  EXPECT_EQ(dispatcher->call({{"cmd", "version"}}).at("ok"), true);
  auto technician = connect();
  EXPECT_EQ(technician->call({{"cmd", "version"}}).at("ok"), true);
  Client fifth(socket_path());
  EXPECT_EQ(error_code(fifth.read_json()), "busy");
}

TEST_F(ApiLimits, SavingATraceNeedsControlAccess) {
  start_server(limited(32, 4, 8));
  auto [reader, hello] = connect_as_reader();
  ASSERT_TRUE(hello);
  EXPECT_EQ(hello->at("data").at("access"), json::array({"read"}));
  const json saved = reader->call({{"cmd", "trace"}, {"save", true}, {"id", 1}});
  EXPECT_EQ(saved.at("error").at("code"), "forbidden");
  EXPECT_EQ(saved.at("error").at("message"),
            "\"trace\" with \"save\" needs control access; uid 65534 is not in that group");
  EXPECT_EQ(reader->call({{"cmd", "trace"}, {"id", 2}}).at("ok"), true);
  // Root may ask (the fake backend keeps no recorder: not_ready, not forbidden).
  auto root = connect();
  EXPECT_EQ(root->call({{"cmd", "trace"}, {"save", true}}).at("error").at("code"), "not_ready");
}

}  // namespace
}  // namespace liftd::api::testing
