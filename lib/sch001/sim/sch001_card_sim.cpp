#include "sch001/sim/sch001_card_sim.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <variant>

namespace liftd::sch001::sim {
namespace {

double seconds_between(MonoTime from, MonoTime to) {
  return std::chrono::duration<double>(to - from).count();
}

}  // namespace

Sch001CardSim::Sch001CardSim(const CardSimConfig& config, MonoTime now) noexcept
    : config_(config), last_advance_(now), next_status_(now) {
  state_.status.rdy = true;  // a healthy unit reports ready
  state_.position_mm = config.start_mm;
}

void Sch001CardSim::violation(MonoTime now, std::string rule) {
  ++state_.violations;
  violations_.push_back({now, std::move(rule)});
}

std::vector<CardViolation> Sch001CardSim::take_violations() {
  std::vector<CardViolation> out;
  out.swap(violations_);
  return out;
}

void Sch001CardSim::on_frame(const can::Frame& frame, MonoTime now) {
  advance(now);
  if (frame.id != config_.ids.to_card || frame.length == 0) return;  // not for the card
  const std::uint8_t first = frame.data[0];
  if (first == sch001::kTimeoutEnabledAck || first == sch001::kTimeoutDisabledAck) {
    const bool enabled = first == sch001::kTimeoutEnabledAck;
    if (!ack_owed_ || *ack_owed_ != enabled) {
      violation(now, "3f: an acknowledgement (0x65/0x6B) the card did not ask for");
    }
    ack_owed_.reset();
    ack_seen_ = true;
    return;
  }
  if (first != sch001::kCommandFrame) return;
  if (frame.length != sch001::kCommandFrameLength) {
    violation(now, "3c: the controller answers with 4 bytes");
    return;
  }
  ++state_.answers;
  const auto bits = sch001::CommandBits::from_byte(frame.data[1]);
  const bool travel = bits.any();
  if (!answer_owed_) {
    violation(now, "3c: a 0x68 frame that answers no status frame");
  }
  // 3d: "Die Steuerung darf die Fahrt-Befehle ... übertragen nur wenn die Karte nicht im
  // Fehlerzustand (ERR) ist." 3e: "RDY=0 die Fahrt-Befehle sollen abgetrennt sein."
  if (travel && status_sent_.err) violation(now, "3d: travel commands while the card reports ERR");
  if (travel && !status_sent_.rdy) violation(now, "3e: travel commands while RDY = 0");
  if (bits.up && bits.dw) violation(now, "1.4: UP and DW at once");
  // 1.4: "SP1 (Geschwindigkeit V3 Signale (zusammen mit HSP Signale)", SP2 likewise for V4.
  if ((bits.sp1 || bits.sp2) && !bits.hsp) violation(now, "1.4: SP1/SP2 without HSP");
  answer_owed_ = false;
  state_.commands = bits;
  state_.current_floor = frame.data[2];
  state_.destination_floor = frame.data[3];
}

std::optional<can::Frame> Sch001CardSim::poll(MonoTime now) {
  advance(now);
  if (now < next_status_) return std::nullopt;
  next_status_ += std::chrono::milliseconds(config_.period_ms);
  if (next_status_ <= now) next_status_ = now + std::chrono::milliseconds(config_.period_ms);
  if (state_.silent) {
    answer_owed_ = false;
    return std::nullopt;
  }
  if (answer_owed_) {
    // 3c: "Die Steuerung soll mit einem Datenpaket von 4 Byte antworten" (to every status frame).
    violation(now, "3c: the last status frame got no answer");
  }
  if (pending_timeout_) {
    const std::array<std::uint8_t, 1> bytes = {*pending_timeout_ ? sch001::kEnableTimeout
                                                                 : sch001::kDisableTimeout};
    ack_owed_ = *pending_timeout_;
    pending_timeout_.reset();
    return can::make_frame(config_.ids.from_card, bytes);
  }
  // AVV: the motor start relay, on while the pump runs (single unit, 3b).
  state_.status.avv = state_.commands.up && state_.commands.sfy;
  status_sent_ = state_.status;
  answer_owed_ = true;
  ++state_.status_frames;
  const std::array<std::uint8_t, 2> bytes = {sch001::kStatusFrame, state_.status.to_byte()};
  return can::make_frame(config_.ids.from_card, bytes);
}

double Sch001CardSim::target_speed() const noexcept {
  const sch001::CommandBits& b = state_.commands;
  // Commands are obeyed only as the card allows them (3d, 3e): with ERR or without RDY the card
  // itself closes the valves and stops the pump. A silent card is taken for a card that is down:
  // its outputs, the valves and the pump contactor, drop with it.
  if (state_.status.err || !state_.status.rdy || state_.silent || (b.up && b.dw)) return 0.0;
  double v = 0.0;
  if (b.up && b.sfy) {  // the pump runs only with the motors on
    if (b.msp) {
      v = config_.inspection_mps;
    } else if (b.hsp && b.sp2) {
      v = config_.v4_mps;
    } else if (b.hsp && b.sp1) {
      v = config_.v3_mps;
    } else if (b.hsp) {
      v = config_.fast_mps;
    } else {
      v = config_.slow_mps;
    }
  } else if (b.dw) {
    const bool fast = config_.fast_down_sp3 ? b.sp3 : b.hsp;
    v = -(b.msp ? config_.inspection_mps : fast ? config_.fast_mps : config_.slow_mps);
  }
  return v * (state_.cold_oil ? config_.cold_factor : 1.0);
}

void Sch001CardSim::advance(MonoTime now) noexcept {
  if (now <= last_advance_) return;
  const double dt = seconds_between(last_advance_, now);
  last_advance_ = now;
  const double target = target_speed();
  const double step = config_.ramp_mps2 * dt;
  double& v = state_.velocity_mps;
  v = target > v ? std::min(target, v + step) : std::max(target, v - step);
  double& p = state_.position_mm;
  p += v * dt * 1000.0;
  if (v == 0.0 && target == 0.0) p -= state_.sink_mm_per_s * dt;
  if (p <= config_.bottom_mm) {
    p = config_.bottom_mm;
    v = std::max(v, 0.0);
  }
  if (p >= config_.top_mm) {
    p = config_.top_mm;
    v = std::min(v, 0.0);
  }
}

void Sch001CardSim::drift(double mm) noexcept {
  if (state_.velocity_mps == 0.0) state_.position_mm += mm;
}

}  // namespace liftd::sch001::sim
