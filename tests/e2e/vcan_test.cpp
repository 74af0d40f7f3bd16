// liftd on a real SocketCAN bus (a vcan interface, LIFTD_TEST_CAN): the hydraulic lift as a
// `liftd` process with can.interface on the vcan against `sch001-sim --interface` as a process
// of its own, and a DCP lift whose car position comes from a CAN absolute encoder on the vcan.
// `candump` records the bus during each test, and the test judges what candump saw, not what
// liftd says about itself: card document 3d/3e (no travel bit in any answer to a status with ERR
// or without RDY), one answer per status frame (nothing unasked), and prints the answer latency
// (judged only by that rule: timing inside user-mode Linux is coarse).
//
// Needs AF_CAN, which the project's build machines lack: tools/uml/can-stage.sh runs this test
// inside user-mode Linux with vcan0 (label "vcan"; the host's ctest run leaves the label out).
// The test plays the machine around the lift: the I/O board (safety chain and doors through the
// `inputs` command) and the shaft encoder (frames on the vcan from the simulated car's position:
// the card simulator's `status` line, or the in-process DCP drive's car).
#include <gtest/gtest.h>
#include <linux/can.h>

#include <algorithm>
#include <atomic>
#include <csignal>
#include <cstdio>
#include <map>
#include <mutex>
#include <regex>
#include <sstream>

#include "can/socket.hpp"
#include "e2e/harness.hpp"
#include "io/pty.hpp"
#include "vcan_harness.hpp"

namespace liftd::e2e {
namespace {

// ---- candump: the bus as a third party saw it ----

bool is_status(const BusFrame& f) {
  return f.id == kFromCard && f.data.size() == 2 && f.data[0] == 0x61;
}
bool is_answer(const BusFrame& f) {
  return f.id == kToCard;
}

/// What the card's status frames got back, judged from the bus.
struct Verdict {
  int statuses = 0;           // status frames of the card
  int answered = 0;           // statuses with exactly one answer
  int unanswered = 0;         // statuses with none (before the next status)
  int extra_answers = 0;      // answers beyond the first to one status (or before any status)
  int travel_bit_breaks = 0;  // 3d/3e: a travel bit answering ERR = 1 or RDY = 0
  int refused_statuses = 0;   // statuses with ERR = 1 or RDY = 0
  std::vector<std::int64_t> latency_us;
  std::vector<std::string> breaks;  // the frames that broke 3d/3e, for the message

