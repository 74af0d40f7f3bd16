// No heap allocation on the CAN runner's thread with the REAL SCH001 controller (card link,
// hydraulic travel sequencing, lift core, snapshots and queues) over a `unix:` endpoint, as under
// --simulate: during a travel, and while the endpoint goes down and is reopened several times
// (the card's listener disappears, the runner's opens fail with backoff, then it comes back).
// heap_hooks.hpp replaces malloc and operator new for the whole binary: this file is alone in
// its executable. The runner's thread switches counting on after a warm-up.
#include <gtest/gtest.h>

#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <new>
#include <optional>
#include <string>
#include <thread>

#include "can/socket.hpp"
#include "common/position_source.hpp"
#include "rt/can_runner.hpp"
#include "sch001/controller.hpp"
#include "sch001/sim/sch001_card_sim.hpp"

#include "support/heap_hooks.hpp"

namespace liftd::sch001 {
namespace {

using namespace std::chrono_literals;

/// Forwards every call to the real controller. Each call sets the thread's counting flag from
/// arm() / disarm(); the flag stays set between calls, so the runner's own code (reading,
/// sending, recording, closing and reopening the endpoint) is counted too.
class CountingEngine final : public rt::CanEngine {
 public:
  explicit CountingEngine(Sch001Controller& inner) : inner_(inner) {}
  void arm() noexcept { wanted_.store(true); }
  void disarm() noexcept { wanted_.store(false); }
  /// Loop passes (ticks) run with counting on.
  std::uint64_t counted_ticks() const noexcept { return counted_ticks_.load(); }

  void on_frame(const can::Frame& frame, MonoTime now, rt::CanOutbox& out) noexcept override {
    heap_hooks::counting = wanted_.load(std::memory_order_relaxed);
    inner_.on_frame(frame, now, out);
  }
  void on_bus_error(const can::ErrorReport& report, MonoTime now) noexcept override {
    heap_hooks::counting = wanted_.load(std::memory_order_relaxed);
    inner_.on_bus_error(report, now);
  }
  void on_endpoint(bool up, MonoTime now) noexcept override {
    heap_hooks::counting = wanted_.load(std::memory_order_relaxed);
    inner_.on_endpoint(up, now);
  }
  void on_tick(MonoTime now, rt::CanOutbox& out) noexcept override {
    heap_hooks::counting = wanted_.load(std::memory_order_relaxed);
    inner_.on_tick(now, out);
    if (heap_hooks::counting) counted_ticks_.fetch_add(1, std::memory_order_relaxed);
  }
  void on_sent(const can::Frame& frame, bool delivered, MonoTime now) noexcept override {
    inner_.on_sent(frame, delivered, now);
  }

 private:
  Sch001Controller& inner_;
  std::atomic<bool> wanted_{false};
  std::atomic<std::uint64_t> counted_ticks_{0};
};

/// The simulated card on its own thread, listening at `path`: it answers the runner's
/// connection, sends its status frames, moves its car as the answers say, and can go away (the
/// connection and the listener closed, the socket file removed) and come back.
class CardPeer final : public PositionSource {
 public:
  explicit CardPeer(std::string path) : path_(std::move(path)), card_(card_config(), mono_now()) {}
  ~CardPeer() override {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
    if (listener_ >= 0) ::close(listener_);
    ::unlink(path_.c_str());
  }
  bool start() {
    if (!listen()) return false;
    thread_ = std::thread([this] { loop(); });
    return true;
  }
  void go_away() { away_ = true; }
  void come_back() { away_ = false; }
  /// Answers the card received (from any connection).
  std::uint64_t answers() const noexcept { return answers_.load(); }
  std::optional<std::int64_t> position_mm(MonoTime) const noexcept override {
    return position_mm_.load();
  }

