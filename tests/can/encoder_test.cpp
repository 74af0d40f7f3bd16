// The CAN absolute encoder: every field of its format as a table of frames and positions,
// refused formats, staleness with a fake clock, and the runtime path: encoder frames sent over a
// socketpair reach the position source through a CAN runner (the same read path as SocketCAN).
#include <gtest/gtest.h>

#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "can/encoder.hpp"
#include "can/socket.hpp"
#include "rt/can_runner.hpp"
#include "rt/encoder_tap.hpp"

namespace liftd::can {
namespace {

using namespace std::chrono_literals;
using Bytes = std::vector<std::uint8_t>;

TEST(CanEncoderFormat, DecodesEveryFieldAsConfigured) {
  struct Case {
    const char* what;
    EncoderFormat format;
    Bytes data;
    std::optional<std::int64_t> mm;
  };
  const auto fmt = [](std::uint8_t offset, std::uint8_t length, bool big, bool is_signed,
                      std::int64_t um, std::int64_t offset_mm) {
    EncoderFormat f;
    f.id = 0x190;
    f.offset = offset;
    f.length = length;
    f.big_endian = big;
    f.is_signed = is_signed;
    f.um_per_count = um;
    f.offset_mm = offset_mm;
    return f;
  };
  const std::vector<Case> cases = {
      {"4 bytes little endian, 1 mm", fmt(0, 4, false, false, 1000, 0), {0x10, 0x27, 0, 0}, 10000},
      {"4 bytes big endian", fmt(0, 4, true, false, 1000, 0), {0, 0, 0x27, 0x10}, 10000},
      {"2 bytes at offset 2", fmt(2, 2, false, false, 1000, 0), {0xFF, 0xFF, 0xB8, 0x0B}, 3000},
      {"3 bytes big endian at offset 5",
       fmt(5, 3, true, false, 1000, 0),
       {0, 0, 0, 0, 0, 0x00, 0x0B, 0xB8},
       3000},
      {"signed 2 bytes: -1 count", fmt(0, 2, false, true, 1000, 0), {0xFF, 0xFF}, -1},
      {"unsigned 2 bytes: 65535", fmt(0, 2, false, false, 1000, 0), {0xFF, 0xFF}, 65535},
      {"signed 4 bytes: -100", fmt(0, 4, false, true, 1000, 0), {0x9C, 0xFF, 0xFF, 0xFF}, -100},
      {"0.1 mm per count, rounded", fmt(0, 2, false, false, 100, 0), {0x2D, 0x00}, 5},  // 4.5
      {"negative scale counts down", fmt(0, 2, false, false, -1000, 9000), {0xE8, 0x03}, 8000},
      {"offset added after scaling", fmt(0, 2, false, false, 2000, -250), {0x64, 0x00}, -50},
      {"frame too short", fmt(4, 4, false, false, 1000, 0), {1, 2, 3, 4, 5}, std::nullopt},
  };
  for (const Case& c : cases) {
    EXPECT_EQ(decode_position(c.format, make_frame(0x190, c.data)), c.mm) << c.what;
  }
  EXPECT_EQ(decode_position(fmt(0, 2, false, false, 1000, 0), make_frame(0x191, Bytes{1, 0})),
            std::nullopt)
      << "another identifier";
}

TEST(CanEncoderFormat, RefusesWhatCannotBeDecoded) {
  EncoderFormat f;
  f.length = 5;
  EXPECT_EQ(validate(f), "the value is 2 to 4 bytes long");
  f.length = 4;
  f.offset = 5;
  EXPECT_EQ(validate(f), "offset + length must stay within the 8 data bytes of a CAN frame");
  f.offset = 0;
  f.um_per_count = 0;
  EXPECT_EQ(validate(f), "the scale (micrometres per count) must not be 0");
  f.um_per_count = 1000;
  f.id = 0x800;
  EXPECT_TRUE(validate(f).has_value());
  f.id = 0x7FF;
  EXPECT_EQ(validate(f), std::nullopt);
}

TEST(CanEncoder, GoesStaleAfterItsTimeout) {
  CanEncoder encoder(EncoderFormat{}, 100ms);
  EXPECT_EQ(encoder.position_mm(MonoTime{}), std::nullopt) << "nothing heard yet";
  EXPECT_TRUE(encoder.on_frame(make_frame(0x190, Bytes{0xB8, 0x0B, 0, 0}), 1000ms));
  EXPECT_EQ(encoder.position_mm(1100ms), 3000);
  EXPECT_EQ(encoder.position_mm(1101ms), std::nullopt);
  EXPECT_FALSE(encoder.on_frame(make_frame(0x191, Bytes{0, 0, 0, 0}), 1101ms));
  EXPECT_TRUE(encoder.on_frame(make_frame(0x190, Bytes{0}), 1102ms));
  EXPECT_EQ(encoder.short_frames(), 1U);
  EXPECT_EQ(encoder.position_mm(1102ms), std::nullopt) << "a short frame is no position";
}

TEST(CanEncoder, FramesReachItThroughACanRunner) {
  auto pair = CanSocket::pair();
  ASSERT_TRUE(pair);
  CanEncoder encoder(EncoderFormat{}, 200ms);
  rt::EncoderTap tap(encoder, nullptr);
  rt::CanRunnerConfig config;
  config.endpoint = "socketpair";
  config.ids = {0x190};
  config.rt.priority = 0;
  config.rt.lock_memory = false;
  rt::CanRunner runner(config, tap);
  runner.adopt(std::move(pair.value().first));
  ASSERT_EQ(runner.start(), 0);
  CanSocket& bus = pair.value().second;
  std::optional<std::int64_t> seen;
  for (int i = 0; i < 200 && seen != 4321; ++i) {
    ASSERT_EQ(bus.write(make_frame(0x190, Bytes{0xE1, 0x10, 0, 0})), 0);
    std::this_thread::sleep_for(5ms);
    seen = encoder.position_mm(mono_now());
  }
  EXPECT_EQ(seen, 4321);
  // The encoder falls silent: within its timeout the position is gone (a travel would end).
  bool stale = false;
  for (int i = 0; i < 200 && !stale; ++i) {
    std::this_thread::sleep_for(5ms);
    stale = !encoder.position_mm(mono_now()).has_value();
  }
  EXPECT_TRUE(stale);
  runner.stop();
  EXPECT_GE(runner.counters().frames_received, 1U);
}

/// Counts what a CAN runner tells its engine.
class CountingEngine final : public rt::CanEngine {
 public:
  void on_frame(const Frame&, MonoTime, rt::CanOutbox&) noexcept override {}
  void on_bus_error(const ErrorReport&, MonoTime) noexcept override {}
  void on_endpoint(bool up, MonoTime) noexcept override { (up ? opened : failed).fetch_add(1); }
  void on_tick(MonoTime, rt::CanOutbox&) noexcept override {}
  std::atomic<int> opened{0};
  std::atomic<int> failed{0};
};

TEST(CanRunnerReopen, BacksOffWhileTheEndpointFailsRightAfterOpening) {
  // Like a CAN interface that is down (bind succeeds, the first read fails with ENETDOWN): a
  // listener that takes each connection and closes it at once. The runner must keep doubling
  // its wait (100, 200, 400, 800 ms ...), not start again at 100 ms after each good open.
  const std::string path =
      (std::filesystem::temp_directory_path() / ("liftd-can-reopen-" + std::to_string(::getpid())))
          .string();
  auto listener = listen_unix(path);
  ASSERT_TRUE(listener) << listener.error().what;
  std::atomic<bool> done{false};
  std::thread closer([&] {
    while (!done) {
      pollfd p{listener.value(), POLLIN, 0};
      if (::poll(&p, 1, 10) == 1) ::close(::accept4(listener.value(), nullptr, nullptr, 0));
    }
  });
  CountingEngine engine;
  rt::CanRunnerConfig config;
  config.endpoint = "unix:" + path;
  config.rt.priority = 0;
  config.rt.lock_memory = false;
  rt::CanRunner runner(config, engine);
  ASSERT_EQ(runner.start(), 0);
  // Wait for the failures a fixed 100 ms retry would reach in about 1 s, or 2.5 s.
  const MonoTime until = mono_now() + 2500ms;
  while (mono_now() < until && engine.failed < 10) std::this_thread::sleep_for(10ms);
  runner.stop();
  done = true;
  closer.join();
  ::close(listener.value());
  ::unlink(path.c_str());
  // In 2.5 s with doubling: opens at about 0, 0.1, 0.3, 0.7 and 1.5 s (a loaded machine only
  // makes it fewer). Without doubling: 10 failures in about 1 s.
  EXPECT_GE(engine.failed, 2);
  EXPECT_LE(engine.failed, 6) << "the reopen backoff started over after each open";
}

}  // namespace
}  // namespace liftd::can
