// End to end: `liftd --simulate` as a process (real pty, real cycle thread, real API socket),
// driven through the JSON API and the liftctl binary the way a dispatcher and a technician would.
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <chrono>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>

#include "daemon/process.hpp"
#include "support/api_client.hpp"

namespace {

using namespace std::chrono_literals;
using liftd::testing::ApiClient;
using liftd::testing::Process;
using nlohmann::json;

/// Starts `liftd --simulate` with its runtime directory (and so its API socket) in `dir`.
std::unique_ptr<Process> start_simulated_liftd(const std::filesystem::path& dir) {
  std::filesystem::create_directories(dir);
  return std::make_unique<Process>(
      std::vector<std::string>{LIFTD_BINARY, "--simulate"},
      std::vector<std::string>{"XDG_RUNTIME_DIR=" + dir.string(), "PATH=/usr/bin:/bin"},
      dir.string(), "liftd");
}

/// True once the daemon on `socket` reports the DCP link up (I0, I1 and I3 went through: well
/// under a second on a quiet machine), false after 30 s.
bool wait_for_link_up(const std::string& socket) {
  for (int i = 0; i < 300; ++i) {
    ApiClient c(socket);
    if (c.connected()) {
      c.next();  // hello
      json r = c.call({{"cmd", "status"}});
      if (r.is_object() && r["result"]["link"]["state"] == "up") return true;
    }
    std::this_thread::sleep_for(100ms);
  }
  return false;
}

class SimulateTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = std::filesystem::temp_directory_path() / ("liftd-e2e-" + std::to_string(::getpid()));
    socket_ = (dir_ / "liftd-sim.sock").string();
    daemon_ = start_simulated_liftd(dir_);
    link_up_ = wait_for_link_up(socket_);
  }
  static void TearDownTestSuite() {
    daemon_.reset();
    std::filesystem::remove_all(dir_);
  }
  // Every test here needs the link: without it they would test a daemon that cannot travel.
  void SetUp() override {
    ASSERT_TRUE(link_up_) << "the simulated drive's link never came up in 30 s; daemon log:\n"
                          << daemon_->err();
  }
  /// Runs liftctl with arguments; returns stdout (exit code in `code`).
  static std::string liftctl(const std::vector<std::string>& args, int* code = nullptr) {
    std::vector<std::string> argv = {LIFTCTL_BINARY, "--socket", socket_};
    argv.insert(argv.end(), args.begin(), args.end());
    Process p(argv, {"PATH=/usr/bin:/bin"}, dir_.string(), "liftctl");
    const auto rc = p.wait(10s);
    if (code != nullptr) *code = rc.value_or(-1);
    return p.out() + p.err();
  }

  static inline std::filesystem::path dir_;
  static inline std::string socket_;
  static inline std::unique_ptr<Process> daemon_;
  static inline bool link_up_ = false;
};

TEST_F(SimulateTest, LinkComesUpAndLiftctlShowsIt) {
  ApiClient c(socket_);
  ASSERT_TRUE(c.connected()) << daemon_->err();
  const json hello = c.next();
  ASSERT_EQ(hello.value("event", ""), "hello");
  const json status = c.call({{"cmd", "status"}});
  ASSERT_TRUE(status["ok"].get<bool>()) << status.dump();
  EXPECT_EQ(status["result"]["link"]["state"], "up") << daemon_->err();
  EXPECT_EQ(status["result"]["drive"]["kind"], "dcp");
  EXPECT_EQ(status["result"]["drive"]["state"], "ready") << status.dump();
  EXPECT_EQ(status["result"]["dcp"]["mode"], "DCP4");
  EXPECT_FALSE(status["result"]["drive"].contains("mode")) << "under dcp only (API 3)";
  EXPECT_EQ(status["result"]["car"]["floor"], 0);
  EXPECT_TRUE(status["result"]["faults"].empty()) << status.dump();
  int code = -1;
  const std::string text = liftctl({"status"}, &code);
  EXPECT_EQ(code, 0) << text;
  EXPECT_NE(text.find("up"), std::string::npos) << text;
  EXPECT_NE(text.find("DCP4"), std::string::npos) << text;
}

TEST_F(SimulateTest, WatchSeesTheDrivesDisplayAfterAKeypress) {
  ApiClient watcher(socket_);
  watcher.next();
  ASSERT_TRUE(watcher.call({{"cmd", "watch"}, {"enable", true}})["ok"].get<bool>());
  ApiClient control(socket_);
  control.next();
  const json key = control.call({{"cmd", "key"}, {"key", 1}});
  ASSERT_TRUE(key["ok"].get<bool>()) << key.dump();
  const json display = watcher.wait_event(
      "display",
      [](const json& d) {
        for (const auto& line : d["lines"]) {
          if (line.get<std::string>().find_first_not_of(' ') != std::string::npos) return true;
        }
        return false;
      },
      10s);
  ASSERT_FALSE(display.is_null()) << "no display text after a keypress";
  const std::string text = liftctl({"display"});
  EXPECT_NE(text.find_first_not_of(" |+-\n"), std::string::npos) << text;
}

