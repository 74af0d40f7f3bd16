// The server through a real Unix socket in a temp dir, with the fake backend.
#include <fcntl.h>
#include <sys/stat.h>
#include <sys/un.h>

#include <algorithm>
#include <fstream>
#include <future>
#include <vector>

#include "api/test_support.hpp"
#include "common/version.hpp"

namespace liftd::api::testing {
namespace {

using nlohmann::json;

class ApiServer : public ServerFixture {
 protected:
  /// A `mark` command that notes each request's id in `order`, in the order the io thread
  /// handles them (read `order` on the io thread).
  void add_mark_command(std::vector<std::string>& order) {
    on_io([&] {
      server_->dispatcher().add({"mark",
                                 Access::Read,
                                 {},
                                 "",
                                 [&order](const Call& call, Responder done) {
                                   order.push_back(call.request.at("id").get<std::string>());
                                   done(Result::ok());
                                 },
                                 kEveryDriveKind});
    });
  }
};

TEST_F(ApiServer, GreetsWithVersionAndAccess) {
  start_server();
  Client client(socket_path());
  ASSERT_TRUE(client.connected());
  const auto hello = client.read_json();
  ASSERT_TRUE(hello);
  EXPECT_EQ(hello->at("event"), "hello");
  EXPECT_EQ(hello->at("data").at("version"), std::string(kVersion));
  EXPECT_EQ(hello->at("data").at("api"), 3);
  EXPECT_EQ(hello->at("data").at("access"), json::array({"read", "control", "inputs"}));
  EXPECT_EQ(hello->at("data").at("max_line_bytes"), 65536);
}

TEST_F(ApiServer, EchoesIdsOfNumbersStringsAndObjects) {
  start_server();
  auto client = connect();
  for (const json& id : {json(1), json(2.5), json("req-7"), json{{"seq", 3}, {"from", "disp"}}}) {
    const json reply = client->call({{"cmd", "status"}, {"id", id}});
    EXPECT_EQ(reply.at("id"), id);
    EXPECT_TRUE(reply.at("ok").get<bool>());
    EXPECT_EQ(reply.at("result").at("link").at("state"), "up");
  }
}

TEST_F(ApiServer, ReportsErrorCodesOverTheSocket) {
  start_server();
  auto client = connect();
  // Legend: request line, expected error code.
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"{\"cmd\":", "bad_json"},
      {R"({"cmd":"status","x":1})", "bad_request"},
      {R"({"cmd":"nope"})", "unknown_cmd"},
  };
  for (const auto& [line, code] : cases) {
    ASSERT_TRUE(client->send(line + "\n"));
    const auto reply = client->read_json();
    ASSERT_TRUE(reply) << line;
    EXPECT_EQ(reply->at("error").at("code"), code) << line;
  }
  for (const auto code : {ErrorCode::NotReady, ErrorCode::Busy, ErrorCode::Fault}) {
    on_io([&] { backend_.control_result = Result::fail(code, "no"); });
    EXPECT_EQ(client->call({{"cmd", "drive_reset"}}).at("error").at("code"), to_string(code));
  }
  on_io([this] {
    server_->dispatcher().add({"crash",
                               Access::Read,
                               {},
                               "",
                               [](const Call&, Responder) { throw std::logic_error("x"); },
                               kEveryDriveKind});
  });
  EXPECT_EQ(client->call({{"cmd", "crash"}}).at("error").at("code"), "internal");
  // forbidden: see access_test.cpp (needs another uid); too_large and timeout below.
  EXPECT_EQ(counters().errors, 7U);
}

TEST_F(ApiServer, MalformedJsonLeavesTheConnectionUsable) {
  start_server();
  auto client = connect();
  ASSERT_TRUE(client->send("{this is not json}\n"));
  const auto bad = client->read_json();
  ASSERT_TRUE(bad);
  EXPECT_EQ(bad->at("ok"), false);
  EXPECT_EQ(bad->at("error").at("code"), "bad_json");
  EXPECT_TRUE(bad->at("id").is_null());
  const json good = client->call({{"cmd", "version"}, {"id", 2}});
  EXPECT_EQ(good.at("ok"), true);
  EXPECT_EQ(good.at("id"), 2);
}

