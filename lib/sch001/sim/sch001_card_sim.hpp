// The SCH001 card's side of the CAN link with a hydraulic car behind it, written from the card's
// document ("CAN Kommunikation mit Steuerung"), not from our controller: it sends its status
// frame every 100 ms (3b), takes the controller's 0x68 answers (3c) and the acknowledgements of
// its timeout commands (3f), moves the car by pump and valves, and reports as a violation what
// the document forbids the controller. Sans-I/O: frames and time come in, frames go out.
//
// The car: up by the pump (only while the controller says the motors run, SFY), down by the
// valve; fast speed HSP (down: HSP when P435 = 0, SP3 when P453 = 1), V3 = HSP + SP1,
// V4 = HSP + SP2, inspection MSP, otherwise the slow (levelling) speed; the valves ramp the speed
// (soft start and stop); every speed is lower while the oil is cold; a leaking car sinks at rest.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "can/frame.hpp"
#include "common/mono_time.hpp"
#include "sch001/protocol.hpp"

namespace liftd::sch001::sim {

/// The simulated card and hydraulic unit.
struct CardSimConfig {
  sch001::Ids ids;                ///< the card's identifiers (P479 / P480)
  bool fast_down_sp3 = false;     ///< P453 = 1: SP3 is fast down (else P435 = 0: HSP)
  double fast_mps = 0.50;         ///< HSP
  double v3_mps = 0.63;           ///< HSP + SP1
  double v4_mps = 0.80;           ///< HSP + SP2
  double inspection_mps = 0.30;   ///< MSP
  double slow_mps = 0.05;         ///< levelling speed: direction signal alone
  double ramp_mps2 = 0.5;         ///< the valves' soft start and stop
  double cold_factor = 0.8;       ///< speeds are this much of nominal while the oil is cold
  double bottom_mm = -200.0;      ///< buffer at the pit: the car cannot go lower
  double top_mm = 20000.0;        ///< the cylinder's end: the car cannot go higher
  double start_mm = 0.0;          ///< where the car stands at power-on
  std::uint32_t period_ms = 100;  ///< the status frame's period (3b)
};

/// Something the controller did that the document forbids.
struct CardViolation {
  MonoTime at{};
  std::string rule;  ///< the document's rule, quoted by chapter
};

/// The card's view of the link, for tests and `sim`.
struct CardSimState {
  sch001::CardStatus status;           ///< what the card reports
  sch001::CommandBits commands;        ///< the last command byte received
  std::uint8_t current_floor = 0;      ///< the last current floor received
  std::uint8_t destination_floor = 0;  ///< the last destination floor received
  double position_mm = 0;
  double velocity_mps = 0;  ///< + up
  bool silent = false;      ///< sending no status frames, valves closed (injected: down)
  bool cold_oil = false;
  double sink_mm_per_s = 0;  ///< leakage while at rest
  std::uint64_t status_frames = 0;
  std::uint64_t answers = 0;
  std::uint64_t violations = 0;
};

class Sch001CardSim {
 public:
  Sch001CardSim(const CardSimConfig& config, MonoTime now) noexcept;

  /// A frame from the bus.
  void on_frame(const can::Frame& frame, MonoTime now);
  /// Moves the car up to `now` and returns the frame the card sends now, if one is due.
  std::optional<can::Frame> poll(MonoTime now);
  /// Sends the timeout command at the next status slot (0x52 enable, 0x5A disable; 3f).
  void send_timeout_command(bool enable) noexcept { pending_timeout_ = enable; }

  // --- injection ---
  void set_err(bool on) noexcept { state_.status.err = on; }
  void set_rdy(bool on) noexcept { state_.status.rdy = on; }
  void set_t1(bool on) noexcept { state_.status.t1 = on; }
  void set_p1(bool on) noexcept { state_.status.p1 = on; }
  void set_p2(bool on) noexcept { state_.status.p2 = on; }
  void set_silent(bool on) noexcept { state_.silent = on; }
  /// The connection to the controller went away (or none was there when poll() sent): a status
  /// frame that never reached a controller is owed no answer (3c).
  void connection_lost() noexcept { answer_owed_ = false; }
  void set_cold_oil(bool on) noexcept { state_.cold_oil = on; }
  void set_sink(double mm_per_s) noexcept { state_.sink_mm_per_s = mm_per_s; }
  /// Moves the stationary car (a drift); ignored while it moves.
  void drift(double mm) noexcept;

  const CardSimState& state() const noexcept { return state_; }
  /// Violations since the last call.
  std::vector<CardViolation> take_violations();
  /// The timeout the card asked for is acknowledged (3f).
  bool timeout_ack_seen() const noexcept { return ack_seen_; }

 private:
  void advance(MonoTime now) noexcept;
  double target_speed() const noexcept;
  void violation(MonoTime now, std::string rule);

  CardSimConfig config_;
  CardSimState state_;
  MonoTime last_advance_;
  MonoTime next_status_;
  bool answer_owed_ = false;          ///< a status frame went out and its answer has not come
  sch001::CardStatus status_sent_{};  ///< the status the owed answer must obey
  std::optional<bool> pending_timeout_;
  std::optional<bool> ack_owed_;  ///< the acknowledgement the card waits for
  bool ack_seen_ = false;
  std::vector<CardViolation> violations_;
};

}  // namespace liftd::sch001::sim
