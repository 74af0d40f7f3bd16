// The simulated USS slave as a drive: the process data, the drive-profile state machine seen
// from the drive (USS C 5.2.1), the motor and lift-car model and the status words it sends.
#include "uss/sim/uss_slave_sim.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "uss/pzd.hpp"
#include "uss/sim/uss_slave_sim_detail.hpp"

namespace liftd::uss::sim {

using namespace detail;

namespace {

double seconds(std::chrono::nanoseconds d) {
  return std::chrono::duration<double>(d).count();
}

}  // namespace

// ---- process data and the drive profile (C 5.2.1) ----

void UssSlaveSim::apply_pzd(std::span<const std::uint16_t> pzd, MonoTime at) noexcept {
  if (local_ || pzd.empty()) return;
  // C 5.2.1 Tabelle 5.4 bit 10: "0 Keine Führung: Prozeßdaten ungültig, d. h., die 'alten'
  // Prozeßdaten bleiben erhalten".
  if ((pzd[0] & uss::stw::kControlByPlc) == 0) return;
  std::copy(pzd.begin(), pzd.end(), pzd_in_.begin());
  apply_stw(pzd[0], at);
}

void UssSlaveSim::enter(UssDriveState s, MonoTime at) noexcept {
  if (s == UssDriveState::Ready && state_ != UssDriveState::Ready) ready_since_ = at;
  state_ = s;
}

void UssSlaveSim::apply_stw(std::uint16_t stw, MonoTime at) noexcept {
  namespace b = uss::stw;
  const std::uint16_t previous = stw_;
  stw_ = stw;
  const bool on = (stw & b::kOn) != 0;
  const bool no_off2 = (stw & b::kNoOff2) != 0;
  const bool no_off3 = (stw & b::kNoOff3) != 0;
  const bool enable = (stw & b::kEnableOperation) != 0;
  // Tabelle 5.3 bit 7: "Sammelmeldung wird bei positiver Flanke quittiert; Umrichter befindet
  // sich bis Fehler erfolgreich behoben wurde, in 'Störung' geht anschließend in
  // 'Einschaltsperre'".
  if (state_ == UssDriveState::Fault) {
    const bool rising = (stw & b::kFaultAcknowledge) != 0 && (previous & b::kFaultAcknowledge) == 0;
    if (rising && !fault_injected_ && !telegram_failed_) {
      fault_number_ = 0;
      enter(UssDriveState::SwitchOnInhibit, at);
    }
    return;
  }
  // Tabelle 5.2 bit 1: OFF2 "Spannungsfreischaltung ... und in Einschaltsperre; Motor trudelt
  // aus" - from every state, at once.
  if (!no_off2) {
    enter(UssDriveState::SwitchOnInhibit, at);
    return;
  }
  // Bit 2: OFF3 "Schnellhalt ... bei n/f = 0 ... in Einschaltsperre".
  if (!no_off3) {
    if (state_ == UssDriveState::OperationEnabled || state_ == UssDriveState::RampStop) {
      enter(UssDriveState::QuickStop, at);
      if (speed_mps_ == 0.0) enter(UssDriveState::SwitchOnInhibit, at);
    } else if (state_ != UssDriveState::QuickStop) {
      enter(UssDriveState::SwitchOnInhibit, at);
    }
    return;
  }
  switch (state_) {
    case UssDriveState::SwitchOnInhibit:
      // Tabelle 5.5 bit 6: "Wiedereinschalten nur durch 'AUS 1' und anschließendem 'EIN'".
      if (!on) {
        enter(UssDriveState::ReadyToSwitchOn, at);
      } else if (stw != previous) {
        violation(at, kRuleSwitchOn);
      }
      break;
    case UssDriveState::ReadyToSwitchOn:
      if (on) {
        enter(UssDriveState::Ready, at);
        if (enable) enter(UssDriveState::OperationEnabled, at);
      }
      break;
    case UssDriveState::Ready:
      if (!on) {
        enter(UssDriveState::ReadyToSwitchOn, at);
      } else if (enable) {
        enter(UssDriveState::OperationEnabled, at);
      }
      break;
    case UssDriveState::OperationEnabled:
      // Bit 0 = 0: OFF1 "Herunterfahren an der Hochlauframpe"; bit 3 = 0: "Antrieb trudelt
      // aus ... und geht in Zustand 'Betriebsbereit'".
      if (!on) {
        enter(UssDriveState::RampStop, at);
      } else if (!enable) {
        enter(UssDriveState::Ready, at);
      }
      break;
    case UssDriveState::RampStop:
      if (!enable) {
        enter(on ? UssDriveState::Ready : UssDriveState::ReadyToSwitchOn, at);
      } else if (on) {
        enter(UssDriveState::OperationEnabled, at);  // ON again during the ramp: carry on
      }
      break;
    case UssDriveState::QuickStop:  // runs to standstill whatever comes
    case UssDriveState::Fault:
      break;
  }
  // A stop at standstill is over at once ("bei n/f = 0").
  if (speed_mps_ == 0.0 && state_ == UssDriveState::RampStop) {
    enter(UssDriveState::ReadyToSwitchOn, at);
  }
  if (speed_mps_ == 0.0 && state_ == UssDriveState::QuickStop) {
    enter(UssDriveState::SwitchOnInhibit, at);
  }
}

void UssSlaveSim::set_drive_fault(bool on) noexcept {
  fault_injected_ = on;
  if (on) {
    fault_number_ = 1;
    enter(UssDriveState::Fault, last_advance_);
  }
}

void UssSlaveSim::advance(MonoTime now) noexcept {
  if (now <= last_advance_) return;
  const double dt = seconds(now - last_advance_);
  last_advance_ = now;
  // C 3.1 Telegrammausfallzeit: "Der Slave beginnt ... erst dann mit der Zeitüberwachung,
  // nachdem das erste fehlerfreie Auftragstelegramm empfangen wurde."
  if (config_.telegram_timeout.count() > 0 && have_good_ && !telegram_failed_ &&
      now - last_good_ > config_.telegram_timeout) {
    telegram_failed_ = true;
    fault_number_ = 2;
    ++stats_.telegram_timeouts;
    receiver_.count_reply_timeout();  // A 5.2.3 error word bit 7 (slave: monitoring time)
    enter(UssDriveState::Fault, now);
  }
  // C 5.2.1 Tabelle 5.2 bit 0: "erfolgt innerhalb einer parametrierbaren Wartezeit (t_wart)
  // kein Weiterschalten, wird in den Zustand 'Einschaltsperre' geschaltet".
  if (state_ == UssDriveState::Ready && config_.ready_timeout.count() > 0 &&
      now - ready_since_ >= config_.ready_timeout) {
    enter(UssDriveState::SwitchOnInhibit, now);
  }

  const UssCarConfig& car = config_.car;
  double target = 0.0;
  double rate = car.brake_mps2;  // no pulses: the brake holds the car
  bool hold = false;
  switch (state_) {
    case UssDriveState::OperationEnabled:
      if ((stw_ & uss::stw::kRampGeneratorEnable) == 0) {
        rate = car.quick_stop_mps2;  // bit 4 = 0: "Ausgang HLG wird auf 0 gesetzt"
      } else if ((stw_ & uss::stw::kRampStart) == 0) {
        hold = true;  // bit 5 = 0: "Einfrieren des aktuellen vom HLG vorgegebenen Sollwertes"
      } else {
        // bit 6 = 0: "Angewählter Wert am Eingang des HLG wird zu 0 gesetzt"
        if ((stw_ & uss::stw::kSetpointEnable) != 0) {
          target = static_cast<std::int16_t>(pzd_in_[1]) / 16384.0 * car.nominal_mps;
        }
        rate = car.accel_mps2;
      }
      if (config_.pzd_words < 2) target = 0.0;
      break;
    case UssDriveState::RampStop:
      rate = car.accel_mps2;
      break;
    case UssDriveState::QuickStop:
      rate = car.quick_stop_mps2;
      break;
    default:
      break;
  }
  // Constant acceleration up to the target, then constant speed: exact for any step size.
  const double v0 = speed_mps_;
  double distance_m = v0 * dt;
  if (!hold) {
    if (rate <= 0.0) {
      speed_mps_ = target;
      distance_m = 0.0;  // the brake (or the drive) stops the car at once
      if (target != 0.0) distance_m = target * dt;
    } else {
      const double reach = std::abs(target - v0) / rate;  // time to the target
      if (reach >= dt) {
        speed_mps_ = v0 + (target > v0 ? rate : -rate) * dt;
        distance_m = (v0 + speed_mps_) / 2.0 * dt;
      } else {
        speed_mps_ = target;
        distance_m = (v0 + target) / 2.0 * reach + target * (dt - reach);
      }
    }
  }
  position_mm_ += distance_m * 1000.0;
  if (position_mm_ <= car.bottom_mm) {
    position_mm_ = car.bottom_mm;
    speed_mps_ = std::max(speed_mps_, 0.0);
  }
  if (position_mm_ >= car.top_mm) {
    position_mm_ = car.top_mm;
    speed_mps_ = std::min(speed_mps_, 0.0);
  }
  if (speed_mps_ == 0.0) {
    if (state_ == UssDriveState::RampStop) enter(UssDriveState::ReadyToSwitchOn, now);
    if (state_ == UssDriveState::QuickStop) enter(UssDriveState::SwitchOnInhibit, now);
  }
  refresh_live();
}

std::uint16_t UssSlaveSim::make_zsw() const noexcept {
  namespace z = uss::zsw;
  std::uint16_t w = 0;
  switch (state_) {
    case UssDriveState::OperationEnabled:
    case UssDriveState::RampStop:
    case UssDriveState::QuickStop:
      w |= z::kOperationEnabled;  // pulses on while the drive brakes the car itself
      [[fallthrough]];
    case UssDriveState::Ready:
      w |= z::kReady;
      [[fallthrough]];
    case UssDriveState::ReadyToSwitchOn:
      w |= z::kReadyToSwitchOn;
      break;
    case UssDriveState::SwitchOnInhibit:
      w |= z::kSwitchOnInhibit;
      break;
    case UssDriveState::Fault:
      w |= z::kFault;
      break;
  }
  if ((stw_ & uss::stw::kNoOff2) != 0) w |= z::kNoOff2;  // Tabelle 5.5 bit 4: "AUS 2 steht an"
  if ((stw_ & uss::stw::kNoOff3) != 0) w |= z::kNoOff3;
  if (warning_) w |= z::kWarning;
  const UssCarConfig& car = config_.car;
  double setpoint = 0.0;
  if (state_ == UssDriveState::OperationEnabled && config_.pzd_words >= 2 &&
      (stw_ & uss::stw::kSetpointEnable) != 0 && (stw_ & uss::stw::kRampGeneratorEnable) != 0) {
    setpoint = static_cast<std::int16_t>(pzd_in_[1]) / 16384.0 * car.nominal_mps;
  }
  // Tabelle 5.6 bit 8: "Istwert innerhalb eines Toleranzbandes".
  if (std::abs(speed_mps_ - setpoint) <= car.tolerance_percent / 100.0 * car.nominal_mps) {
    w |= z::kSetpointReached;
  }
  if (!local_) w |= z::kPlcControlRequested;  // bit 9: "Führung gefordert"
  // Bit 10: "Istwert >= Vergleichswert (Sollwert), der über Parameternummer einstellbar ist".
  const auto cmp = parameter(kPnuComparison);
  if (cmp && std::abs(speed_mps_) >= *cmp / 16384.0 * car.nominal_mps) w |= z::kFrequencyReached;
  return w;
}

std::int16_t UssSlaveSim::make_hiw() const noexcept {
  const double raw = std::round(speed_mps_ / config_.car.nominal_mps * 16384.0);
  return static_cast<std::int16_t>(std::clamp(raw, -32768.0, 32767.0));
}

void UssSlaveSim::refresh_live() noexcept {
  if (const Param* p = find(kPnuActualSpeed)) {
    values_[p->value_at] = static_cast<std::uint16_t>(make_hiw());
  }
  if (const Param* p = find(kPnuFault)) values_[p->value_at] = fault_number_;
}

void UssSlaveSim::move_car(double mm) noexcept {
  if (speed_mps_ == 0.0) position_mm_ += mm;
}

int UssSlaveSim::floor_at(double tolerance_mm) const noexcept {
  const auto& floors = config_.car.floors_mm;
  for (std::size_t i = 0; i < floors.size(); ++i) {
    if (std::abs(position_mm_ - floors[i]) <= tolerance_mm) return static_cast<int>(i);
  }
  return -1;
}

UssDriveView UssSlaveSim::drive() const noexcept {
  UssDriveView v;
  v.state = state_;
  v.stw = stw_;
  v.hsw = static_cast<std::int16_t>(pzd_in_[1]);
  v.zsw = make_zsw();
  v.hiw = make_hiw();
  v.position_mm = position_mm_;
  v.velocity_mps = speed_mps_;
  v.brake_open = state_ == UssDriveState::OperationEnabled || state_ == UssDriveState::RampStop ||
                 state_ == UssDriveState::QuickStop;
  v.fault_number = fault_number_;
  v.fault_cause = fault_injected_ || telegram_failed_;
  return v;
}

}  // namespace liftd::uss::sim