  std::string summary() const {
    std::vector<std::int64_t> l = latency_us;
    std::sort(l.begin(), l.end());
    std::ostringstream o;
    o << statuses << " status frames: " << answered << " answered once, " << unanswered
      << " unanswered, " << extra_answers << " extra answers; " << refused_statuses
      << " with ERR or without RDY, " << travel_bit_breaks << " answered with a travel bit";
    if (!l.empty()) {
      o << "; answer latency p50 " << static_cast<double>(l[l.size() / 2]) / 1000.0 << " ms, max "
        << static_cast<double>(l.back()) / 1000.0 << " ms";
    }
    return o.str();
  }
};

/// Judges the frames between `from_us` and `to_us` (bus time): every status frame gets exactly
/// one answer before the next status frame (`allow_unanswered` statuses may get none: the ones
/// a down interface or a reopening controller could not answer), and no answer to a status
/// with ERR or without RDY carries a travel bit (card document 3c-3e: SP3 SP2 SP1 SFY MSP HSP
/// DW UP, all 0).
Verdict judge(const std::vector<BusFrame>& frames, std::int64_t from_us = 0,
              std::int64_t to_us = INT64_MAX) {
  Verdict v;
  const BusFrame* status = nullptr;
  int answers = 0;
  const auto close_status = [&] {
    if (status == nullptr) return;
    if (answers == 0) ++v.unanswered;
    if (answers == 1) ++v.answered;
    if (answers > 1) v.extra_answers += answers - 1;
  };
  for (const BusFrame& f : frames) {
    if (f.t_us < from_us) continue;
    // After the window only the answers to its last status count: the next status ends it.
    if (f.t_us > to_us && is_status(f)) break;
    if (f.t_us > to_us && !is_answer(f)) continue;
    if (is_status(f)) {
      close_status();
      status = &f;
      answers = 0;
      ++v.statuses;
      const bool err = (f.data[1] & 0x80) != 0;
      const bool rdy = (f.data[1] & 0x02) != 0;
      if (err || !rdy) ++v.refused_statuses;
    } else if (is_answer(f)) {
      if (status == nullptr) continue;  // before the first status in the window: not judged
      ++answers;
      if (answers == 1) v.latency_us.push_back(f.t_us - status->t_us);
      const bool err = (status->data[1] & 0x80) != 0;
      const bool rdy = (status->data[1] & 0x02) != 0;
      const bool travel = f.data.size() >= 2 && f.data[0] == 0x68 && f.data[1] != 0;
      if ((err || !rdy) && travel) {
        ++v.travel_bit_breaks;
        char text[96];
        std::snprintf(text, sizeof text, "status 61 %02X answered with 68 %02X", status->data[1],
                      f.data[1]);
        v.breaks.emplace_back(text);
      }
    }
  }
  close_status();
  return v;
}

/// The encoder's frames as candump saw them: how many, the longest gap and the largest step
/// between two of them (for the message when liftd reports the position lost).
std::string encoder_on_bus(const std::vector<BusFrame>& frames) {
  std::int64_t last_t = -1, max_gap = 0, count = 0;
  long last_v = 0, max_step = 0;
  for (const BusFrame& f : frames) {
    if (f.id != kEncoderId || f.data.size() < 4) continue;
    const long v = static_cast<long>(f.data[0] | (f.data[1] << 8) | (f.data[2] << 16) |
                                     (static_cast<std::uint32_t>(f.data[3]) << 24));
    if (last_t >= 0) {
      max_gap = std::max(max_gap, f.t_us - last_t);
      max_step = std::max(max_step, std::abs(v - last_v));
    }
    last_t = f.t_us;
    last_v = v;
    ++count;
  }
  return "encoder on the bus: " + std::to_string(count) + " frames, longest gap " +
         std::to_string(max_gap / 1000) + " ms, largest step " + std::to_string(max_step) + " mm";
}

// ---- the hydraulic lift on the vcan ----

const json kFloors = json::array({{{"name", "0"}, {"level_mm", 0}},
                                  {{"name", "1"}, {"level_mm", 1200}},
                                  {{"name", "2"}, {"level_mm", 2400}}});

class HydraulicOnVcan : public ::testing::Test {
 protected:
  void SetUp() override {
    REQUIRE_CAN_INTERFACE();
    std::signal(SIGPIPE, SIG_IGN);
    const std::string name = ::testing::UnitTest::GetInstance()->current_test_info()->name();
    dir_ = test_dir(name);
    candump_ = std::make_unique<Candump>(dir_);
    ASSERT_TRUE(candump_->ready()) << "candump did not start recording";
    card_ = std::make_unique<liftd::testing::Process>(
        std::vector<std::string>{SCH001_SIM_BINARY, "--interface", can_interface()}, daemon_env(),
        dir_.string(), "sch001-sim", -1, /*stdin_pipe=*/true);
    json config = {
        {"drive", {{"kind", "sch001"}}},
        {"floors", kFloors},
        {"sch001", {{"star_delta_ms", 500}, {"slowdown_up_mm", 300}, {"slowdown_down_mm", 350}}},
        {"can", {{"interface", can_interface()}}},
        {"position", encoder_config()},
        {"inputs", {{"timeout_ms", 2000}}},
        {"log", {{"level", "info"}}},
        {"rt", {{"require_realtime", false}, {"lock_memory", false}}},
        {"api", api_section((dir_ / "api.sock").string())}};
    daemon_ = std::make_unique<Daemon>(dir_, config);
    machine_ = std::make_unique<Machine>(daemon_->socket(), [this] { return card_position(); });
    ASSERT_TRUE(daemon_->wait_up([](const json& s) { return s["car"]["floor"] == 0; }))
        << daemon_->log() << card_->out();
    ASSERT_TRUE(daemon_->wait_machine()) << daemon_->status().dump() << daemon_->log();
    ASSERT_TRUE(daemon_->wait_no_faults()) << daemon_->status().dump() << daemon_->log();
    start_us_ = bus_now_us();
    // The card may have sent a status frame before liftd listened (it counts that one as
    // unanswered): the test judges what happens from here.
    (void)card_position();
    violations_at_start_ = card_violations();
  }
  void TearDown() override {
    if (HasFailure() && candump_) {  // what the bus showed, whatever failed
      const auto frames = candump_->frames();
      std::printf("bus at the failure: %s; %s\n",
                  judge(frames, start_us_, candump_->cut_us()).summary().c_str(),
                  encoder_on_bus(frames).c_str());
    }
    machine_.reset();
    daemon_.reset();
    if (card_) {
      card_->write_stdin("quit\n");
      (void)card_->wait(5s);
    }
    std::error_code ignored;
    if (!HasFailure()) std::filesystem::remove_all(dir_, ignored);
  }

