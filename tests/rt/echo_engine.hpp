// A protocol-free engine for the cycle tests: sends a numbered 6-byte frame each cycle and
// accepts only the FakeResponder's answer to exactly that frame.
#pragma once

#include <algorithm>
#include <array>
#include <atomic>
#include <cstdint>

#include "fake_responder.hpp"
#include "rt/cycle_runner.hpp"

namespace liftd::rt::testing {

/// Frame: 0x01, sequence high, sequence low, 0, 0, checksum. Reply: see echo_reply().
class EchoEngine : public CycleEngine {
 public:
  std::span<const std::uint8_t> frame_to_send(MonoTime /*now*/) noexcept override {
    frame_ = frame_for(++sequence_);
    return frame_;
  }
  std::size_t reply_size() const noexcept override { return kEchoFrameSize; }
  bool on_reply(std::span<const std::uint8_t> reply, MonoTime /*now*/) noexcept override {
    const bool good = answers(sequence_, reply);
    (good ? good_ : bad_).fetch_add(1, std::memory_order_relaxed);
    if (!good) {
      // A bad reply is either an intact answer to one of the last frames (delivered late:
      // the transport or the machine stalled) or a corrupt one.
      bool stale = false;
      for (std::uint16_t back = 1; back <= kStaleWindow && !stale; ++back) {
        stale = answers(static_cast<std::uint16_t>(sequence_ - back), reply);
      }
      (stale ? stale_ : corrupt_).fetch_add(1, std::memory_order_relaxed);
    }
    return good;
  }
  void on_no_reply(MonoTime /*now*/) noexcept override {
    no_reply_.fetch_add(1, std::memory_order_relaxed);
  }
  void on_port_lost(MonoTime /*now*/) noexcept override {
    lost_.fetch_add(1, std::memory_order_relaxed);
  }
  void on_port_ready(MonoTime /*now*/) noexcept override {
    ready_.fetch_add(1, std::memory_order_relaxed);
  }
  void after_cycle(MonoTime /*now*/) noexcept override {
    after_.fetch_add(1, std::memory_order_relaxed);
  }

  std::atomic<std::uint64_t> good_{0};      ///< replies matching the frame sent
  std::atomic<std::uint64_t> bad_{0};       ///< complete replies that did not match
  std::atomic<std::uint64_t> stale_{0};     ///< of the bad: intact answers to an earlier frame
  std::atomic<std::uint64_t> corrupt_{0};   ///< of the bad: anything else
  std::atomic<std::uint64_t> no_reply_{0};  ///< on_no_reply calls
  std::atomic<std::uint64_t> lost_{0};      ///< on_port_lost calls
  std::atomic<std::uint64_t> ready_{0};     ///< on_port_ready calls
  std::atomic<std::uint64_t> after_{0};     ///< after_cycle calls

 private:
  static constexpr std::uint16_t kStaleWindow = 8;  // frames back a late answer may belong to

  static std::array<std::uint8_t, kEchoFrameSize> frame_for(std::uint16_t sequence) noexcept {
    std::array<std::uint8_t, kEchoFrameSize> f{};
    f[0] = 0x01;
    f[1] = static_cast<std::uint8_t>(sequence >> 8);
    f[2] = static_cast<std::uint8_t>(sequence & 0xFF);
    f[5] = echo_checksum(f);
    return f;
  }
  static bool answers(std::uint16_t sequence, std::span<const std::uint8_t> reply) noexcept {
    const auto expected = echo_reply(frame_for(sequence));
    return std::equal(expected.begin(), expected.end(), reply.begin(), reply.end());
  }

  std::uint16_t sequence_ = 0;
  std::array<std::uint8_t, kEchoFrameSize> frame_{};
};

}  // namespace liftd::rt::testing
