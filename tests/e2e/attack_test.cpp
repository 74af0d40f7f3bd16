// The hydraulic and USS lifts under attack, end to end. A card scripted by the test on a Unix
// socket (can.interface "unix:PATH") drops its connection and comes back silent: liftd must treat
// the card's status as unknown (link init, travels refused) and answer the new card's first frame
// without a travel bit (card document 3d, 3e); an empty record is no end of the connection.
// Floods of pipelined requests during a travel: every reply is the truth (ok for what took
// effect, an error for what did not), never `internal`, checked against the lift's state after.
#include <gtest/gtest.h>
#include <poll.h>
#include <sys/socket.h>

#include <atomic>
#include <map>
#include <mutex>
#include <set>

#include "can/socket.hpp"
#include "e2e/harness.hpp"

namespace liftd::e2e {
namespace {

const json kFloors = json::array({{{"name", "0"}, {"level_mm", 0}},
                                  {{"name", "1"}, {"level_mm", 1200}},
                                  {{"name", "2"}, {"level_mm", 2400}}});
const json kHydraulic = {
    {"drive", {{"kind", "sch001"}}},
    {"floors", kFloors},
    {"sch001", {{"star_delta_ms", 500}, {"slowdown_up_mm", 300}, {"slowdown_down_mm", 350}}}};
const json kUss = {
    {"drive", {{"kind", "uss"}}},
    {"floors", kFloors},
    {"travel", {{"dcp3_decel_distance_mm", {{"V4", 700}, {"V3", 500}}}}},
    {"uss", {{"speeds", {{"V0", 10}, {"VN", 3}, {"VI", 30}, {"V3", 63}, {"V4", 100}}}}}};

constexpr std::uint32_t kFromCard = 0x581;  // card document 1.6: base 0x550 + 0x31
constexpr std::uint8_t kRdy = 0x02;         // 3b: RDY is bit 1 of the status byte

/// A card played by the test: listens where liftd's can.interface points, sends status frames
/// when told, and keeps every answer it read.
class ScriptedCard {
 public:
  explicit ScriptedCard(const std::string& path) : path_(path) {
    auto l = can::listen_unix(path);
    if (l) listener_ = l.value();
  }
  ~ScriptedCard() {
    peer_.reset();
    if (listener_ >= 0) ::close(listener_);
    ::unlink(path_.c_str());
  }
  ScriptedCard(const ScriptedCard&) = delete;
  ScriptedCard& operator=(const ScriptedCard&) = delete;

