// libFuzzer target: arbitrary master frames (and so arbitrary channel bytes) into the simulated
// drive, with time advancing by a fuzzed step; replies must always be well formed.
#include <cstdlib>

#include "dcp/sim/drive_sim.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace liftd;
  dcp::sim::DriveConfig cfg;
  cfg.protocol = (size > 0 && (data[0] & 1) != 0) ? dcp::Protocol::Dcp3 : dcp::Protocol::Dcp4;
  cfg.require_init = size > 0 && (data[0] & 2) != 0;
  cfg.fast_start_limit_ms = 1000;
  MonoTime now{};
  dcp::sim::DriveSim drive(cfg, now);
  std::size_t i = 1;
  while (i + 7 <= size) {
    // One step byte (0..255 ms), then 6 frame bytes; every 8th frame gets a valid checksum
    // forced so the engine sees plenty of good frames too.
    now += std::chrono::milliseconds(data[i]);
    dcp::FrameBytes f{};
    for (std::size_t k = 0; k < 6; ++k) f[k] = data[i + 1 + k];
    if ((data[i] & 0x07) != 0) {
      f[5] = static_cast<std::uint8_t>(f[0] ^ f[1] ^ f[2] ^ f[3] ^ f[4]);
    }
    const dcp::sim::Reply r = drive.on_master_frame(f, now);
    if (r.size != 0 && r.size != 6 && r.size != 3) abort();
    if (r.size == 6 && !dcp::decode_slave(std::span<const std::uint8_t, 6>(r.bytes.data(), 6))) {
      abort();
    }
    const double pos = drive.position_mm();
    if (!(pos > -1e9 && pos < 1e9)) abort();  // finite and bounded
    i += 7;
  }
  drive.advance(now + std::chrono::seconds(5));
  dcp::sim::SimEvent e;
  while (drive.pop_event(e)) {
  }
  return 0;
}
