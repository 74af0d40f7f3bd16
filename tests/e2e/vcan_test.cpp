// Over 800 lines: the harness (candump, verdict, machine, daemon) and the cases of one vcan stage.
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
#include "dcp/sim/serial_runner.hpp"
#include "e2e/harness.hpp"
#include "io/pty.hpp"

namespace liftd::e2e {
namespace {

constexpr std::uint32_t kToCard = 0x551;     // controller -> card (card document 6, P479 = 0)
constexpr std::uint32_t kFromCard = 0x581;   // card -> controller
constexpr std::uint32_t kEncoderId = 0x190;  // position.can_id 400
constexpr int kEncoderOffsetMm = -10000;     // count 0 = -10 m: counts stay positive

std::string can_interface() {
  const char* name = std::getenv("LIFTD_TEST_CAN");
  return name == nullptr ? std::string() : std::string(name);
}

#define REQUIRE_CAN_INTERFACE()                                                            \
  if (can_interface().empty()) {                                                           \
    GTEST_SKIP() << "LIFTD_TEST_CAN is not set: run by tools/uml/can-stage.sh (user-mode " \
                    "Linux with vcan0)";                                                   \
  }                                                                                        \
  ASSERT_TRUE(can::kernel_has_can()) << "LIFTD_TEST_CAN is set but this kernel has no AF_CAN"

std::filesystem::path test_dir(const std::string& leaf) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("liftd-vcan-" + std::to_string(::getpid()) + "-" + leaf);
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

json api_section(const std::string& socket) {
  return {{"socket", socket},
          {"socket_group", ""},
          {"read_group", ""},
          {"control_group", ""},
          {"inputs_group", ""}};
}

/// An encoder frame for position.can_* as configured below (4 bytes little endian, 1 mm/count).
can::Frame encoder_frame(double position_mm) {
  const auto count = static_cast<std::uint32_t>(std::llround(position_mm - kEncoderOffsetMm));
  return can::make_frame(kEncoderId,
                         std::vector<std::uint8_t>{static_cast<std::uint8_t>(count),
                                                   static_cast<std::uint8_t>(count >> 8),
                                                   static_cast<std::uint8_t>(count >> 16),
                                                   static_cast<std::uint8_t>(count >> 24)});
}

json encoder_config() {
  return {{"source", "can"},
          {"can_id", kEncoderId},
          {"can_offset_mm", kEncoderOffsetMm},
          // The encoder frames come from this test's thread inside user-mode Linux, whose
          // timing is coarse: a loaded host may hold them back for tens of ms.
          {"can_timeout_ms", 1000}};
}

// ---- candump: the bus as a third party saw it ----

struct BusFrame {
  std::int64_t t_us = 0;
  std::uint32_t id = 0;
  std::vector<std::uint8_t> data;
};

/// `candump -L` on the interface for the lifetime of the object; frames() stops it and parses
/// what it logged ("(1700000000.123456) vcan0 581#6102").
///
/// Our own marker frames (identifier 0x7EE) bound the recording: one at the start (recording
/// from then on), and at the end a cut (`cut_us()`, the end of the judged window) and, 200 ms
/// later, a last one. candump reads its socket in order, so once it logged the last marker it
/// has logged every frame before it, and the answer to a status frame sent just before the cut
/// is in the log: stopping it at once could lose that answer and judge its status unanswered.
class Candump {
 public:
  explicit Candump(const std::filesystem::path& dir) : dir_(dir) {
    process_ = std::make_unique<liftd::testing::Process>(
        std::vector<std::string>{"/usr/bin/stdbuf", "-oL", "/usr/bin/candump", "-L", "-d", "-r",
                                 "4194304", can_interface()},
        daemon_env(), dir.string(), "candump");
    ready_ = mark(kStartMarker);
  }
  /// True once candump records.
  bool ready() const { return ready_; }
  /// Stops candump (after the end markers) and returns every frame it saw (the markers left out).
  std::vector<BusFrame> frames() {
    if (process_) {
      if (mark(kCutMarker)) {
        std::this_thread::sleep_for(200ms);  // the answers to statuses before the cut
        (void)mark(kLastMarker);
      }
      process_->signal(SIGTERM);
      (void)process_->wait(5s);
      log_ = process_->out();
      process_.reset();
    }
    std::vector<BusFrame> out;
    std::istringstream in(log_);
    std::string line;
    static const std::regex kLine(R"(\((\d+)\.(\d{6})\) \S+ ([0-9A-F]+)#([0-9A-F]*))");
    while (std::getline(in, line)) {
      std::smatch m;
      if (!std::regex_search(line, m, kLine)) continue;
      BusFrame f;
      f.t_us = std::stoll(m[1]) * 1000000 + std::stoll(m[2]);
      f.id = static_cast<std::uint32_t>(std::stoul(m[3], nullptr, 16));
      const std::string hex = m[4];
      for (std::size_t i = 0; i + 1 < hex.size(); i += 2) {
        f.data.push_back(static_cast<std::uint8_t>(std::stoul(hex.substr(i, 2), nullptr, 16)));
      }
      if (f.id == kMarkerId) {
        if (f.data.size() == 1 && f.data[0] == kCutMarker && cut_us_ == INT64_MAX) cut_us_ = f.t_us;
        continue;
      }
      out.push_back(std::move(f));
    }
    return out;
  }
  /// The end of the judged window in bus time (after frames()): the cut marker, or no end when
  /// candump never logged it.
  std::int64_t cut_us() const { return cut_us_; }
  /// candump's whole log (after frames()), for failure messages.
  const std::string& log() const { return log_; }
  /// Frames the kernel dropped on candump's own full receive queue (after frames()): `-d`
  /// prints its socket's running total ("DROPCOUNT: ... (total drops N)"). The recording
  /// misses that many frames, and an answer it misses makes its status look unanswered.
  int dropped() const {
    static const std::regex kDrops(R"(DROPCOUNT: .*\(total drops (\d+)\))");
    int total = 0;
    for (std::sregex_iterator i(log_.begin(), log_.end(), kDrops), end; i != end; ++i) {
      total = std::max(total, std::stoi((*i)[1]));
    }
    return total;
  }

