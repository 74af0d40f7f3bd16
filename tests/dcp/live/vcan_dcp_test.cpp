// A DCP lift on the vcan: its car position from a CAN absolute encoder (frames from this test).
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
#include "e2e/vcan_harness.hpp"
#include "io/pty.hpp"

namespace liftd::e2e {
namespace {

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
