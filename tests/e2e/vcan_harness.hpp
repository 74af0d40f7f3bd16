// The vcan tests' harness: candump, the machine around the lift (inputs, encoder) and the daemon.
#pragma once

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

namespace liftd::e2e {
namespace {

constexpr std::uint32_t kToCard = 0x551;     // controller -> card (card document 6, P479 = 0)
constexpr std::uint32_t kFromCard = 0x581;   // card -> controller
constexpr std::uint32_t kEncoderId = 0x190;  // position.can_id 400
constexpr int kEncoderOffsetMm = -10000;     // count 0 = -10 m: counts stay positive

inline std::string can_interface() {
  const char* name = std::getenv("LIFTD_TEST_CAN");
  return name == nullptr ? std::string() : std::string(name);
}

#define REQUIRE_CAN_INTERFACE()                                                            \
  if (can_interface().empty()) {                                                           \
    GTEST_SKIP() << "LIFTD_TEST_CAN is not set: run by tools/uml/can-stage.sh (user-mode " \
                    "Linux with vcan0)";                                                   \
  }                                                                                        \
  ASSERT_TRUE(can::kernel_has_can()) << "LIFTD_TEST_CAN is set but this kernel has no AF_CAN"

inline std::filesystem::path test_dir(const std::string& leaf) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("liftd-vcan-" + std::to_string(::getpid()) + "-" + leaf);
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

inline json api_section(const std::string& socket) {
  return {{"socket", socket},
          {"socket_group", ""},
          {"read_group", ""},
          {"control_group", ""},
          {"inputs_group", ""}};
}

/// An encoder frame for position.can_* as configured below (4 bytes little endian, 1 mm/count).
inline can::Frame encoder_frame(double position_mm) {
  const auto count = static_cast<std::uint32_t>(std::llround(position_mm - kEncoderOffsetMm));
  return can::make_frame(kEncoderId,
                         std::vector<std::uint8_t>{static_cast<std::uint8_t>(count),
                                                   static_cast<std::uint8_t>(count >> 8),
                                                   static_cast<std::uint8_t>(count >> 16),
                                                   static_cast<std::uint8_t>(count >> 24)});
}

inline json encoder_config() {
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

/// Bus time (candump's wall-clock stamps) now, in microseconds.
inline std::int64_t bus_now_us() {
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

}  // namespace
}  // namespace liftd::e2e