  bool listening() const { return listener_ >= 0; }
  /// Waits for liftd to connect (the first time, or after a drop).
  bool accept(std::chrono::milliseconds timeout) {
    pollfd p{listener_, POLLIN, 0};
    if (::poll(&p, 1, static_cast<int>(timeout.count())) != 1) return false;
    const int fd = ::accept4(listener_, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
    if (fd < 0) return false;
    peer_.emplace(can::CanSocket::adopt(fd));
    return true;
  }
  /// Drops the connection, as a card whose gateway restarts.
  void drop() { peer_.reset(); }
  /// Sends the status frame (3b) and returns liftd's answer's command byte (3c), or -1.
  int status(std::uint8_t byte) {
    if (!peer_) return -1;
    const std::array<std::uint8_t, 2> data = {0x61, byte};
    if (peer_->write(can::make_frame(kFromCard, data)) != 0) return -1;
    const auto end = Clock::now() + 2s;
    while (Clock::now() < end) {
      pollfd p{peer_->fd(), POLLIN, 0};
      ::poll(&p, 1, 20);
      const can::Received r = peer_->read();
      if (r.kind == can::Received::Kind::Frame && r.frame.length == 4 && r.frame.data[0] == 0x68) {
        return r.frame.data[1];
      }
    }
    return -1;
  }
  /// An empty SOCK_SEQPACKET record.
  void empty_record() {
    if (peer_) (void)::send(peer_->fd(), "", 0, MSG_NOSIGNAL);
  }

 private:
  std::string path_;
  int listener_ = -1;
  std::optional<can::CanSocket> peer_;
};

/// A liftd (no --simulate) whose card is `card_socket`, with its API on `api_socket`.
std::unique_ptr<liftd::testing::Process> start_liftd(const std::filesystem::path& dir,
                                                     const std::string& card_socket) {
  json config = kHydraulic;
  config["can"] = {{"interface", "unix:" + card_socket}};
  config["api"] = {{"socket", (dir / "api.sock").string()},
                   {"socket_group", ""},
                   {"read_group", ""},
                   {"control_group", ""},
                   {"inputs_group", ""}};
  config["rt"] = {{"require_realtime", false}, {"lock_memory", false}};
  config["position"] = {{"source", "api"}};
  const std::string config_path = (dir / "liftd.json").string();
  std::ofstream(config_path) << config.dump(2);
  return std::make_unique<liftd::testing::Process>(
      std::vector<std::string>{LIFTD_BINARY, "--config", config_path}, daemon_env(), dir.string(),
      "liftd");
}

/// The machine inputs of a car standing at floor 0 with its doors locked.
json inputs_at_floor_0() {
  return {{"cmd", "inputs"},      {"safety_chain", true}, {"doors_closed", true},
          {"doors_locked", true}, {"position_mm", 0},     {"inspection", false}};
}

TEST(HydraulicAttack, AReopenedEndpointToASilentCardIsNotReadyAndTheFirstAnswerHasNoTravelBit) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("liftd-e2e-" + std::to_string(::getpid()) + "-hyd-reopen");
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  ScriptedCard card((dir / "card.sock").string());
  ASSERT_TRUE(card.listening());
  auto daemon = start_liftd(dir, (dir / "card.sock").string());
  ASSERT_TRUE(card.accept(20s)) << daemon->err();
  std::unique_ptr<Client> connected;
  for (int i = 0; i < 100 && !connected; ++i) {
    auto c = std::make_unique<Client>((dir / "api.sock").string());
    if (c->connected()) connected = std::move(c);
    if (!connected) std::this_thread::sleep_for(100ms);
  }
  ASSERT_TRUE(connected) << daemon->err();
  Client& api = *connected;
  // The card is heard (RDY), the inputs say the car can travel: ready.
  json s;
  for (int i = 0; i < 50; ++i) {
    ASSERT_TRUE(api.call(inputs_at_floor_0()).value("ok", false));
    EXPECT_EQ(card.status(kRdy), 0);
    if (i == 10) card.empty_record();  // a record, not the end of the connection
    s = api.call({{"cmd", "status"}})["result"];
    if (i > 15 && s["drive"]["state"] == "ready") break;
  }
  ASSERT_EQ(s["link"]["state"], "up") << s.dump() << daemon->err();
  ASSERT_EQ(s["drive"]["state"], "ready") << s.dump();
  EXPECT_TRUE(s["faults"].empty()) << "the empty record faulted the link: " << s.dump();