TEST_F(ApiServer, AnswersPipelinedRequestsInOrderAndIgnoresBlankLines) {
  start_server();
  auto client = connect();
  std::string batch;
  for (int i = 0; i < 100; ++i) batch += json{{"cmd", "version"}, {"id", i}}.dump() + "\r\n\n";
  ASSERT_TRUE(client->send(batch));
  for (int i = 0; i < 100; ++i) {
    const auto reply = client->read_json();
    ASSERT_TRUE(reply);
    EXPECT_EQ(reply->at("id"), i);
  }
}

TEST_F(ApiServer, APipeliningClientTakesTurnsWithTheOthers) {
  // One client's batch of requests must not hold the io thread while another waits.
  // The io thread is held until both clients have written, so both are readable at once; the
  // batch came first. The one request of the second client is handled after at most one turn
  // of the first (a handful of lines), not after the whole batch.
  start_server();
  std::vector<std::string> order;  // io thread only
  add_mark_command(order);
  auto batcher = connect();
  auto single = connect();
  std::promise<void> release;
  std::shared_future<void> released = release.get_future().share();
  asio::post(io_, [released] { released.wait(); });
  std::string batch;
  for (int i = 0; i < 40; ++i)
    batch += json{{"cmd", "mark"}, {"id", "a" + std::to_string(i)}}.dump() + "\n";
  ASSERT_TRUE(batcher->send(batch));
  ASSERT_TRUE(single->send(json{{"cmd", "mark"}, {"id", "b"}}.dump() + "\n"));
  release.set_value();
  const json reply = single->read_json().value_or(json());
  EXPECT_EQ(reply.value("id", json()), "b");
  for (int i = 0; i < 40; ++i) {
    const auto r = batcher->read_json();
    ASSERT_TRUE(r);
    EXPECT_EQ(r->at("id"), "a" + std::to_string(i));  // its own order is kept
  }
  const auto seen = on_io([&] { return order; });
  ASSERT_EQ(seen.size(), 41U);
  const auto b_at = std::find(seen.begin(), seen.end(), "b") - seen.begin();
  EXPECT_LE(b_at, 8) << "the second client waited behind " << b_at << " of the batch";
}

TEST_F(ApiServer, RequestsBeyondTheBudgetWaitTheirTurnAndAreAllAnswered) {
  // 40 requests a second over all clients, so the first 4 are answered at once and the rest
  // one every 25 ms: 40 pipelined requests take at least (40 - 4) x 25 ms. None is refused.
  ServerConfig config = default_config();
  config.max_requests_per_second = 40;
  start_server(config);
  auto client = connect();
  std::string batch;
  for (int i = 0; i < 40; ++i) batch += json{{"cmd", "version"}, {"id", i}}.dump() + "\n";
  const auto sent = std::chrono::steady_clock::now();
  ASSERT_TRUE(client->send(batch));
  for (int i = 0; i < 40; ++i) {
    const auto reply = client->read_json(5s);
    ASSERT_TRUE(reply) << "reply " << i;
    EXPECT_EQ(reply->at("id"), i);
    EXPECT_EQ(reply->at("ok"), true);
  }
  EXPECT_GE(std::chrono::steady_clock::now() - sent, 36 * 25ms);
  const auto counters = on_io([&] { return server_->counters(); });
  EXPECT_GE(counters.budget_waits, 1U);
  EXPECT_EQ(counters.requests, 40U);
}

