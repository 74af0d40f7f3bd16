// Test master for the drive simulator: sends one frame per 15 ms cycle on a fake clock, carries
// the channel byte stream both ways and records every reply.
#pragma once

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <deque>
#include <string>
#include <vector>

#include "dcp/frame.hpp"
#include "dcp/sim/drive_sim.hpp"

namespace liftd::dcp::sim::testing {

using namespace std::chrono_literals;

/// One exchanged cycle.
struct Cycle {
  MonoTime at{};            ///< when the master frame was sent
  std::uint8_t status = 0;  ///< reply status byte (0 when no reply)
  std::uint16_t data = 0;   ///< reply data word
  double position_mm = 0;   ///< car position after the cycle
  double velocity_mps = 0;  ///< car speed after the cycle
  Reply reply{};            ///< raw reply
};

/// Drives a DriveSim like a lift controller would.
class Harness {
 public:
  explicit Harness(DriveConfig config = {}) : sim(config, now) {}

  /// One 15 ms cycle with `command` and `data`; channel bytes come from the send queue.
  Cycle cycle(std::uint8_t command, std::uint16_t data = 0) {
    now += 15ms;  // DCP 7.2: 15 ms cycle
    dcp::MasterFrame f;
    f.command = command;
    f.set_data_word(data);
    f.comm1 = next_tx();
    f.comm2 = next_tx();
    const dcp::FrameBytes bytes = dcp::encode(f);
    return record(sim.on_master_frame(bytes, now));
  }
  /// Sends raw bytes as a frame (e.g. with a bad checksum).
  Cycle raw(const dcp::FrameBytes& bytes) {
    now += 15ms;
    return record(sim.on_master_frame(bytes, now));
  }
  /// A DCP4 remaining-distance frame towards absolute `target_mm`, measured the way a master
  /// with an encoder does: the position as the frame leaves, clamped at 0 once passed and at
  /// `clamp_mm` (0x7FFF or 0xFFFF, DCP 3.5.3.4) above.
  Cycle distance_cycle(std::uint8_t command, double target_mm, double clamp_mm = 32767.0) {
    sim.advance(now + 15ms);
    const double pos = sim.position_mm();
    const double rd = (command & 0x10) != 0 ? pos - target_mm : target_mm - pos;
    return cycle(command, static_cast<std::uint16_t>(std::lround(std::clamp(rd, 0.0, clamp_mm))));
  }
  /// Repeats `command` for `n` cycles; returns the last.
  Cycle repeat(std::uint8_t command, int n, std::uint16_t data = 0) {
    Cycle c;
    for (int i = 0; i < n; ++i) c = cycle(command, data);
    return c;
  }
  /// Queues a channel message STX mode body ETX.
  void send_channel(std::uint8_t mode, const std::string& body) {
    tx.push_back(0x02);
    tx.push_back(mode);
    for (char c : body) tx.push_back(static_cast<std::uint8_t>(c));
    tx.push_back(0x03);
  }
  /// Runs idle cycles until a complete drive message of `mode` arrives (at most `limit`);
  /// returns its body, or "<none>".
  std::string await_channel(std::uint8_t mode, std::uint8_t command = 0, int limit = 200) {
    for (int i = 0; i < limit; ++i) {
      cycle(command);
      std::string body;
      if (take_message(mode, body)) return body;
    }
    return "<none>";
  }
  /// The I0 exchange (DCP 5.12.2); returns the reply body.
  std::string init(char type = '0') {
    send_channel(0x1C, "I0LI0100010126DE");
    std::string r = await_channel(0x1C);
    if (type != '0') {
      send_channel(0x1C, std::string("I10") + type);
      await_channel(0x1C);
    }
    return r;
  }

  /// Extracts the first complete message of `mode` from the received bytes.
  bool take_message(std::uint8_t mode, std::string& body) {
    for (std::size_t i = 0; i + 1 < rx.size(); ++i) {
      if (rx[i] != 0x02 || rx[i + 1] != mode) continue;
      for (std::size_t j = i + 2; j < rx.size(); ++j) {
        if (rx[j] == 0x03) {
          body.assign(rx.begin() + static_cast<std::ptrdiff_t>(i + 2),
                      rx.begin() + static_cast<std::ptrdiff_t>(j));
          rx.erase(rx.begin(), rx.begin() + static_cast<std::ptrdiff_t>(j + 1));
          return true;
        }
      }
    }
    return false;
  }

  MonoTime now{};
  DriveSim sim;
  std::deque<std::uint8_t> tx;
  std::vector<std::uint8_t> rx;
  std::vector<Cycle> history;

 private:
  std::uint8_t next_tx() {
    if (tx.empty()) return 0;
    const std::uint8_t b = tx.front();
    tx.pop_front();
    return b;
  }
  Cycle record(const Reply& r) {
    Cycle c;
    c.at = now;
    c.reply = r;
    if (r.size == dcp::kFrameSize) {
      std::array<std::uint8_t, 6> b{};
      std::copy(r.bytes.begin(), r.bytes.begin() + 6, b.begin());
      if (auto s = dcp::decode_slave(b)) {
        c.status = s->status;
        c.data = s->data_word();
        if (s->comm1 != 0) rx.push_back(s->comm1);
        if (s->comm2 != 0) rx.push_back(s->comm2);
      }
    }
    c.position_mm = sim.position_mm();
    c.velocity_mps = sim.velocity_mps();
    history.push_back(c);
    return c;
  }
};

/// Command bytes used in the tests (B3..B0 plus B4 direction).
namespace cmd {
inline constexpr std::uint8_t kIdle = 0x00;
inline constexpr std::uint8_t kStop = 0x01;     // B0
inline constexpr std::uint8_t kRelevel = 0x03;  // B1 B0
inline constexpr std::uint8_t kDecel = 0x05;    // B2 B0 (0101)
inline constexpr std::uint8_t kTravel = 0x07;   // B2 B1 B0
inline constexpr std::uint8_t kSpeed = 0x09;    // B3 B0
inline constexpr std::uint8_t kGo3 = 0x0F;      // DCP3 speed after fast start
inline constexpr std::uint8_t kGo4 = 0x0D;      // DCP4 speed after fast start
inline constexpr std::uint8_t kDown = 0x10;     // B4
inline constexpr std::uint8_t kB7 = 0x80;       // your last reply was corrupt
}  // namespace cmd

}  // namespace liftd::dcp::sim::testing
