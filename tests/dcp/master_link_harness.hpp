// The link, fake drive and fake clock every DCP master link test runs on (master_link*_test.cpp).
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <functional>
#include <vector>

#include "dcp/dcp_test_util.hpp"
#include "dcp/master_link.hpp"
#include "fake_drive.hpp"

namespace liftd::dcp {
namespace {

using namespace std::chrono_literals;
using test::bytes;
using test::FakeDrive;

constexpr std::uint8_t kB0B2 = command_bit::kDriveEnable | command_bit::kStopSwitch;

// One link, one fake drive, one fake clock; a cycle is 15 ms (DCP 2).
struct Harness {
  explicit Harness(MasterLinkConfig c = {}) : link(c) {}

  MasterLink link;
  FakeDrive drive;
  MonoTime now = 1000ms;
  int corrupt_masters = 0;  ///< corrupt the next N master frames on the wire
  /// The next N master frames collide on an echoing line: corrupted on the wire for the drive,
  /// and the master reads its echo back changed (on_bad_reply), whatever the drive answers.
  int collide_masters = 0;
  std::vector<FrameBytes> sent;
  std::vector<Completion> completions;
  std::vector<LinkEvent> events;
  std::vector<DriveErrorEvent> errors;

  void cycle() {
    const FrameBytes frame = link.next_frame(now);
    sent.push_back(frame);
    FrameBytes wire = frame;
    if (corrupt_masters > 0) {
      --corrupt_masters;
      wire[5] ^= 0x01;
    }
    const bool collided = collide_masters > 0;
    if (collided) {
      --collide_masters;
      wire[1] ^= 0x10;
    }
    const auto reply = drive.exchange(wire, now);
    if (collided) {
      link.on_bad_reply(now + 2ms);  // the echo differed: read while sending (DCP 7.2)
    } else if (reply) {
      link.on_reply(*reply, now + 5ms);  // DCP 7.2: reply well inside the cycle
    } else {
      link.on_no_reply(now + 14ms);
    }
    drain();
    now += 15ms;
  }
  void run(int cycles) {
    for (int i = 0; i < cycles; ++i) cycle();
  }
  // Runs until pred() holds; returns the cycles it took, or -1 after `max`.
  int run_until(const std::function<bool()>& pred, int max = 400) {
    for (int i = 0; i < max; ++i) {
      if (pred()) return i;
      cycle();
    }
    return pred() ? max : -1;
  }
  void drain() {
    while (auto c = link.pop_completion()) completions.push_back(*c);
    while (auto e = link.pop_event()) events.push_back(*e);
    while (auto d = link.pop_drive_error()) errors.push_back(*d);
  }
  bool up() const { return link.state() == LinkState::Up; }
  void bring_up() {
    ASSERT_GE(run_until([&] { return up(); }), 0) << "handshake never finished";
  }
  const FrameBytes& last() const { return sent.back(); }
  int count_messages(MessageId id) const {
    return static_cast<int>(std::count_if(drive.messages.begin(), drive.messages.end(),
                                          [&](const auto& m) { return message_id(m) == id; }));
  }
  const LinkEvent* last_state_change() const {
    for (auto it = events.rbegin(); it != events.rend(); ++it) {
      if (it->kind == LinkEventKind::StateChanged) return &*it;
    }
    return nullptr;
  }
};

inline MasterLinkConfig dcp4_config() {
  MasterLinkConfig c;
  c.maker = {'B', 'P'};
  c.version = 123;
  c.software_date = {15, 6, 25};
  c.language = {'D', 'E'};
  c.data_info_type = DataInfoType::Decel15;
  c.extended_position = true;
  return c;
}

}  // namespace
}  // namespace liftd::dcp
