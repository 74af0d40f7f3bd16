#include "sim/sim_io.hpp"

#include <algorithm>
#include <chrono>

namespace liftd::sim {

namespace {

MonoTime ms(std::uint32_t value) noexcept {
  return std::chrono::milliseconds(value);
}

// Time to move the doors over `fraction` of their travel when the whole travel takes `full_ms`.
MonoTime span_of(double fraction, std::uint32_t full_ms) noexcept {
  const double ns = fraction * static_cast<double>(ms(full_ms).count());
  return MonoTime{static_cast<MonoTime::rep>(ns + 0.5)};
}

double fraction_of(MonoTime t, std::uint32_t full_ms) noexcept {
  if (full_ms == 0) return 1.0;
  return static_cast<double>(t.count()) / static_cast<double>(ms(full_ms).count());
}

}  // namespace

const char* to_string(DoorState state) noexcept {
  switch (state) {
    case DoorState::Locked:
      return "locked";
    case DoorState::Closed:
      return "closed";
    case DoorState::Opening:
      return "opening";
    case DoorState::Open:
      return "open";
    case DoorState::Closing:
      return "closing";
  }
  return "?";
}

SimulatedIo::SimulatedIo(const SimIoConfig& config, MonoTime now) noexcept
    : config_(config), now_(now), door_since_(now) {
  inputs_.valid = true;
  if (config_.doors_open_at_start) {
    door_state_ = DoorState::Open;
    opening_ = 1.0;
  }
}

void SimulatedIo::set_door_state(DoorState state, MonoTime now) noexcept {
  door_state_ = state;
  door_since_ = now;
}

void SimulatedIo::advance(MonoTime now) noexcept {
  MonoTime t = now_;
  while (t < now) {
    const MonoTime left = now - t;
    switch (door_state_) {
      case DoorState::Opening: {
        const MonoTime need = span_of(1.0 - opening_, config_.open_ms);
        if (left >= need) {
          t += need;
          opening_ = 1.0;
          set_door_state(DoorState::Open, t);
        } else {
          opening_ = std::min(1.0, opening_ + fraction_of(left, config_.open_ms));
          t = now;
        }
        break;
      }
      case DoorState::Closing: {
        const MonoTime need = span_of(opening_, config_.close_ms);
        if (left >= need) {
          t += need;
          opening_ = 0.0;
          set_door_state(DoorState::Closed, t);
        } else {
          opening_ = std::max(0.0, opening_ - fraction_of(left, config_.close_ms));
          t = now;
        }
        break;
      }
      case DoorState::Closed: {
        const MonoTime lock_at = door_since_ + ms(config_.lock_ms);
        if (now >= lock_at) {
          t = std::max(t, lock_at);
          set_door_state(DoorState::Locked, t);
        } else {
          t = now;
        }
        break;
      }
      case DoorState::Locked:
      case DoorState::Open:
        t = now;
        break;
    }
  }
  // A door that closed exactly at `now` with lock_ms 0 locks at the same instant.
  if (door_state_ == DoorState::Closed && now >= door_since_ + ms(config_.lock_ms))
    set_door_state(DoorState::Locked, door_since_ + ms(config_.lock_ms));
  now_ = std::max(now_, now);
}

lift::Inputs SimulatedIo::inputs() const noexcept {
  lift::Inputs in = inputs_;
  in.safety_chain_closed = !chain_open_;
  in.doors_closed = door_state_ == DoorState::Closed || door_state_ == DoorState::Locked;
  in.doors_locked = door_state_ == DoorState::Locked;
  in.door_reversal = obstructed_ || now_ < reversal_until_;
  if (config_.shaft_top_mm > config_.shaft_bottom_mm) {
    in.end_zone_bottom = car_position_mm_ < config_.shaft_bottom_mm + config_.end_zone_mm;
    in.end_zone_top = car_position_mm_ > config_.shaft_top_mm - config_.end_zone_mm;
  }
  return in;
}

void SimulatedIo::close_doors(MonoTime now) noexcept {
  advance(now);
  open_pending_ = false;
  if (obstructed_) return;
  if (door_state_ == DoorState::Open || door_state_ == DoorState::Opening)
    set_door_state(DoorState::Closing, now_);
}

void SimulatedIo::start_opening(MonoTime now) noexcept {
  if (door_state_ == DoorState::Open || door_state_ == DoorState::Opening) return;
  set_door_state(DoorState::Opening, now);
}

void SimulatedIo::open_doors(MonoTime now) noexcept {
  advance(now);
  if (car_moving_) {
    open_pending_ = true;
    return;
  }
  start_opening(now_);
}

void SimulatedIo::set_car(bool moving, double position_mm, MonoTime now) noexcept {
  advance(now);
  car_position_mm_ = position_mm;
  if (moving && !car_moving_) car_moved_ = true;
  if (!moving && car_moving_ && (open_pending_ || (config_.open_on_arrival && car_moved_))) {
    open_pending_ = false;
    car_moved_ = false;
    start_opening(now_);
  }
  car_moving_ = moving;
}

void SimulatedIo::inject_door_reversal(MonoTime now) noexcept {
  advance(now);
  reversal_until_ = now_ + ms(config_.reversal_ms);
  if (door_state_ == DoorState::Closing || door_state_ == DoorState::Closed) start_opening(now_);
}

void SimulatedIo::set_door_obstructed(bool on, MonoTime now) noexcept {
  advance(now);
  obstructed_ = on;
  if (on && (door_state_ == DoorState::Closing || door_state_ == DoorState::Closed))
    start_opening(now_);
}

}  // namespace liftd::sim