TEST_F(ApiServer, ClientsWaitingForTheBudgetShareItEvenly) {
  // Two clients pipeline far more than the budget allows; while both wait, each gets every
  // other turn. Counted on the io thread: of the first 40 answered after the burst, each had
  // between 16 and 24 (a turn is at most four lines, so shares may differ by a turn).
  ServerConfig config = default_config();
  config.max_requests_per_second = 200;
  start_server(config);
  std::vector<std::string> order;  // io thread only
  add_mark_command(order);
  auto a = connect();
  auto b = connect();
  std::string batch_a;
  std::string batch_b;
  for (int i = 0; i < 60; ++i) {
    batch_a += json{{"cmd", "mark"}, {"id", "a" + std::to_string(i)}}.dump() + "\n";
    batch_b += json{{"cmd", "mark"}, {"id", "b" + std::to_string(i)}}.dump() + "\n";
  }
  ASSERT_TRUE(a->send(batch_a));
  ASSERT_TRUE(b->send(batch_b));
  for (int i = 0; i < 60; ++i) {
    ASSERT_TRUE(a->read_json(5s)) << "a " << i;
    ASSERT_TRUE(b->read_json(5s)) << "b " << i;
  }
  const auto seen = on_io([&] { return order; });
  ASSERT_EQ(seen.size(), 120U);
  // The burst (20: a tenth of a second's worth) may go to whoever came first.
  const auto from = seen.begin() + 20;
  const auto a_share =
      std::count_if(from, from + 40, [](const std::string& id) { return id.front() == 'a'; });
  EXPECT_GE(a_share, 16) << "a had " << a_share << " of 40 turns' lines";
  EXPECT_LE(a_share, 24) << "a had " << a_share << " of 40 turns' lines";
}

TEST_F(ApiServer, ReconfigureLiftsTheBudgetForClientsAlreadyWaiting) {
  ServerConfig config = default_config();
  config.max_requests_per_second = 1;  // 4 at once, then one a second
  start_server(config);
  auto client = connect();
  std::string batch;
  for (int i = 0; i < 20; ++i) batch += json{{"cmd", "version"}, {"id", i}}.dump() + "\n";
  ASSERT_TRUE(client->send(batch));
  for (int i = 0; i < 4; ++i) ASSERT_TRUE(client->read_json(5s));
  ServerConfig next = config;
  next.max_requests_per_second = 0;
  on_io([&] { server_->reconfigure(next); });
  // The other 16 come now, not over 16 seconds.
  for (int i = 4; i < 20; ++i) {
    const auto reply = client->read_json(3s);
    ASSERT_TRUE(reply) << "reply " << i;
    EXPECT_EQ(reply->at("id"), i);
  }
}

TEST_F(ApiServer, OversizedLineGetsTooLargeThenClose) {
  ServerConfig config = default_config();
  config.max_line_bytes = 1024;
  start_server(config);
  auto client = connect();
  // Exactly at the limit is fine.
  std::string at_limit = R"({"cmd":"version","id":")";
  at_limit += std::string(1024 - at_limit.size() - 2, 'a') + "\"}";
  ASSERT_EQ(at_limit.size(), 1024U);
  EXPECT_EQ(client->call(json::parse(at_limit)).at("ok"), true);
  // One byte more, and no newline needed for the server to give up.
  std::string over = R"({"cmd":"version","id":")" + std::string(1100, 'b');
  ASSERT_TRUE(client->send(over));
  const auto reply = client->read_json();
  ASSERT_TRUE(reply);
  EXPECT_EQ(reply->at("error").at("code"), "too_large");
  EXPECT_TRUE(client->wait_closed());
}

TEST_F(ApiServer, HugeLineDoesNotGrowMemoryBeyondTheLimit) {
  start_server();
  auto client = connect();
  // 1 MiB without a newline: the server answers too_large after 64 KiB and closes, so the
  // rest of the send may fail; that is expected.
  client->send(std::string(1 << 20, ' '));
  const auto reply = client->read_json();
  ASSERT_TRUE(reply);
  EXPECT_EQ(reply->at("error").at("code"), "too_large");
  EXPECT_TRUE(client->wait_closed());
}

TEST_F(ApiServer, AssemblesARequestFromPartialWrites) {
  start_server();
  auto client = connect();
  const std::string line = R"({"cmd":"version","id":"pieces"})"
                           "\n";
  for (char c : line) {
    ASSERT_TRUE(client->send(std::string(1, c)));
    std::this_thread::sleep_for(1ms);
  }
  const auto reply = client->read_json();
  ASSERT_TRUE(reply);
  EXPECT_EQ(reply->at("id"), "pieces");
}

