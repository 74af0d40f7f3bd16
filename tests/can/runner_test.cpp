// The CAN runner's engine seam: an engine sends on its own schedule (a CANopen-like SYNC every
// N ms with nothing received), what one call queues beyond the outbox is refused and counted,
// and frames queued while the endpoint is down are reported unsent, with the open failure in
// words. All through the real CanRunner over a `unix:` endpoint, as under --simulate.
#include <gtest/gtest.h>

#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstddef>
#include <cstring>
#include <filesystem>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "can/socket.hpp"
#include "rt/can_runner.hpp"

namespace liftd::can {
namespace {

using namespace std::chrono_literals;

/// CiA 301 7.2.5: the SYNC object's COB-ID and its optional counter, which runs 1..240.
constexpr std::uint32_t kSyncId = 0x080;

/// A unix: endpoint of this test's own, removed at the end.
struct UnixEndpoint {
  explicit UnixEndpoint(const std::string& tag)
      : path((std::filesystem::temp_directory_path() /
              ("liftd-can-" + tag + "-" + std::to_string(::getpid())))
                 .string()) {}
  ~UnixEndpoint() { ::unlink(path.c_str()); }
  std::string path;
};

/// The peer's end: accepts the runner's connection within 5 s.
std::optional<CanSocket> accept_runner(int listener) {
  pollfd p{listener, POLLIN, 0};
  if (::poll(&p, 1, 5000) != 1) return std::nullopt;
  const int fd = ::accept4(listener, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
  if (fd < 0) return std::nullopt;
  return CanSocket::adopt(fd);
}

/// Reads frames until `count` arrived or `limit` passed, then whatever else is queued.
std::vector<Frame> read_frames(CanSocket& peer, std::size_t count,
                               std::chrono::milliseconds limit) {
  std::vector<Frame> out;
  const MonoTime until = mono_now() + limit;
  while (out.size() < count && mono_now() < until) {
    const Received r = peer.read();
    if (r.kind == Received::Kind::Frame) {
      out.push_back(r.frame);
      continue;
    }
    if (r.kind == Received::Kind::Closed || r.kind == Received::Kind::Failed) break;
    pollfd p{peer.fd(), POLLIN, 0};
    (void)::poll(&p, 1, 10);
  }
  return out;
}

/// Everything still queued on the peer's side, without waiting (up to the runner's hang-up).
void drain(CanSocket& peer, std::vector<Frame>& out) {
  for (Received r = peer.read(); r.kind == Received::Kind::Frame || r.kind == Received::Kind::Error;
       r = peer.read()) {
    if (r.kind == Received::Kind::Frame) out.push_back(r.frame);
  }
}

rt::CanRunnerConfig runner_config(const std::string& endpoint) {
  rt::CanRunnerConfig config;
  config.endpoint = endpoint;
  config.rt.priority = 0;  // an ordinary thread: the test needs no privileges
  config.rt.lock_memory = false;
  return config;
}

/// Sends a SYNC every `period` from on_tick while the endpoint is up, `limit` of them in all,
/// never in answer to anything. Written by the runner's thread; read after the runner stopped.
class SyncEngine final : public rt::CanEngine {
 public:
  static constexpr std::size_t kLimit = 10;
  explicit SyncEngine(MonoTime period) : period_(period) {}

  void on_frame(const Frame&, MonoTime, rt::CanOutbox&) noexcept override { received.fetch_add(1); }
  void on_bus_error(const ErrorReport&, MonoTime) noexcept override {}
  void on_endpoint(bool up, MonoTime now) noexcept override {
    up_ = up;
    next_ = now;  // the first SYNC in the tick that follows the opening
  }
  void on_tick(MonoTime now, rt::CanOutbox& out) noexcept override {
    if (!up_ || requested.load() == kLimit || now < next_) return;
    const std::array<std::uint8_t, 1> counter = {static_cast<std::uint8_t>(requested.load() + 1)};
    if (!out.send(make_frame(kSyncId, counter))) return;
    queued_at[requested.load()] = now;
    requested.fetch_add(1);
    next_ = now + period_;
  }
  void on_sent(const Frame& frame, bool delivered, MonoTime) noexcept override {
    if (!delivered) {
      failed.fetch_add(1);
      return;
    }
    if (delivered_count < kLimit) sent[delivered_count] = frame;
    ++delivered_count;
  }

  std::atomic<std::size_t> requested{0};  ///< SYNCs the engine queued
  std::atomic<int> received{0};
  std::atomic<int> failed{0};
  std::array<MonoTime, kLimit> queued_at{};
  std::array<Frame, kLimit> sent{};  ///< as on_sent() reported them delivered
  std::size_t delivered_count = 0;

 private:
  MonoTime period_;
  bool up_ = false;
  MonoTime next_{};
};

TEST(CanRunnerEngineSeam, AnEngineSendsAPeriodicSyncWithNothingReceived) {
  UnixEndpoint endpoint("sync");
  auto listener = listen_unix(endpoint.path);
  ASSERT_TRUE(listener) << listener.error().what;
  constexpr MonoTime kPeriod = 20ms;
  SyncEngine engine(kPeriod);
  rt::CanRunner runner(runner_config("unix:" + endpoint.path), engine);
  ASSERT_EQ(runner.start(), 0);
  auto peer = accept_runner(listener.value());
  ASSERT_TRUE(peer) << "the runner did not connect";
  // Ten SYNCs take 180 ms of the engine's schedule; 10 s leaves room for a loaded machine.
  std::vector<Frame> got = read_frames(*peer, SyncEngine::kLimit, 10s);
  ASSERT_EQ(got.size(), SyncEngine::kLimit) << "SYNCs the peer received in 10 s";
  runner.stop();  // after the join, everything the runner sent is queued at the peer
  drain(*peer, got);
  ::close(listener.value());

  // Exactly the frames the engine decided, in order, and nothing more.
  EXPECT_EQ(engine.requested.load(), SyncEngine::kLimit);
  ASSERT_EQ(got.size(), SyncEngine::kLimit) << "frames the engine never asked for";
  ASSERT_EQ(engine.delivered_count, SyncEngine::kLimit);
  for (std::size_t i = 0; i < SyncEngine::kLimit; ++i) {
    const std::array<std::uint8_t, 1> counter = {static_cast<std::uint8_t>(i + 1)};
    EXPECT_EQ(got[i], make_frame(kSyncId, counter)) << "SYNC " << i + 1;
    EXPECT_EQ(engine.sent[i], got[i]) << "on_sent() names the frame that went out";
  }
  // The engine's own schedule: never two SYNCs closer than its period (however late a loaded
  // machine woke it, which only makes them farther apart).
  for (std::size_t i = 1; i < SyncEngine::kLimit; ++i) {
    EXPECT_GE(engine.queued_at[i] - engine.queued_at[i - 1], kPeriod) << "SYNC " << i + 1;
  }
  EXPECT_EQ(engine.received.load(), 0) << "nothing was sent to the engine";
  EXPECT_EQ(engine.failed.load(), 0);
  const rt::CanRunnerCounters c = runner.counters();
  EXPECT_EQ(c.frames_sent, SyncEngine::kLimit);
  EXPECT_EQ(c.frames_received, 0U);
  EXPECT_EQ(c.send_errors, 0U);
  EXPECT_EQ(c.outbox_overflows, 0U);
  EXPECT_EQ(runner.last_error(), "");
  // The recorder has every SYNC as sent (Tx), after the endpoint's opening.
  std::size_t recorded = 0;
  for (const rt::FrameRecord& r : runner.recorder().copy()) {
    if (r.direction == rt::Direction::Tx && (r.flags & rt::record_flag::kSent) != 0) ++recorded;
  }
  EXPECT_EQ(recorded, SyncEngine::kLimit);
}

/// Queues one more frame than the outbox holds, once, in the first tick with the endpoint up.
class BurstEngine final : public rt::CanEngine {
 public:
  static constexpr std::size_t kTried = rt::CanOutbox::kCapacity + 1;
  void on_frame(const Frame&, MonoTime, rt::CanOutbox&) noexcept override {}
  void on_bus_error(const ErrorReport&, MonoTime) noexcept override {}
  void on_endpoint(bool up, MonoTime) noexcept override { up_ = up; }
  void on_tick(MonoTime, rt::CanOutbox& out) noexcept override {
    if (!up_ || done_) return;
    done_ = true;
    for (std::size_t i = 0; i < kTried; ++i) {
      const std::array<std::uint8_t, 1> index = {static_cast<std::uint8_t>(i)};
      if (out.send(make_frame(0x200, index))) ++accepted;
    }
    room_after = out.room();
  }
  void on_sent(const Frame& frame, bool delivered, MonoTime) noexcept override {
    if (delivered && reported < sent.size()) sent[reported] = frame;
    ++reported;
  }
  std::size_t accepted = 0;
  std::size_t room_after = 99;
  std::size_t reported = 0;
  std::array<Frame, kTried> sent{};

 private:
  bool up_ = false;
  bool done_ = false;
};

TEST(CanRunnerEngineSeam, WhatOneCallQueuesBeyondTheOutboxIsRefusedAndCounted) {
  UnixEndpoint endpoint("burst");
  auto listener = listen_unix(endpoint.path);
  ASSERT_TRUE(listener) << listener.error().what;
  BurstEngine engine;
  rt::CanRunner runner(runner_config("unix:" + endpoint.path), engine);
  ASSERT_EQ(runner.start(), 0);
  auto peer = accept_runner(listener.value());
  ASSERT_TRUE(peer) << "the runner did not connect";
  std::vector<Frame> got = read_frames(*peer, rt::CanOutbox::kCapacity, 10s);
  runner.stop();
  drain(*peer, got);
  ::close(listener.value());

  EXPECT_EQ(engine.accepted, rt::CanOutbox::kCapacity);
  EXPECT_EQ(engine.room_after, 0U);
  ASSERT_EQ(got.size(), rt::CanOutbox::kCapacity);
  ASSERT_EQ(engine.reported, rt::CanOutbox::kCapacity) << "one on_sent() per queued frame";
  for (std::size_t i = 0; i < got.size(); ++i) {
    const std::array<std::uint8_t, 1> index = {static_cast<std::uint8_t>(i)};
    EXPECT_EQ(got[i], make_frame(0x200, index)) << "sent in the order queued";
    EXPECT_EQ(engine.sent[i], got[i]);
  }
  const rt::CanRunnerCounters c = runner.counters();
  EXPECT_EQ(c.outbox_overflows, 1U);
  EXPECT_EQ(c.frames_sent, rt::CanOutbox::kCapacity);
}

/// Queues one frame in each of its first three ticks whatever the endpoint's state.
class BlindEngine final : public rt::CanEngine {
 public:
  void on_frame(const Frame&, MonoTime, rt::CanOutbox&) noexcept override {}
  void on_bus_error(const ErrorReport&, MonoTime) noexcept override {}
  void on_endpoint(bool up, MonoTime) noexcept override {
    (up ? opened : failed_opens).fetch_add(1);
  }
  void on_tick(MonoTime, rt::CanOutbox& out) noexcept override {
    if (queued < 3 && out.send(make_frame(0x200, {}))) ++queued;
  }
  void on_sent(const Frame&, bool delivered, MonoTime) noexcept override {
    (delivered ? delivered_count : undelivered).fetch_add(1);
  }
  int queued = 0;
  std::atomic<int> opened{0};
  std::atomic<int> failed_opens{0};
  std::atomic<int> delivered_count{0};
  std::atomic<int> undelivered{0};
};

TEST(CanRunnerEngineSeam, FramesQueuedWithoutAnEndpointAreReportedUnsent) {
  const std::string path = "/nonexistent/liftd-can-runner.sock";
  BlindEngine engine;
  rt::CanRunner runner(runner_config("unix:" + path), engine);
  ASSERT_EQ(runner.start(), 0);
  const MonoTime until = mono_now() + 10s;
  while (engine.undelivered.load() < 3 && mono_now() < until) std::this_thread::sleep_for(5ms);
  runner.stop();
  EXPECT_EQ(engine.undelivered.load(), 3);
  EXPECT_EQ(engine.delivered_count.load(), 0);
  EXPECT_EQ(engine.opened.load(), 0) << "opening never succeeded, so it was never reported";
  const rt::CanRunnerCounters c = runner.counters();
  EXPECT_EQ(c.send_errors, 3U);
  EXPECT_EQ(c.frames_sent, 0U);
  // The open failure, in the words CanSocket::open() gives, made on this thread.
  EXPECT_EQ(runner.last_error(), "connect to " + path + ": " + std::strerror(ENOENT));
}

}  // namespace
}  // namespace liftd::can