 private:
  static constexpr std::uint32_t kMarkerId = 0x7EE;
  static constexpr std::uint8_t kStartMarker = 0xCA;
  static constexpr std::uint8_t kCutMarker = 0xE1;
  static constexpr std::uint8_t kLastMarker = 0xE2;

  /// Sends marker `value` until candump has logged it (at most 5 s); false if it never did.
  bool mark(std::uint8_t value) {
    auto bus = can::CanSocket::open(can_interface(), {});
    if (!bus) return false;
    char text[16];
    std::snprintf(text, sizeof text, " 7EE#%02X", value);
    for (int i = 0; i < 100; ++i) {
      (void)bus.value().write(can::make_frame(kMarkerId, std::vector<std::uint8_t>{value}));
      for (int look = 0; look < 5; ++look) {
        std::this_thread::sleep_for(10ms);
        if (process_->out().find(text) != std::string::npos) return true;
      }
    }
    return false;
  }

  std::filesystem::path dir_;
  std::unique_ptr<liftd::testing::Process> process_;
  bool ready_ = false;
  std::string log_;
  std::int64_t cut_us_ = INT64_MAX;
};

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

/// Bus time (candump's wall-clock stamps) now, in microseconds.
std::int64_t bus_now_us() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

// ---- the machine around the lift: inputs and the encoder ----

/// Every 10 ms: asks `position()` where the car is and puts it on the bus as the encoder's
/// frame; every 100 ms: the safety chain closed, doors closed and locked (`inputs`).
class Machine {
 public:
  Machine(const std::string& api_socket, std::function<std::optional<double>()> position)
      : api_socket_(api_socket), position_(std::move(position)) {
    encoder_thread_ = std::thread([this] { encoder(); });
    inputs_thread_ = std::thread([this] { inputs(); });
  }
  ~Machine() {
    stop_ = true;
    encoder_thread_.join();
    inputs_thread_.join();
  }
  /// Stops or resumes the encoder's frames.
  void encoder_silent(bool silent) { silent_ = silent; }
  /// The newest position sent.
  double last_mm() const { return last_mm_.load(); }
  /// The longest time between two encoder frames sent (the guest's scheduling, for messages).
  std::string feed() const {
    return "encoder frames sent: " + std::to_string(sent_.load()) + ", longest gap " +
           std::to_string(max_gap_ms_.load()) + " ms, failed writes " +
           std::to_string(failed_.load());
  }

 private:
  void encoder() {
    auto bus = can::CanSocket::open(can_interface(), {});
    auto last = Clock::now();
    while (!stop_) {
      if (const auto mm = position_()) {
        last_mm_ = *mm;
        if (bus && !silent_) {
          if (bus.value().write(encoder_frame(*mm)) == 0) {
            const auto now = Clock::now();
            const auto gap = std::chrono::duration_cast<std::chrono::milliseconds>(now - last);
            if (sent_.fetch_add(1) > 0 && gap.count() > max_gap_ms_) max_gap_ms_ = gap.count();
            last = now;
          } else {
            ++failed_;
          }
        }
      }
      std::this_thread::sleep_for(10ms);
    }
  }
  void inputs() {
    std::unique_ptr<Client> api;
    while (!stop_) {
      if (!api || !api->connected()) api = std::make_unique<Client>(api_socket_);
      if (api->connected()) {
        (void)api->call({{"cmd", "inputs"},
                         {"safety_chain", true},
                         {"doors_closed", true},
                         {"doors_locked", true}},
                        1s);
      }
      std::this_thread::sleep_for(100ms);
    }
  }