TEST_F(ApiServer, PartialLineTimesOut) {
  ServerConfig config = default_config();
  config.partial_line_timeout = 200ms;
  start_server(config);
  auto client = connect();
  const auto sent_at = std::chrono::steady_clock::now();
  ASSERT_TRUE(client->send(R"({"cmd":"sta)"));
  const auto reply = client->read_json(10s);
  const auto elapsed = std::chrono::steady_clock::now() - sent_at;
  ASSERT_TRUE(reply);
  EXPECT_EQ(reply->at("error").at("code"), "timeout");
  EXPECT_GE(elapsed, 190ms);  // a timer never fires early; the upper bound is the machine's
  EXPECT_TRUE(client->wait_closed());
  EXPECT_EQ(counters().timeouts, 1U);
}

TEST_F(ApiServer, IdleClientIsClosedButWatcherIsNot) {
  ServerConfig config = default_config();
  config.idle_timeout = 200ms;
  start_server(config);
  auto idle = connect();
  auto watcher = connect();
  EXPECT_EQ(watcher->call({{"cmd", "watch"}, {"enable", true}}).at("ok"), true);
  const auto reply = idle->read_json(10s);
  ASSERT_TRUE(reply);
  EXPECT_EQ(reply->at("error").at("code"), "timeout");
  EXPECT_TRUE(idle->wait_closed());
  std::this_thread::sleep_for(300ms);
  EXPECT_EQ(watcher->call({{"cmd", "status"}, {"id", 1}}).at("id"), 1);
}

TEST_F(ApiServer, ServesManyClientsAtOnce) {
  ServerConfig config = default_config();
  config.max_clients = 40;
  start_server(config);
  std::vector<std::unique_ptr<Client>> clients;
  for (int i = 0; i < 32; ++i) {
    clients.push_back(connect());
    ASSERT_TRUE(clients.back()->connected());
  }
  // Interleave: every client sends 20 requests before anyone reads.
  for (int round = 0; round < 20; ++round) {
    for (std::size_t c = 0; c < clients.size(); ++c) {
      ASSERT_TRUE(clients[c]->send_json({{"cmd", "status"}, {"id", {c, round}}}));
    }
  }
  for (std::size_t c = 0; c < clients.size(); ++c) {
    for (int round = 0; round < 20; ++round) {
      const auto reply = clients[c]->read_json();
      ASSERT_TRUE(reply);
      EXPECT_EQ(reply->at("id"), (json{c, round}));
    }
  }
  EXPECT_EQ(counters().clients, 32U);
  EXPECT_EQ(counters().requests, 32U * 20U);
}

TEST_F(ApiServer, RefusesClientsBeyondMaxWithBusy) {
  ServerConfig config = default_config();
  config.max_clients = 3;
  start_server(config);
  std::vector<std::unique_ptr<Client>> clients;
  for (int i = 0; i < 3; ++i) clients.push_back(connect());
  Client extra(socket_path());
  ASSERT_TRUE(extra.connected());  // the kernel accepts; the server refuses at once
  const auto reply = extra.read_json();
  ASSERT_TRUE(reply);
  EXPECT_EQ(reply->at("ok"), false);
  EXPECT_EQ(reply->at("error").at("code"), "busy");
  EXPECT_TRUE(extra.wait_closed());
  EXPECT_EQ(counters().rejected, 1U);
  // A freed slot can be used again.
  clients.pop_back();
  ASSERT_TRUE(eventually([this] { return server_->counters().clients == 2; }));
  auto again = connect();
  EXPECT_EQ(again->call({{"cmd", "version"}}).at("ok"), true);
}

TEST_F(ApiServer, WatchStreamsEventsUntilDisabled) {
  start_server();
  auto client = connect();
  EXPECT_EQ(client->call({{"cmd", "watch"}, {"enable", true}, {"id", 1}}).at("result"),
            (json{{"watching", true}}));
  // The current state follows the reply at once.
  const auto state = client->read_json();
  ASSERT_TRUE(state);
  EXPECT_EQ(state->at("event"), "state");
  EXPECT_EQ(state->at("data").at("link").at("state"), "up");
  on_io([this] { server_->publish("drive_error", {{"text", "E12 overcurrent"}}); });
  const auto event = client->read_json();
  ASSERT_TRUE(event);
  EXPECT_EQ(*event, (json{{"event", "drive_error"}, {"data", {{"text", "E12 overcurrent"}}}}));
  EXPECT_EQ(client->call({{"cmd", "watch"}, {"enable", false}}).at("ok"), true);
  on_io([this] { server_->publish("fault", {{"code", "x"}}); });
  EXPECT_EQ(client->call({{"cmd", "version"}, {"id", "after"}}).at("id"), "after");
  EXPECT_FALSE(client->read_line(100ms));  // no event arrived after the stop
}

TEST_F(ApiServer, SlowWatcherIsToldWhatItMissedWhileAnotherKeepsItsStream) {
  ServerConfig config = default_config();
  config.write_queue_max_bytes = 64 * 1024;
  config.write_queue_max_messages = 256;
  start_server(config);
  auto slow = connect();
  auto fast = connect();
  for (auto* c : {slow.get(), fast.get()}) {
    ASSERT_EQ(c->call({{"cmd", "watch"}, {"enable", true}}).at("ok"), true);
    ASSERT_TRUE(c->read_json());  // the initial state event
  }
  // The slow watcher now stops reading. Publish 2 MiB in batches; the fast one reads each batch.
  const std::string payload(1000, 'x');
  constexpr int kBatches = 40;
  constexpr int kPerBatch = 50;
  int expected = 0;
  for (int batch = 0; batch < kBatches; ++batch) {
    on_io([&] {
      for (int i = 0; i < kPerBatch; ++i) {
        server_->publish("travel", {{"seq", batch * kPerBatch + i}, {"pad", payload}});
      }
    });
    for (int i = 0; i < kPerBatch; ++i) {
      const auto event = fast->read_json();
      ASSERT_TRUE(event) << "fast watcher lost its stream at event " << expected;
      ASSERT_EQ(event->at("data").at("seq"), expected);
      ++expected;
    }
  }
  // The slow one catches up: it stayed connected and got the events that fit, in order.
  int received = 0;
  int last_seq = -1;
  while (const auto event = slow->read_json(300ms)) {
    ASSERT_EQ(event->at("event"), "travel");
    const int seq = event->at("data").at("seq").get<int>();
    EXPECT_GT(seq, last_seq);
    last_seq = seq;
    ++received;
  }
  ASSERT_FALSE(slow->eof()) << "the slow watcher was disconnected";
  ASSERT_GT(received, 0);
  ASSERT_LT(received, kBatches * kPerBatch) << "the test never filled the queue";
  // The next event comes after a `missed` event counting every one it did not get.
  on_io([this] { server_->publish("fault", {{"code", "after"}}); });
  const auto missed = slow->read_json();
  ASSERT_TRUE(missed);
  ASSERT_EQ(missed->at("event"), "missed");
  EXPECT_EQ(missed->at("data").at("count").get<int>() + received, kBatches * kPerBatch);
  const auto after = slow->read_json();
  ASSERT_TRUE(after);
  EXPECT_EQ(after->at("event"), "fault");
  const ServerCounters c = counters();
  EXPECT_EQ(c.dropped, 0U);
  EXPECT_EQ(c.missed_events, static_cast<std::uint64_t>(kBatches * kPerBatch - received));
  EXPECT_EQ(c.clients, 2U);
  EXPECT_EQ(c.watchers, 2U);
}

TEST_F(ApiServer, ClientThatNeverReadsRepliesIsDropped) {
  ServerConfig config = default_config();
  config.write_queue_max_bytes = 16 * 1024;
  // The server stops reading from it once its queue is full, then drops it when it has taken
  // nothing for this long (30 s by default).
  config.stalled_reader_timeout = 300ms;
  start_server(config);
  auto hog = connect();
  auto other = connect();
  // The in-flight limit does not stop this: each reply is queued at once. Without reading,
  // replies fill the socket buffer, then the queue: the server must drop the client.
  const std::string request = json{{"cmd", "status"}}.dump() + "\n";
  std::string many;
  for (int i = 0; i < 200; ++i) many += request;
  for (int i = 0; i < 100 && !hog->eof(); ++i) {
    if (!hog->send(many)) break;
  }
  ASSERT_TRUE(eventually([this] { return server_->counters().dropped == 1; }));
  EXPECT_EQ(other->call({{"cmd", "version"}, {"id", 5}}).at("id"), 5);
}

TEST_F(ApiServer, ResponderOutlivingTheClientIsHarmless) {
  start_server();
  on_io([this] { backend_.defer = true; });
  {
    auto client = connect();
    ASSERT_TRUE(client->send_json({{"cmd", "drive_reset"}}));
    ASSERT_TRUE(eventually([this] { return backend_.deferred.size() == 1; }));
  }
  ASSERT_TRUE(eventually([this] { return server_->counters().clients == 0; }));
  on_io([this] { backend_.deferred[0](Result::ok()); });
  auto next = connect();
  EXPECT_EQ(next->call({{"cmd", "version"}}).at("ok"), true);
}

TEST_F(ApiServer, StatsIncludeApiCounters) {
  start_server();
  auto client = connect();
  client->call({{"cmd", "nope"}});
  const json stats = client->call({{"cmd", "stats"}}).at("result");
  EXPECT_EQ(stats.at("api").at("clients"), 1);
  EXPECT_EQ(stats.at("api").at("requests"), 2);
  EXPECT_EQ(stats.at("api").at("errors"), 1);
  EXPECT_TRUE(stats.at("link").contains("frames_sent"));
  EXPECT_TRUE(stats.at("cycle").contains("dropped_events"));
  EXPECT_TRUE(stats.at("cycle").contains("dropped_travel_samples"));
  EXPECT_TRUE(stats.at("dcp").is_object()) << "the drive kind's own counters";
}

// --- the socket file -----------------------------------------------------------------------

TEST_F(ApiServer, SocketFileGetsTheConfiguredMode) {
  start_server();
  struct stat st {};
  ASSERT_EQ(::stat(socket_path().c_str(), &st), 0);
  EXPECT_TRUE(S_ISSOCK(st.st_mode));
  EXPECT_EQ(st.st_mode & 0777, 0660U);
  stop_server();
  EXPECT_NE(::access(socket_path().c_str(), F_OK), 0) << "stop() removes the socket file";
}

TEST_F(ApiServer, StopLeavesASocketAnotherServerBoundSinceAlone) {
  start_server();
  // Someone deletes our socket file and another server binds the same path.
  ASSERT_EQ(::unlink(socket_path().c_str()), 0);
  asio::io_context other;
  asio::local::stream_protocol::acceptor theirs(
      other, asio::local::stream_protocol::endpoint(socket_path()));
  struct stat before {};
  ASSERT_EQ(::lstat(socket_path().c_str(), &before), 0);
  stop_server();
  struct stat after {};
  ASSERT_EQ(::lstat(socket_path().c_str(), &after), 0) << "stop() removed someone else's socket";
  EXPECT_EQ(after.st_ino, before.st_ino);
}

TEST_F(ApiServer, UsesAListeningSocketPassedToItAndLeavesItsFileAlone) {
  // What systemd does for liftd.socket: bind, set the mode, listen, pass the descriptor.
  const int fd = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
  sockaddr_un address{};
  address.sun_family = AF_UNIX;
  socket_path().copy(address.sun_path, sizeof(address.sun_path) - 1);
  ASSERT_EQ(::bind(fd, reinterpret_cast<const sockaddr*>(&address), sizeof(address)), 0);
  ASSERT_EQ(::chmod(socket_path().c_str(), 0600), 0);
  ASSERT_EQ(::listen(fd, 16), 0);
  ServerConfig config = default_config();
  config.listen_fd = fd;
  start_server(config);
  auto client = connect();
  EXPECT_EQ(client->call({{"cmd", "version"}}).at("ok"), true);
  stop_server();
  struct stat st {};
  ASSERT_EQ(::stat(socket_path().c_str(), &st), 0) << "stop() removed the manager's socket file";
  EXPECT_EQ(st.st_mode & 0777, 0600U) << "the passed socket keeps the mode its owner gave it";
}

// --- reconfigure (configuration reload) --------------------------------------------------------

TEST_F(ApiServer, ReconfigureLowersTheClientLimitForNewClientsOnly) {
  ServerConfig config = default_config();
  config.max_clients = 3;
  start_server(config);
  auto first = connect();
  auto second = connect();
  ServerConfig next = config;
  next.max_clients = 1;
  on_io([&] { server_->reconfigure(next); });
  // Connected clients stay; a new one is refused.
  EXPECT_EQ(first->call({{"cmd", "version"}}).at("ok"), true);
  EXPECT_EQ(second->call({{"cmd", "version"}}).at("ok"), true);
  Client extra(socket_path());
  const auto reply = extra.read_json();
  ASSERT_TRUE(reply);
  EXPECT_EQ(reply->at("error").at("code"), "busy");
}

TEST_F(ApiServer, ReconfigureWithAnUnknownGroupChangesNothing) {
  ServerConfig config = default_config();
  config.max_clients = 2;
  start_server(config);
  ServerConfig next = config;
  next.max_clients = 1;
  next.read_group = "liftd-no-such-group-xyz";
  const std::string error = on_io([&]() -> std::string {
    try {
      server_->reconfigure(next);
    } catch (const std::runtime_error& e) {
      return e.what();
    }
    return "";
  });
  EXPECT_NE(error.find("liftd-no-such-group-xyz"), std::string::npos) << error;
  // The limit is still 2.
  auto first = connect();
  auto second = connect();
  EXPECT_EQ(second->call({{"cmd", "version"}}).at("ok"), true);
  EXPECT_EQ(counters().rejected, 0U);
}

TEST_F(ApiServer, ReconfigureAppliesTheIdleTimeoutToConnectedClients) {
  start_server();  // idle timeout 10 minutes
  auto client = connect();
  ServerConfig next = default_config();
  next.idle_timeout = 50ms;
  on_io([&] { server_->reconfigure(next); });
  const auto reply = client->read_json();
  ASSERT_TRUE(reply);
  EXPECT_EQ(reply->at("error").at("code"), "timeout");
  EXPECT_TRUE(client->wait_closed());
}

TEST_F(ApiServer, RemovesAStaleSocketFile) {
  {
    // A socket file nobody listens on, as a crashed daemon leaves behind.
    asio::io_context other;
    asio::local::stream_protocol::acceptor stale(
        other, asio::local::stream_protocol::endpoint(socket_path()));
  }
  ASSERT_EQ(::access(socket_path().c_str(), F_OK), 0);
  start_server();
  auto client = connect();
  EXPECT_EQ(client->call({{"cmd", "version"}}).at("ok"), true);
}

TEST_F(ApiServer, RefusesWhenAnotherServerListens) {
  start_server();
  asio::io_context io2;
  FakeBackend backend2;
  Server second(io2, backend2, default_config(), [](LogLevel, std::string_view) {});
  try {
    second.start();
    FAIL() << "second server started";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("another process is listening"), std::string::npos)
        << e.what();
  }
  // The first one still works and its socket file is untouched.
  auto client = connect();
  EXPECT_EQ(client->call({{"cmd", "version"}}).at("ok"), true);
}

TEST_F(ApiServer, RefusesToReplaceARegularFile) {
  std::ofstream(socket_path()) << "precious";
  asio::io_context io2;
  Server server(io2, backend_, default_config(), [](LogLevel, std::string_view) {});
  EXPECT_THROW(server.start(), std::runtime_error);
  std::ifstream in(socket_path());
  std::string content;
  in >> content;
  EXPECT_EQ(content, "precious");
}

TEST_F(ApiServer, UnknownGroupIsAClearStartupError) {
  ServerConfig config = default_config();
  config.control_group = "liftd-no-such-group-xyz";
  try {
    Server server(io_, backend_, config, [](LogLevel, std::string_view) {});
    FAIL() << "constructed with an unknown group";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("liftd-no-such-group-xyz"), std::string::npos);
  }
}

TEST_F(ApiServer, MissingDirectoryIsAClearStartupError) {
  ServerConfig config = default_config();
  config.socket_path = dir_ + "/missing/api.sock";
  Server server(io_, backend_, config, [](LogLevel, std::string_view) {});
  try {
    server.start();
    FAIL() << "started in a missing directory";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("cannot bind"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace liftd::api::testing
