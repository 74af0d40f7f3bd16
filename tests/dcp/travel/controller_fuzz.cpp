// Fuzzes the travel controller: the input bytes choose requests, stops, extensions and faults
// cycle by cycle against the scripted drive. Traps if a frame carries B0/B1/B2 while a gating
// condition forbids it, or if a DCP4 distance frame's data word disagrees with the position.
#include <cstddef>
#include <cstdint>

#include "fake_drive.hpp"

using namespace liftd;
using namespace liftd::travel;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 2) return 0;
  const dcp::Protocol protocol = (data[0] & 1) != 0 ? dcp::Protocol::Dcp4 : dcp::Protocol::Dcp3;
  TravelConfig config;
  config.use_i7 = (data[0] & 2) != 0;
  config.dcp3_reference =
      (data[0] & 4) != 0 ? Dcp3Reference::Position : Dcp3Reference::ShaftSignals;
  config.dcp3_decel_distance_mm.fill(1500);
  travel::test::Rig rig(protocol, config);
  rig.with_position = protocol == dcp::Protocol::Dcp4 || (data[0] & 8) != 0;
  rig.controller.set_home_level(0);
  bool previous_enable = false;
  for (std::size_t i = 1; i < size; ++i) {
    const std::uint8_t b = data[i];
    auto& in = rig.input;
    switch (b >> 4) {
      case 0: {
        TravelRequest request;
        request.kind = static_cast<TravelKind>(1 + (b & 7) % 7);
        request.speed = dcp::kAllSpeeds[(b >> 1) % dcp::kAllSpeeds.size()];
        request.target_mm = static_cast<std::int64_t>(b & 0x0F) * 1500 - 1500;
        request.direction = (b & 8) != 0 ? Direction::Down : Direction::Up;
        request.fast_start = (b & 1) != 0;
        static_cast<void>(rig.controller.start(request));
        break;
      }
      case 1:
        rig.controller.stop();
        break;
      case 2:
        rig.controller.fast_stop();
        break;
      case 3:
        static_cast<void>(rig.controller.extend_target(static_cast<std::int64_t>(b & 0x0F) * 2000));
        break;
      case 4:
        in.link_up = !in.link_up;
        break;
      case 5:
        in.handshake_done = !in.handshake_done;
        break;
      case 6:
        in.inputs.valid = !in.inputs.valid;
        break;
      case 7:
        in.inputs.safety_chain_closed = !in.inputs.safety_chain_closed;
        break;
      case 8:
        in.inputs.doors_locked = !in.inputs.doors_locked;
        break;
      case 9:
        in.inputs.door_reversal = !in.inputs.door_reversal;
        break;
      case 10:
        rig.drive.status().general_fault = !rig.drive.status().general_fault;
        break;
      case 11:
        rig.drive.status().advance_warning = !rig.drive.status().advance_warning;
        break;
      case 12:
        rig.drive.status().ready = !rig.drive.status().ready;
        break;
      case 13:
        if ((b & 1) != 0) in.inputs.inspection = !in.inputs.inspection;
        if ((b & 2) != 0) in.inputs.button_up = !in.inputs.button_up;
        if ((b & 4) != 0) in.inputs.button_down = !in.inputs.button_down;
        if ((b & 8) != 0) in.inputs.end_zone_top = !in.inputs.end_zone_top;
        break;
      case 14:
        if ((b & 1) != 0) in.inputs.decel_up[3] = !in.inputs.decel_up[3];
        if ((b & 2) != 0) in.inputs.level_zone = !in.inputs.level_zone;
        if ((b & 4) != 0) in.inputs.door_zone_bridge = !in.inputs.door_zone_bridge;
        if ((b & 8) != 0 && protocol == dcp::Protocol::Dcp4) rig.with_position = !rig.with_position;
        break;
      default:
        break;
    }
    for (int n = 0; n <= (b & 0x0F); ++n) {  // a few cycles per byte
      const CycleOutput out = rig.cycle();
      const bool motion = (out.command & 0x07) != 0;
      if (!motion) {
        previous_enable = false;
        continue;
      }
      const auto& status = rig.records.back().status;
      const bool button_mode = in.inputs.inspection || in.inputs.recall;
      const bool hold_frame =
          (out.command & 0x02) == 0 && ((out.command & 0x04) == 0 || out.data_word == 0);
      if (!in.link_up || !in.handshake_done || !in.inputs.valid || !in.inputs.safety_chain_closed ||
          status.general_fault) {
        __builtin_trap();
      }
      if (!(in.inputs.doors_locked || in.inputs.door_zone_bridge || button_mode || hold_frame)) {
        __builtin_trap();
      }
      if (!previous_enable && (!status.ready || status.advance_warning)) __builtin_trap();
      const TravelKind kind = rig.controller.active_kind();
      if ((kind == TravelKind::Dcp4Distance || kind == TravelKind::Dcp4Relevel) &&
          !in.position_mm) {
        __builtin_trap();
      }
      previous_enable = (out.command & 0x01) != 0;
    }
    if (rig.records.size() > 20000) break;
  }
  return 0;
}