 private:
  static sim::CardSimConfig card_config() {
    sim::CardSimConfig c;
    // Status frames every 20 ms instead of the card's 100 ms (3b): five times the traffic in
    // the counted window; the controller answers each as it comes.
    c.period_ms = 20;
    return c;
  }
  bool listen() {
    auto listener = can::listen_unix(path_);
    if (!listener) return false;
    listener_ = listener.value();
    return true;
  }
  void loop() {
    while (!stop_) {
      if (away_ && listener_ >= 0) {
        peer_.reset();
        card_.connection_lost();
        ::close(listener_);
        listener_ = -1;
        ::unlink(path_.c_str());
      } else if (!away_ && listener_ < 0) {
        (void)listen();
      }
      std::array<pollfd, 2> fds{};
      fds[0] = {listener_, POLLIN, 0};
      fds[1] = {peer_ ? peer_->fd() : -1, POLLIN, 0};
      (void)::poll(fds.data(), fds.size(), 2);
      const MonoTime now = mono_now();
      if (listener_ >= 0 && (fds[0].revents & POLLIN) != 0) {
        const int fd = ::accept4(listener_, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
        if (fd >= 0) peer_.emplace(can::CanSocket::adopt(fd));
      }
      for (int i = 0; peer_ && i < 16; ++i) {
        const can::Received r = peer_->read();
        if (r.kind == can::Received::Kind::Frame) {
          card_.on_frame(r.frame, now);
        } else if (r.kind == can::Received::Kind::Closed || r.kind == can::Received::Kind::Failed) {
          peer_.reset();
          card_.connection_lost();
        } else {
          break;
        }
      }
      if (const auto frame = card_.poll(now)) {
        if (peer_) {
          (void)peer_->write(*frame);
        } else {
          card_.connection_lost();
        }
      }
      answers_.store(card_.state().answers);
      position_mm_.store(std::llround(card_.state().position_mm));
    }
  }

  std::string path_;
  sim::Sch001CardSim card_;
  int listener_ = -1;
  std::optional<can::CanSocket> peer_;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  std::atomic<bool> away_{false};
  std::atomic<std::uint64_t> answers_{0};
  std::atomic<std::int64_t> position_mm_{0};
};

/// Runs `io` (the io thread's part: fresh inputs, draining replies and events, reading the
/// runner's counters and last error) every 10 ms until `done` or 10 s; true when done.
bool pump_until(const std::function<void()>& io, const std::function<bool()>& done) {
  const MonoTime until = mono_now() + 10s;
  while (mono_now() < until) {
    io();
    if (done()) return true;
    std::this_thread::sleep_for(10ms);
  }
  return false;
}

TEST(Sch001CanAlloc, TheCanLoopAllocatesNothingThroughATravelAndRepeatedReopens) {
  if (!LIFTD_HEAP_HOOKS) GTEST_SKIP() << "allocation hooks are off under the sanitizers";
  ASSERT_TRUE(heap_hooks::counts_allocations()) << "the hooks must see an allocation";

  const std::string path = (std::filesystem::temp_directory_path() /
                            ("liftd-sch001-alloc-" + std::to_string(::getpid())))
                               .string();
  CardPeer card(path);
  ASSERT_TRUE(card.start());
  ControllerConfig cc;
  cc.floors_mm = {0, 3000, 6000};
  Sch001Controller controller(cc, card, mono_now());
  CountingEngine engine(controller);
  rt::CanRunnerConfig rc;
  rc.endpoint = "unix:" + path;
  rc.ids = {cc.link.ids.from_card, cc.link.ids.to_card};
  rc.rt.priority = 0;  // an ordinary thread: the test needs no privileges
  rc.rt.lock_memory = false;
  // Quick retries, so the counted window holds many failed opens (the default is 100 ms
  // doubling up to 5 s).
  rc.reopen_first = 5ms;
  rc.reopen_max = 20ms;
  rt::CanRunner runner(rc, engine);

  std::uint32_t tag = 0;
  std::optional<lift::CommandReply> travel_reply;
  std::uint32_t travel_tag = 0;
  std::string last_error;
  const auto io = [&] {
    lift::Inputs in;
    in.valid = in.doors_closed = in.doors_locked = in.safety_chain_closed = true;
    (void)controller.post({0, InputsCommand{in}});
    lift::CommandReply r;
    while (controller.poll_reply(r)) {
      if (r.tag == travel_tag) travel_reply = r;
    }
    ControllerEvent e;
    while (controller.poll_event(e)) {
    }
    (void)controller.snapshot();
    (void)runner.counters();
    last_error = runner.last_error();
  };

  ASSERT_EQ(runner.start(), 0);
  // Warm-up: the card is heard and a few dozen answers went out.
  ASSERT_TRUE(pump_until(io, [&] { return controller.snapshot().heard && card.answers() >= 30; }));
  engine.arm();
  ASSERT_TRUE(pump_until(io, [&] { return engine.counted_ticks() >= 10; }));

  // A travel: the answers carry travel bits and the car moves.
  travel_tag = ++tag;
  ASSERT_TRUE(controller.post({travel_tag, TravelCommand{1, Speed::Fast}}));
  ASSERT_TRUE(pump_until(io, [&] { return travel_reply.has_value(); }));
  ASSERT_EQ(travel_reply->code, lift::ReplyCode::Ok) << travel_reply->detail;
  ASSERT_TRUE(pump_until(io, [&] { return card.position_mm(mono_now()).value_or(0) > 50; }))
      << "the car did not move";

  // The endpoint goes down and comes back, three times: the peer closes, the runner's opens
  // fail (first ENOENT: the socket file is gone), then a new listener takes it again.
  constexpr std::uint64_t kOutages = 3;
  for (std::uint64_t i = 1; i <= kOutages; ++i) {
    card.go_away();
    ASSERT_TRUE(pump_until(io, [&] { return !controller.snapshot().endpoint_up; }))
        << "outage " << i << ": the runner did not see the card go";
    // A while of failed opens (5 to 20 ms apart) before the card comes back.
    const std::uint64_t ticks = engine.counted_ticks();
    ASSERT_TRUE(pump_until(io, [&] { return engine.counted_ticks() >= ticks + 10; }));
    EXPECT_EQ(last_error.rfind("connect to " + path + ": ", 0), 0U)
        << "outage " << i << ": the last error is not a failed open: " << last_error;
    const std::uint64_t answers = card.answers();
    card.come_back();
    ASSERT_TRUE(pump_until(
        io, [&] { return runner.counters().reopens >= i && card.answers() >= answers + 10; }))
        << "outage " << i << ": the card is not answered again";
    EXPECT_TRUE(controller.snapshot().heard);
  }
  engine.disarm();
  const std::uint64_t mallocs = heap_hooks::mallocs.load();
  const std::uint64_t news = heap_hooks::news.load();
  const std::uint64_t counted = engine.counted_ticks();
  runner.stop();

  EXPECT_EQ(mallocs, 0U) << "malloc calls on the CAN thread";
  EXPECT_EQ(news, 0U) << "operator new calls on the CAN thread";
  EXPECT_GE(counted, 40U);
  EXPECT_GE(runner.counters().reopens, kOutages);
}

}  // namespace
}  // namespace liftd::sch001