  // The card's connection drops; liftd reopens to a card that stays silent.
  card.drop();
  ASSERT_TRUE(card.accept(10s)) << daemon->err();
  json after;
  for (int i = 0; i < 30; ++i) {
    ASSERT_TRUE(api.call(inputs_at_floor_0()).value("ok", false));
    after = api.call({{"cmd", "status"}})["result"];
    if (after["link"]["state"] != "fault" && after["link"]["state"] != "up") break;
    std::this_thread::sleep_for(100ms);
  }
  EXPECT_EQ(after["link"]["state"], "init") << after.dump();
  EXPECT_NE(after["drive"]["state"], "ready") << after.dump();
  EXPECT_TRUE(after["sch001"]["card"].is_null()) << "the old connection's status was kept";
  const json travel = api.call({{"cmd", "travel"}, {"floor", 2}});
  EXPECT_FALSE(travel.value("ok", true)) << travel.dump();
  EXPECT_EQ(travel["error"]["code"], "not_ready") << travel.dump();
  // The new card's first status (RDY): answered without any travel bit (before the fix: DW/UP).
  EXPECT_EQ(card.status(kRdy), 0);
  daemon->signal(SIGTERM);
  EXPECT_EQ(daemon->wait(10s), std::optional<int>(0)) << daemon->err();
  std::error_code ignored;
  std::filesystem::remove_all(dir, ignored);
}

/// `clients` connections each pipelining `per_client` requests made by `request(client, k)`;
/// every reply, by client, in the order sent.
std::vector<std::vector<json>> flood(const std::string& socket, int clients, int per_client,
                                     const std::function<json(int, int)>& request) {
  std::vector<std::vector<json>> replies(static_cast<std::size_t>(clients));
  std::vector<std::thread> threads;
  for (int c = 0; c < clients; ++c) {
    threads.emplace_back([&, c] {
      liftd::testing::ApiClient client(socket);
      if (!client.connected()) return;
      std::string lines;
      for (int k = 0; k < per_client; ++k) {
        json r = request(c, k);
        r["id"] = k;
        lines += r.dump() + "\n";
      }
      if (!client.send_line(lines.substr(0, lines.size() - 1))) return;
      auto& mine = replies[static_cast<std::size_t>(c)];
      const auto end = Clock::now() + 90s;
      while (static_cast<int>(mine.size()) < per_client && Clock::now() < end) {
        const json m = client.next(5s);
        if (m.is_object() && m.contains("id") && !m.contains("event")) mine.push_back(m);
      }
    });
  }
  for (auto& t : threads) t.join();
  return replies;
}

/// Counts of each reply outcome ("ok" or the error code); fails on `internal` and on a missing
/// reply.
std::map<std::string, int> outcomes(const std::vector<std::vector<json>>& replies, int per_client) {
  std::map<std::string, int> out;
  for (const auto& mine : replies) {
    EXPECT_EQ(static_cast<int>(mine.size()), per_client) << "replies missing";
    for (const json& r : mine) {
      const std::string code = r.value("ok", false) ? "ok" : r["error"]["code"].get<std::string>();
      EXPECT_NE(code, "internal") << r.dump();
      ++out[code];
    }
  }
  return out;
}

TEST(HydraulicAttack, CallFloodsDuringATravelAreAnsweredTruthfully) {
  Lift lift("hyd-flood", 4, json::object(), {}, kHydraulic);
  ASSERT_EQ(lift.setup_error(), "") << lift.log();
  ASSERT_TRUE(lift.call({{"cmd", "travel"}, {"floor", 2}}).value("ok", false));
  constexpr int kClients = 30;
  constexpr int kEach = 32;
  const auto replies = flood(lift.socket(), kClients, kEach, [](int c, int k) {
    const bool add = ((c + k) % 2) == 0;
    return json{{"cmd", "calls"}, {"action", add ? "add" : "cancel"}, {"floor", 1 + (c + k) % 2}};
  });
  const auto seen = outcomes(replies, kEach);
  EXPECT_GT(seen.count("ok") ? seen.at("ok") : 0, 0);
  for (const auto& [code, n] : seen) {
    EXPECT_TRUE(code == "ok" || code == "busy" || code == "bad_request") << code << " x" << n;
  }
  // After the flood, what the API answers is what the lift does.
  const json add = lift.call({{"cmd", "calls"}, {"action", "add"}, {"floor", 1}});
  const json list = lift.call({{"cmd", "calls"}, {"action", "list"}});
  ASSERT_TRUE(add.value("ok", false)) << add.dump();
  const json calls = list["result"]["calls"];
  EXPECT_NE(std::find(calls.begin(), calls.end(), 1), calls.end()) << list.dump();
  const json stats = lift.call({{"cmd", "stats"}})["result"];
  EXPECT_EQ(stats["cycle"]["dropped_events"], 0) << stats.dump();
}

TEST(UssAttack, ParameterFloodsDuringATravelAreAnsweredTruthfully) {
  Lift lift("uss-flood", 4, json::object(), {}, kUss);
  ASSERT_EQ(lift.setup_error(), "") << lift.log();
  ASSERT_TRUE(lift.call({{"cmd", "travel"}, {"floor", 2}}).value("ok", false));
  constexpr int kClients = 30;
  constexpr int kEach = 32;
  // Every client writes values of its own to element 2 of P4 (a double word), and reads.
  const auto value_of = [](int c, int k) { return 100000 + c * 1000 + k; };
  const auto replies = flood(lift.socket(), kClients, kEach, [&](int c, int k) {
    if (k % 4 == 3) return json{{"cmd", "uss_read"}, {"pnu", 52}};
    return json{{"cmd", "uss_write"},      {"pnu", 4},        {"target", "array"}, {"index", 2},
                {"value", value_of(c, k)}, {"width", "dword"}};
  });
  const auto seen = outcomes(replies, kEach);
  EXPECT_GT(seen.count("ok") ? seen.at("ok") : 0, 0);
  std::set<int> written;  // values of the writes answered ok
  std::set<int> refused;  // values of the writes answered with an error
  for (int c = 0; c < kClients; ++c) {
    for (const json& r : replies[static_cast<std::size_t>(c)]) {
      const int k = r["id"].get<int>();
      if (k % 4 == 3) continue;
      (r.value("ok", false) ? written : refused).insert(value_of(c, k));
    }
  }
  const json back =
      lift.api().call({{"cmd", "uss_read"}, {"pnu", 4}, {"target", "array"}, {"index", 2}}, 30s);
  ASSERT_TRUE(back.value("ok", false)) << back.dump();
  const int value = back["result"]["value"].get<int>();
  EXPECT_TRUE(written.count(value) == 1)
      << value << " was never answered ok" << (refused.count(value) ? " (it was refused)" : "");
  const json stats = lift.call({{"cmd", "stats"}})["result"];
  EXPECT_EQ(stats["cycle"]["dropped_events"], 0) << stats.dump();
}

}  // namespace
}  // namespace liftd::e2e