  std::string api_socket_;
  std::function<std::optional<double>()> position_;
  std::atomic<bool> stop_{false};
  std::atomic<bool> silent_{false};
  std::atomic<double> last_mm_{0.0};
  std::atomic<std::uint64_t> sent_{0}, failed_{0};
  std::atomic<std::int64_t> max_gap_ms_{0};
  std::thread encoder_thread_;
  std::thread inputs_thread_;
};

/// `liftd --config FILE` (no --simulate) and a watching client.
class Daemon {
 public:
  Daemon(const std::filesystem::path& dir, const json& config)
      : socket_((dir / "api.sock").string()) {
    const std::string path = (dir / "liftd.json").string();
    std::ofstream(path) << config.dump(2);
    process_ = std::make_unique<liftd::testing::Process>(
        std::vector<std::string>{LIFTD_BINARY, "--config", path}, daemon_env(), dir.string(),
        "liftd");
  }
  ~Daemon() {
    client_.reset();
    process_->signal(SIGTERM);
    (void)process_->wait(10s);
  }
  const std::string& socket() const { return socket_; }
  /// Waits until status says the link is up and `check` holds; then watches events.
  bool wait_up(const std::function<bool(const json&)>& check, std::chrono::seconds limit = 30s) {
    const auto end = Clock::now() + limit;
    while (Clock::now() < end) {
      auto c = std::make_unique<Client>(socket_);
      if (c->connected()) {
        const json s = c->call({{"cmd", "status"}});
        if (s.is_object() && s["result"]["link"]["state"] == "up" && check(s["result"])) {
          if (!client_) {
            client_ = std::move(c);
            const json w = client_->call({{"cmd", "watch"}, {"enable", true}});
            if (!w.is_object() || !w.value("ok", false)) return false;
          }
          return true;
        }
      }
      std::this_thread::sleep_for(100ms);
    }
    return false;
  }
  /// Waits until liftd has the machine inputs from the test (safety chain closed) and a car
  /// position (the encoder's frames).
  bool wait_machine(std::chrono::seconds limit = 20s) {
    const auto end = Clock::now() + limit;
    while (Clock::now() < end) {
      const json inputs = call({{"cmd", "inputs"}});
      const json s = status();
      if (inputs.is_object() && inputs["result"].value("safety_chain", false) && s.is_object() &&
          s["car"]["position_mm"].is_number()) {
        return true;
      }
      client_->drain(100ms);
    }
    return false;
  }
  /// Waits until no fault is active, resetting the ones the start left (the machine inputs
  /// arrive only once the API listens, and a slow start may see them late: inputs_lost).
  bool wait_no_faults(std::chrono::seconds limit = 20s) {
    const auto end = Clock::now() + limit;
    while (Clock::now() < end) {
      const json s = status();
      if (s.is_object() && s["faults"].is_array() && s["faults"].empty()) return true;
      (void)call({{"cmd", "reset"}});
      client_->drain(300ms);
    }
    return false;
  }
  Client& api() { return *client_; }
  json call(const json& request) { return client_->call(request); }
  json status() { return client_->call({{"cmd", "status"}})["result"]; }
  /// The next end (finished or aborted) of a travel of `kind` (any kind when empty): a
  /// relevelling liftd started by itself ends on its own.
  json wait_travel_end(std::chrono::milliseconds timeout, const std::string& kind = "") {
    return client_->wait_event(
        "travel",
        [&](const json& d) {
          return (d["event"] == "finished" || d["event"] == "aborted") &&
                 (kind.empty() || d["kind"] == kind);
        },
        timeout);
  }

  int count_events(const std::string& name, const std::function<bool(const json&)>& match) {
    return static_cast<int>(
        std::count_if(client_->events().begin(), client_->events().end(),
                      [&](const json& e) { return e["event"] == name && match(e["data"]); }));
  }
  std::string log() const { return process_->err(); }

