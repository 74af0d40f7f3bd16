// The `sim` actions only the simulated SCH001 card and hydraulic unit take, and the shared
// actions its simulator takes (general_fault is the card's ERR there, not_ready its RDY = 0).
#pragma once

#include <array>
#include <cstdint>
#include <string_view>

#include "api/sim.hpp"

namespace liftd::daemon {

/// The simulated SCH001 card's own `sim` actions.
enum class Sch001SimAction : std::uint8_t {
  OilTemperature,  ///< the card's T1 relay on/off (oil temperature)
  Pressure,        ///< the card's P1 relay on/off (minimum/maximum pressure)
  Overpressure,    ///< the card's P2 relay on/off (overpressure)
  CardSilence,     ///< the card stops sending (on) or sends again (off)
  BusOff,          ///< one CAN bus-off error frame reaches the controller
  ColdOil,         ///< cold oil: every speed of the unit is lower (on/off)
  Sink,            ///< the car at rest sinks 2 mm/s (leaking valve, cooling oil) on/off
  CardReconnect,   ///< the card's CAN connection drops once; the controller reopens it
};
/// Wire names of Sch001SimAction, in enum order.
inline constexpr std::array<std::string_view, 8> kSch001SimActions = {
    "oil_temperature", "pressure", "overpressure", "card_silence",
    "bus_off",         "cold_oil", "sink",         "card_reconnect"};

/// The SCH001 kind's part of `sim`, for the registry of drive kinds.
extern const api::KindSimActions kSch001SimActionTable;

}  // namespace liftd::daemon
