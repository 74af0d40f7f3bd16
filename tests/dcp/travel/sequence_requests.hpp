// The travel requests and the DCP3 shaft lift the sequence tests (sequence*_test.cpp) share.
#pragma once

#include <cstdint>

#include "fake_drive.hpp"

namespace liftd::travel::test {
namespace {

using dcp::Protocol;
using dcp::Speed;
using Type = Event::Type;

// Legend for the command bytes below (DCP 3.1, 3.5): B0 0x01 enable, B1 0x02 travel, B2 0x04
// stop switch, B3 0x08 speed in data bytes, B4 0x10 direction down.
//   0x09 speed message up, 0x19 speed message down, 0x05 B2+B0 (remaining distance in DCP4),
//   0x07 B2+B1+B0 travel, 0x03 B1+B0 relevelling, 0x01 B0 only (stop), 0x0D / 0x0F speed after
//   fast start (DCP4 / DCP3), 0x00 idle.

inline TravelRequest dcp4_request(std::int64_t target_mm, Speed speed = Speed::V4) {
  TravelRequest request;
  request.kind = TravelKind::Dcp4Distance;
  request.speed = speed;
  request.target_mm = target_mm;
  return request;
}

inline TravelRequest dcp3_request(Speed speed, Direction direction, std::int64_t target_mm = 0) {
  TravelRequest request;
  request.kind = speed == Speed::V0 ? TravelKind::Dcp3Crawl : TravelKind::Dcp3Speed;
  request.speed = speed;
  request.direction = direction;
  request.target_mm = target_mm;
  return request;
}

/// The DCP3 lift the figures of DCP chapter 10 draw: deceleration points and the level from the
/// shaft's signals, all seven travelling speeds, relevelling with electric stop (DCP 9.2.3.2,
/// figure 9.6). A default TravelConfig is the daemon's default lift (by position, two speeds),
/// so these tests say which lift they run.
inline TravelConfig dcp3_shaft() {
  TravelConfig config;
  config.dcp3_reference = Dcp3Reference::ShaftSignals;
  config.dcp3_speed_count = 7;
  config.relevel_electric_stop = true;
  return config;
}

}  // namespace
}  // namespace liftd::travel::test