  /// The card simulator's car position: asks for its status line and reads the newest one
  /// that came (its stdout read on from where the last call stopped).
  std::optional<double> card_position() {
    std::lock_guard lock(card_mutex_);
    if (!card_->write_stdin("status\n")) return std::nullopt;
    if (!card_out_.is_open()) card_out_.open(dir_ / "sch001-sim.out");
    card_out_.clear();
    std::string line;
    while (std::getline(card_out_, line)) {
      if (card_out_.eof()) {  // a line still being written: read it again next time
        card_out_.clear();
        card_out_.seekg(-static_cast<std::streamoff>(line.size()), std::ios::cur);
        break;
      }
      if (line.rfind("car ", 0) == 0) {
        try {
          card_mm_ = std::stod(line.substr(4));
        } catch (...) {
        }
      }
    }
    return card_mm_;
  }
  void card_command(const std::string& line) {
    std::lock_guard lock(card_mutex_);
    ASSERT_TRUE(card_->write_stdin(line + "\n"));
  }
  /// The simulator's violation count from its newest status line.
  int card_violations() {
    const std::string out = card_->out();
    const auto at = out.rfind(" violations");
    if (at == std::string::npos) return -1;
    const auto start = out.rfind(' ', at - 1);
    return std::stoi(out.substr(start + 1, at - start - 1));
  }

  /// Requests a travel, waiting while liftd says not_ready (the machine inputs and the
  /// encoder's first frames reach it from this test's threads, after start or a fault) or busy
  /// (a relevelling it started by itself): the reply it finally gave.
  json request_travel(int floor) {
    json r;
    const auto end = Clock::now() + 15s;
    do {
      r = daemon_->call({{"cmd", "travel"}, {"floor", floor}});
      // not_ready: inputs or position not there yet; busy: liftd relevels the car after a
      // landing (its decision when the encoder's frames came late under the flood).
      if (r.value("ok", false) ||
          (r["error"]["code"] != "not_ready" && r["error"]["code"] != "busy")) {
        break;
      }
      daemon_->api().drain(100ms);
    } while (Clock::now() < end);
    return r;
  }
  void travel_to(int floor) {
    const json r = request_travel(floor);
    ASSERT_TRUE(r.value("ok", false)) << r.dump() << daemon_->log();
    const json end = daemon_->wait_travel_end(60s, "hydraulic");
    ASSERT_TRUE(end.is_object()) << "no end of travel to " << floor << "\n" << daemon_->log();
    ASSERT_EQ(end["data"]["event"], "finished") << end.dump() << "\n"
                                                << machine_->feed() << "\n"
                                                << daemon_->log();
    const json s = daemon_->status();
    EXPECT_EQ(s["car"]["floor"], floor) << s.dump();
    // The position reaches liftd through this test's encoder thread (10 ms steps, coarse in
    // user-mode Linux): landing precision is measured by tests/e2e/hydraulic_test.cpp.
    EXPECT_NEAR(s["car"]["position_mm"].get<double>(), 1200.0 * floor, 30.0);
  }
  void start_long_travel() {
    const json r = request_travel(2);
    ASSERT_TRUE(r.value("ok", false)) << r.dump() << daemon_->log();
    const auto end = Clock::now() + 30s;
    while (Clock::now() < end && machine_->last_mm() < 300) daemon_->api().drain(30ms);
    ASSERT_GE(machine_->last_mm(), 300) << daemon_->log();
  }
  /// The travel ended with `cause`, reported once.
  void expect_aborted(const std::string& cause, std::chrono::seconds limit = 20s) {
    const json end = daemon_->wait_travel_end(limit);
    ASSERT_TRUE(end.is_object()) << daemon_->log();
    EXPECT_EQ(end["data"]["event"], "aborted") << end.dump();
    EXPECT_EQ(end["data"]["cause"], cause) << end.dump() << "\n"
                                           << machine_->feed() << "\n"
                                           << daemon_->log();
    daemon_->api().drain(500ms);
    EXPECT_EQ(
        daemon_->count_events("travel", [](const json& d) { return d["event"] == "aborted"; }), 1);
  }
  /// Judges the bus since SetUp (or since `since_us`: after the test's own frames on liftd's
  /// identifier, which would count as answers); `max_unanswered` statuses may go unanswered.
  /// Judges the bus as candump recorded it. A status frame may look unanswered for two reasons
  /// that are not liftd's: candump's own queue overflowed (it lost the answer; `-d` counts
  /// those frames, and that many statuses are allowed to look unanswered), or the status never
  /// reached liftd because liftd's queue overflowed, which is liftd's failure and reported as
  /// such (stats `sch001.overflowed_frames`, the kernel's count).
  Verdict judge_bus(int max_unanswered = 0, std::int64_t since_us = 0) {
    const json stats = daemon_->call({{"cmd", "stats"}})["result"];
    const auto frames = candump_->frames();
    const Verdict v = judge(frames, since_us != 0 ? since_us : start_us_, candump_->cut_us());
    const int recording_lost = candump_->dropped();
    std::printf("bus: %s; %s; candump lost %d frames\n", v.summary().c_str(),
                encoder_on_bus(frames).c_str(), recording_lost);
    EXPECT_GT(v.statuses, 0) << candump_->log();
    EXPECT_EQ(v.travel_bit_breaks, 0)
        << "card document 3d/3e broken on the bus: " << (v.breaks.empty() ? "" : v.breaks.front())
        << "\n"
        << v.summary();
    EXPECT_EQ(v.extra_answers, 0) << "one answer per status frame: " << v.summary();
    EXPECT_EQ(stats["sch001"]["overflowed_frames"], 0)
        << "liftd read the bus too slowly: the kernel dropped frames on its full queue; "
        << stats.dump();
    EXPECT_LE(v.unanswered, max_unanswered + recording_lost)
        << v.summary() << "; candump lost " << recording_lost
        << " frames; liftd: " << stats["sch001"].dump();
    return v;
  }

