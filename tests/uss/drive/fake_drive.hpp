// A small USS drive for the tests, written from the drive-profile sentences of USS C 5.2.1 (not
// from the master's code), and a car hanging on it. One call to receive() is one telegram with
// STW and HSW; zsw() / actual() are what the drive answers to it.
#pragma once

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <vector>

#include "common/mono_time.hpp"
#include "uss/pzd.hpp"

namespace liftd::uss::test {

class FakeDrive {
 public:
  double ramp_percent_per_s = 100.0;        ///< the drive's ramp generator (HLG)
  double quick_stop_percent_per_s = 400.0;  ///< OFF3: "schnellstmögliches Herunterfahren"
  bool plc_control = true;                  ///< ZSW bit 9 "Führung gefordert"
  bool never_enables = false;               ///< a drive that stays "ready" (supervision tests)
  std::vector<std::uint16_t> stw_log;       ///< every STW received, in order

  /// One telegram from the master, `dt` after the previous one.
  void receive(std::uint16_t stw, double setpoint_percent, MonoTime dt) {
    stw_log.push_back(stw);
    const double dt_s = std::chrono::duration<double>(dt).count();
    // Table 5.4 bit 10: "0 Keine Führung: Prozeßdaten ungültig, d. h., die alten Prozeßdaten
    // bleiben erhalten".
    if ((stw & stw::kControlByPlc) == 0) {
      stw = stw_;
      setpoint_percent = setpoint_;
    }
    // Table 5.3 bit 7: "Sammelmeldung wird bei positiver Flanke quittiert".
    const bool ack_edge =
        (stw & stw::kFaultAcknowledge) != 0 && (stw_ & stw::kFaultAcknowledge) == 0;
    stw_ = stw;
    setpoint_ = setpoint_percent;
    if (state_ == S::Fault) {
      // Table 5.5 bit 3: "geht nach Quittierung und erfolgreicher Fehlerbehebung in
      // Einschaltsperre".
      speed_ = 0.0;
      if (ack_edge && !fault_cause_) state_ = S::Inhibit;
      return;
    }
    if ((stw & stw::kNoOff2) == 0) {
      // Table 5.2 bit 1 = 0, OFF2: "Impulse sperren ... in Einschaltsperre; Motor trudelt aus".
      state_ = S::Inhibit;
      speed_ = 0.0;
      return;
    }
    if ((stw & stw::kNoOff3) == 0) {
      // Table 5.2 bit 2 = 0, OFF3: "Schnellhalt ... bei n/f = 0 ... in Einschaltsperre".
      if (state_ == S::Operation) {
        speed_ = towards(speed_, 0.0, quick_stop_percent_per_s * dt_s);
        if (speed_ == 0.0) state_ = S::Inhibit;
      } else {
        state_ = S::Inhibit;
      }
      return;
    }
    const bool on = (stw & stw::kOn) != 0;
    switch (state_) {
      case S::Fault:
        break;
      case S::Inhibit:
        // Table 5.5 bit 6: "Wiedereinschalten nur durch AUS 1 und anschließendem EIN".
        if (!on) state_ = S::ReadyToSwitchOn;
        break;
      case S::ReadyToSwitchOn:
        if (on) state_ = S::Ready;  // table 5.2 bit 0: "Betriebsbereit"
        break;
      case S::Ready:
        if (!on) {
          state_ = S::ReadyToSwitchOn;
        } else if ((stw & stw::kEnableOperation) != 0 && !never_enables) {
          state_ = S::Operation;  // table 5.3 bit 3: "Betrieb freigeben"
        }
        break;
      case S::Operation:
        if (!on) {
          // Table 5.2 bit 0 = 0, OFF1: "Herunterfahren an der Hochlauframpe ... bei n/f = 0
          // und I = 0 Spannungsfreischaltung" -> ready to switch on.
          speed_ = towards(speed_, 0.0, ramp_percent_per_s * dt_s);
          if (speed_ == 0.0) state_ = S::ReadyToSwitchOn;
        } else if ((stw & stw::kEnableOperation) == 0) {
          state_ = S::Ready;  // bit 3 = 0: "Antrieb trudelt aus"
          speed_ = 0.0;
        } else if ((stw & stw::kRampGeneratorEnable) == 0) {
          speed_ = 0.0;  // bit 4 = 0: "Ausgang HLG wird auf 0 gesetzt"
        } else if ((stw & stw::kRampStart) != 0) {
          // Bit 6 = 0: "Angewählter Wert am Eingang des HLG wird zu 0 gesetzt"; bit 5 = 0
          // freezes the ramp.
          const double target = (stw & stw::kSetpointEnable) != 0 ? setpoint_percent : 0.0;
          speed_ = towards(speed_, target, ramp_percent_per_s * dt_s);
        }
        break;
    }
  }

  /// The status word the drive answers with (tables 5.5, 5.6).
  std::uint16_t zsw() const {
    std::uint16_t z = plc_control ? zsw::kPlcControlRequested : 0;
    switch (state_) {
      case S::Fault:
        z |= zsw::kFault;
        break;
      case S::Inhibit:
        z |= zsw::kSwitchOnInhibit;
        break;
      case S::ReadyToSwitchOn:
        z |= zsw::kReadyToSwitchOn;
        break;
      case S::Ready:
        z |= zsw::kReadyToSwitchOn | zsw::kReady;
        break;
      case S::Operation:
        z |= zsw::kReadyToSwitchOn | zsw::kReady | zsw::kOperationEnabled;
        break;
    }
    // Bits 4, 5: "0 = AUS 2 / AUS 3 Befehl steht an".
    if ((stw_ & stw::kNoOff2) != 0) z |= zsw::kNoOff2;
    if ((stw_ & stw::kNoOff3) != 0) z |= zsw::kNoOff3;
    if (warning) z |= zsw::kWarning;
    return z;
  }
  /// The main actual value HIW: the speed in percent.
  double actual() const { return speed_; }

  /// The drive trips (pulses off, ZSW bit 3) and the cause stays until clear_fault_cause().
  void trip() {
    state_ = S::Fault;
    fault_cause_ = true;
  }
  void clear_fault_cause() { fault_cause_ = false; }
  bool warning = false;

 private:
  enum class S { Inhibit, ReadyToSwitchOn, Ready, Operation, Fault };
  static double towards(double v, double target, double step) {
    if (v < target) return std::min(target, v + step);
    return std::max(target, v - step);
  }
  S state_ = S::Inhibit;  // after power-up a drive waits in switch-on inhibit
  std::uint16_t stw_ = 0;
  double setpoint_ = 0.0;
  double speed_ = 0.0;
  bool fault_cause_ = false;
};

/// The car: moves at the drive's speed while the brake is open (100 % = rated_mm_per_s).
struct Car {
  double position_mm = 0.0;
  double rated_mm_per_s = 1000.0;
  void advance(double actual_percent, bool brake_open, MonoTime dt) {
    if (!brake_open) return;  // the brake holds the car
    position_mm +=
        actual_percent / 100.0 * rated_mm_per_s * std::chrono::duration<double>(dt).count();
  }
};

}  // namespace liftd::uss::test