TEST_F(SimulateTest, TravelThroughTheApiLandsOnTheFloorAndEndsWithDriveEnableOff) {
  ApiClient watcher(socket_);
  watcher.next();
  ASSERT_TRUE(watcher.call({{"cmd", "watch"}, {"enable", true}})["ok"].get<bool>());
  ApiClient control(socket_);
  control.next();
  const json r = control.call({{"cmd", "travel"}, {"floor", 2}});
  ASSERT_TRUE(r["ok"].get<bool>()) << r.dump();
  const json finished = watcher.wait_event(
      "travel", [](const json& d) { return d["event"] == "finished"; }, 60s);
  ASSERT_FALSE(finished.is_null()) << daemon_->err();
  EXPECT_NEAR(finished["data"]["position_mm"].get<double>(), 6000.0, 2.0);
  std::this_thread::sleep_for(300ms);
  const json status = control.call({{"cmd", "status"}});
  EXPECT_EQ(status["result"]["car"]["floor"], 2);
  EXPECT_EQ(status["result"]["travel"]["state"], "idle");
  // The newest frames on the wire: drive enable (B0) off while stationary (DCP 9.1.1).
  const json trace = control.call({{"cmd", "trace"}, {"count", 3}});
  ASSERT_TRUE(trace["ok"].get<bool>()) << trace.dump();
  for (const auto& e : trace["result"]["frames"]) {
    const std::string tx = e["tx"];
    const int command = std::stoi(tx.substr(0, 2), nullptr, 16);
    EXPECT_EQ(command & 0x01, 0) << tx;
  }
}

TEST_F(SimulateTest, CallsAreServedInOrder) {
  ApiClient watcher(socket_);
  watcher.next();
  ASSERT_TRUE(watcher.call({{"cmd", "watch"}, {"enable", true}})["ok"].get<bool>());
  ApiClient control(socket_);
  control.next();
  ASSERT_TRUE(control.call({{"cmd", "calls"}, {"action", "add"}, {"floor", 4}})["ok"].get<bool>());
  ASSERT_TRUE(control.call({{"cmd", "calls"}, {"action", "add"}, {"floor", 1}})["ok"].get<bool>());
  const json first = watcher.wait_event(
      "call_served", [](const json&) { return true; }, 60s);
  ASSERT_FALSE(first.is_null()) << daemon_->err();
  EXPECT_EQ(first["data"]["floor"], 4);
  const json second = watcher.wait_event(
      "call_served", [](const json&) { return true; }, 60s);
  ASSERT_FALSE(second.is_null()) << daemon_->err();
  EXPECT_EQ(second["data"]["floor"], 1);
}

TEST_F(SimulateTest, TraceSaveWritesTheDecodedFlightRecorder) {
  ApiClient control(socket_);
  control.next();
  const json r = control.call({{"cmd", "trace"}, {"count", 1}, {"save", true}});
  ASSERT_TRUE(r["ok"].get<bool>()) << r.dump();
  const std::string path = r["result"]["file"];
  EXPECT_EQ(std::filesystem::path(path).parent_path(), dir_);
  EXPECT_GT(r["result"]["records"].get<int>(), 10);
  std::ifstream in(path);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  // Every reply of a running link is decoded: the drive's ready bit by name.
  EXPECT_NE(text.find("S0:ready"), std::string::npos) << text.substr(0, 2000);
}

TEST_F(SimulateTest, RefusesATravelToAFloorThatDoesNotExist) {
  ApiClient control(socket_);
  control.next();
  const json r = control.call({{"cmd", "travel"}, {"floor", 99}});
  EXPECT_FALSE(r["ok"].get<bool>());
  EXPECT_EQ(r["error"]["code"], "bad_request");
  EXPECT_NE(r["error"]["message"].get<std::string>().find("floor"), std::string::npos);
}

// Last: SIGTERM stops the whole stack cleanly with exit code 0.
TEST(SimulateProcess, SigtermAtRestStopsCleanly) {
  // Its own daemon, so the other tests keep theirs whatever order they run in.
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("liftd-e2e-sigterm-" + std::to_string(::getpid()));
  std::unique_ptr<Process> daemon = start_simulated_liftd(dir);
  ASSERT_TRUE(wait_for_link_up((dir / "liftd-sim.sock").string())) << daemon->err();
  daemon->signal(SIGTERM);
  const auto code = daemon->wait(5s);
  ASSERT_TRUE(code.has_value()) << "the car stands: liftd exits at once";
  EXPECT_EQ(*code, 0) << daemon->err();
  daemon.reset();
  std::filesystem::remove_all(dir);
}

}  // namespace