  std::filesystem::path dir_;
  std::unique_ptr<Candump> candump_;
  std::unique_ptr<liftd::testing::Process> card_;
  std::mutex card_mutex_;
  std::ifstream card_out_;
  std::optional<double> card_mm_;
  std::unique_ptr<Daemon> daemon_;
  std::unique_ptr<Machine> machine_;
  std::int64_t start_us_ = 0;
  int violations_at_start_ = 0;
};

TEST_F(HydraulicOnVcan, EveryFloorToEveryFloorUpAndDown) {
  for (int floor : {1, 2, 0, 2, 1, 0}) {
    travel_to(floor);
    if (HasFatalFailure()) return;
  }
  EXPECT_EQ(daemon_->status()["drive"]["state"], "ready");
  const Verdict v = judge_bus();
  EXPECT_EQ(v.refused_statuses, 0);
  (void)card_position();
  EXPECT_EQ(card_violations(), violations_at_start_) << card_->out();
}

TEST_F(HydraulicOnVcan, RdyDroppingMidTravelEndsIt) {
  start_long_travel();
  if (HasFatalFailure()) return;
  card_command("rdy off");
  expect_aborted("drive_not_ready");
  daemon_->api().drain(1s);  // several more status frames without RDY
  const Verdict v = judge_bus();
  EXPECT_GE(v.refused_statuses, 5) << "the card's frames without RDY are on the bus";
}

TEST_F(HydraulicOnVcan, ErrMidTravelEndsItAndIsAFault) {
  start_long_travel();
  if (HasFatalFailure()) return;
  card_command("err on");
  expect_aborted("drive_fault");
  EXPECT_EQ(daemon_->call({{"cmd", "travel"}, {"floor", 0}})["error"]["code"], "fault");
  daemon_->api().drain(1s);
  const Verdict v = judge_bus();
  EXPECT_GE(v.refused_statuses, 5);
}

TEST_F(HydraulicOnVcan, CardSilenceMidTravelEndsItAndTheLinkRecovers) {
  start_long_travel();
  if (HasFatalFailure()) return;
  card_command("silence on");
  expect_aborted("card_silent", 20s);
  EXPECT_EQ(daemon_->status()["link"]["state"], "fault");
  card_command("silence off");
  EXPECT_TRUE(daemon_->wait_up([](const json&) { return true; }, 10s)) << daemon_->log();
  // Nothing unasked while the card was silent: judged as "one answer per status frame".
  judge_bus();
}

// The interface goes down mid-travel and comes back. Expected: the travel ends (the link is
// lost), liftd reopens the interface, refuses travel until the card's first status frame, and
// a travel runs again; the card simulator survives it; the bus shows no rule broken. The whole
// episode is one link_fault (liftd backs off while the interface is down, and the fault ends
// only once the card is heard again).
TEST_F(HydraulicOnVcan, InterfaceDownAndUpMidTravel) {
  start_long_travel();
  if (HasFatalFailure()) return;
  const std::string name = can_interface();
  ASSERT_EQ(std::system(("ip link set " + name + " down").c_str()), 0);
  const json end = daemon_->wait_travel_end(20s);
  ASSERT_EQ(std::system(("ip link set " + name + " up").c_str()), 0);
  ASSERT_TRUE(end.is_object()) << "the travel did not end with the interface down\n"
                               << daemon_->log();
  EXPECT_EQ(end["data"]["event"], "aborted") << end.dump();
  ASSERT_TRUE(daemon_->wait_up([](const json& s) { return s["drive"]["state"] == "ready"; }, 30s))
      << "no link after the interface came back\n"
      << daemon_->log() << "\ncard:\n"
      << card_->out();
  EXPECT_EQ(
      daemon_->count_events(
          "fault", [](const json& d) { return d["code"] == "link_fault" && d["active"] == true; }),
      1)
      << daemon_->log();
  travel_to(0);
  // The statuses around the interface going down may have gone unanswered; none may be
  // answered twice or with a forbidden travel bit.
  judge_bus(5);
}

// Traffic of other nodes at full rate (cangen, one frame per ms) on other identifiers and on the
// card's own identifier (frames that are no status: first byte not 0x61) while the car travels.
TEST_F(HydraulicOnVcan, FloodOnOtherIdentifiersAndOnTheCardsIdentifier) {
  const std::string name = can_interface();
  {
    liftd::testing::Process low({"/usr/bin/cangen", name, "-g", "1", "-I", "100", "-L", "8"},
                                daemon_env(), dir_.string(), "cangen-low");
    liftd::testing::Process high({"/usr/bin/cangen", name, "-g", "1", "-I", "7FF", "-L", "8"},
                                 daemon_env(), dir_.string(), "cangen-high");
    travel_to(2);
    if (HasFatalFailure()) return;
    low.signal(SIGTERM);
    high.signal(SIGTERM);
    (void)low.wait(5s);
    (void)high.wait(5s);
  }
  liftd::testing::Process card_id(
      {"/usr/bin/cangen", name, "-g", "1", "-I", "581", "-L", "2", "-D", "0000"}, daemon_env(),
      dir_.string(), "cangen-card-id");
  const json r = request_travel(0);
  ASSERT_TRUE(r.value("ok", false)) << r.dump();
  const json end = daemon_->wait_travel_end(60s, "hydraulic");
  card_id.signal(SIGTERM);
  (void)card_id.wait(5s);
  ASSERT_TRUE(end.is_object()) << daemon_->log();
  EXPECT_EQ(end["data"]["event"], "finished")
      << "frames on the card's identifier that are no status frame: " << end.dump() << "\n"
      << daemon_->log();
  judge_bus();
  // The card, the other observer of the bus, got an answer to each of its status frames.
  EXPECT_EQ(card_violations(), violations_at_start_) << card_->out();
}

// Another node sends on liftd's own identifier (0x551, the card's command identifier; card
// document 1.6 reserves it): liftd reports it, withdraws its travel commands (a link fault, the
// travel refused) and goes on 10 s after the last such frame.
TEST_F(HydraulicOnVcan, AnotherNodeOnLiftdsIdentifierIsALinkFault) {
  const std::string name = can_interface();
  {
    liftd::testing::Process foreign(
        {"/usr/bin/cangen", name, "-g", "20", "-I", "551", "-L", "4", "-D", "68010003"},
        daemon_env(), dir_.string(), "cangen-own-id");
    json s;
    for (int i = 0; i < 50; ++i) {
      s = daemon_->status();
      if (s["sch001"]["foreign_sender"] == true) break;
      daemon_->api().drain(100ms);
    }
    EXPECT_EQ(s["sch001"]["foreign_sender"], true) << s.dump();
    EXPECT_TRUE(std::any_of(s["faults"].begin(), s["faults"].end(), [](const json& f) {
      return f["code"] == "link_fault";
    })) << s.dump();
    const json r = daemon_->call({{"cmd", "travel"}, {"floor", 2}});
    EXPECT_FALSE(r.value("ok", true)) << r.dump();
    foreign.signal(SIGTERM);
    (void)foreign.wait(5s);
  }
  const std::int64_t quiet_since = bus_now_us();
  EXPECT_NE(daemon_->log().find("another node sends on liftd's CAN identifier"), std::string::npos)
      << daemon_->log();
  ASSERT_TRUE(daemon_->wait_up([](const json& s) { return s["drive"]["state"] == "ready"; }, 30s))
      << daemon_->log();
  travel_to(2);
  judge_bus(0, quiet_since);
}

}  // namespace
}  // namespace liftd::e2e