 private:
  std::string socket_;
  std::unique_ptr<liftd::testing::Process> process_;
  std::unique_ptr<Client> client_;
};

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

// ---- a DCP lift with the CAN encoder on the vcan ----

// liftd drives a simulated DCP drive over a pseudo-terminal (the drive in this process, on the
// pty's master) and takes the car position from an absolute encoder's frames on the vcan, which
// this test sends from the simulated car.
TEST(DcpOnVcanEncoder, TravelsOnThePositionFromTheBus) {
  REQUIRE_CAN_INTERFACE();
  std::signal(SIGPIPE, SIG_IGN);
  const auto dir = test_dir("dcp-encoder");
  Candump candump(dir);
  ASSERT_TRUE(candump.ready());
  auto created = io::PtyPair::create({}, /*hold_slave=*/false);
  ASSERT_TRUE(created.ok()) << created.error().message();
  io::PtyPair pty = std::move(created).value();
  const std::string slave = pty.slave_path();
  dcp::sim::RunnerOptions o;
  o.fd = pty.take_master().release();
  dcp::sim::DriveConfig drive_config;
  // The drive's DCP 7.3 supervision (10 missing frames, 150 ms) is tested on the host, where the
  // cycle runs on a real-time thread. Inside user-mode Linux the whole guest is one process of
  // the host, which a busy host holds back for 100 ms and more: the drive here allows a second
  // of silence, so that what this test judges is the position from the bus.
  drive_config.link_timeout_frames = 66;
  // As in liftd --simulate: the drive's thread one step below the master's cycle (rt.priority
  // 80), so that nothing else in the guest (candump, the encoder feed, ctest) delays a reply.
  o.priority = 79;
  dcp::sim::SerialDriveRunner drive(drive_config, o);
  ASSERT_TRUE(drive.start()) << drive.last_error();
  json config = {{"drive", {{"device", slave}}},
                 {"can", {{"interface", can_interface()}}},
                 {"position", encoder_config()},
                 {"inputs", {{"timeout_ms", 2000}}},
                 {"rt", {{"require_realtime", false}, {"lock_memory", false}}},
                 {"api", api_section((dir / "api.sock").string())}};
  const std::int64_t from_us = bus_now_us();
  {
    Daemon daemon(dir, config);
    Machine machine(daemon.socket(), [&]() -> std::optional<double> {
      return drive.encoder_sample().position_at_mm(mono_now());
    });
    ASSERT_TRUE(daemon.wait_up([](const json& s) { return s["car"]["floor"] == 0; }))
        << daemon.log();
    ASSERT_TRUE(daemon.wait_machine()) << daemon.status().dump() << daemon.log();
    ASSERT_TRUE(daemon.wait_no_faults()) << daemon.status().dump() << daemon.log();
    for (int floor : {1, 0}) {
      const json r = daemon.call({{"cmd", "travel"}, {"floor", floor}});
      ASSERT_TRUE(r.value("ok", false)) << r.dump() << daemon.log();
      const json end = daemon.wait_travel_end(60s);
      ASSERT_TRUE(end.is_object()) << daemon.log();
      ASSERT_EQ(end["data"]["event"], "finished") << end.dump() << daemon.log();
      const json s = daemon.status();
      EXPECT_EQ(s["car"]["floor"], floor);
      // Where the drive's car is, not only what liftd read.
      EXPECT_NEAR(drive.encoder_sample().position_mm, level_mm(floor), 30.0);
    }
    // The encoder falls silent: the position is lost (after position.can_timeout_ms) and no
    // travel starts.
    machine.encoder_silent(true);
    bool lost = false;
    for (int i = 0; i < 100 && !lost; ++i) {
      lost = daemon.status()["car"]["position_mm"].is_null();
      if (!lost) daemon.api().drain(100ms);
    }
    ASSERT_TRUE(lost) << daemon.status().dump();
    const json refused = daemon.call({{"cmd", "travel"}, {"floor", 1}});
    EXPECT_FALSE(refused.value("ok", true)) << refused.dump();
    EXPECT_EQ(refused["error"]["code"], "not_ready") << refused.dump();
    machine.encoder_silent(false);
  }
  drive.stop();
  // liftd only listens on the encoder's bus: nothing on it but the encoder's frames.
  const auto frames = candump.frames();
  int encoder = 0;
  for (const BusFrame& f : frames) {
    if (f.t_us < from_us) continue;
    EXPECT_EQ(f.id, kEncoderId) << "a frame on the encoder's bus that is not the encoder's";
    encoder += f.id == kEncoderId ? 1 : 0;
  }
  EXPECT_GT(encoder, 100);
  std::error_code ignored;
  if (!::testing::Test::HasFailure()) std::filesystem::remove_all(dir, ignored);
}

}  // namespace
}  // namespace liftd::e2e
