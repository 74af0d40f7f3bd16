// A scripted DCP drive for the sequencer tests: it plays the drive's side of DCP chapters 9 to 13
// realistically enough (S1 at the travel command, S6 after pre-fluxing, motion with a constant
// acceleration, deceleration distance, S6 falling at standstill and S1 about 100 ms later) and
// moves the car. Time advances in whole 15 ms cycles; nothing here reads a clock.
#pragma once

#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "dcp/frame.hpp"
#include "dcp/travel/controller.hpp"

namespace liftd::travel::test {

/// DCP 2 / 7.2: one cycle.
inline constexpr double kCycleS = 0.015;
inline constexpr MonoTime kCycle = std::chrono::milliseconds(15);

/// The drive's behaviour figures.
struct FakeDriveConfig {
  double accel_mm_s2 = 800.0;       ///< acceleration and normal deceleration
  double fast_stop_mm_s2 = 2000.0;  ///< DCP 13: separate fast stop ramp
  int preflux_cycles = 4;           ///< S1 on -> S6 on (motor magnetised, DCP 9.1.7)
  int brake_hold_cycles = 7;        ///< S6 off -> S1 off: ~100 ms of torque (DCP 9.1.7)
};

/// Nominal speed in mm/s of each DCP speed in this fake installation.
inline double nominal_speed_mm_s(dcp::Speed speed) {
  switch (speed) {
    case dcp::Speed::V0:
      return 60.0;
    case dcp::Speed::VN:
      return 30.0;
    case dcp::Speed::VF:
      return 0.0;
    case dcp::Speed::VI:
      return 300.0;
    case dcp::Speed::V4:
      return 1600.0;
    case dcp::Speed::V3:
      return 1000.0;
    case dcp::Speed::V2:
      return 800.0;
    case dcp::Speed::V1:
      return 630.0;
    case dcp::Speed::V7:
      return 500.0;
    case dcp::Speed::V6:
      return 400.0;
    case dcp::Speed::V5:
      return 350.0;
  }
  return 0.0;
}

/// The scripted drive.
class FakeDrive {
 public:
  enum class Phase { Idle, Preflux, Moving, Stopping, BrakeClosing };

  explicit FakeDrive(dcp::Protocol protocol, FakeDriveConfig config = {})
      : protocol_(protocol), config_(config) {
    status_.ready = true;
  }

  /// The master frame of this cycle arrives; the drive reacts and the car moves one cycle.
  void on_frame(std::uint8_t command, std::uint16_t data_word) {
    const bool enable = (command & dcp::command_bit::kDriveEnable) != 0;
    const bool travel_bit = (command & dcp::command_bit::kTravel) != 0;
    const bool stop_switch = (command & dcp::command_bit::kStopSwitch) != 0;
    const auto type = dcp::classify_command(command, protocol_);
    if ((command & dcp::command_bit::kDriveEnable) != 0) {
      down_ = (command & dcp::command_bit::kDirectionDown) != 0;
    }
    if (!enable || status_.general_fault) {  // B0 off: motor off, brake drops at once
      v_ = 0.0;
      phase_ = Phase::Idle;
      status_.brake_open = false;
      status_.travel_active = false;
      fast_stop_ = false;
      return;
    }
    if (type == dcp::MessageType::Speed) {
      speed_ = dcp::speed_from_word(data_word);
      status_.accepted = speed_.has_value();
      distance_mode_ = false;
      if (speed_ == dcp::Speed::VF && phase_ == Phase::Idle) {  // DCP 12.1.1: fast start
        begin_preflux();
        holding_ = true;
      }
    } else if (type == dcp::MessageType::SpeedAfterFastStart) {
      const auto speed = dcp::speed_from_word(data_word);
      if (speed == dcp::Speed::VF && phase_ != Phase::Idle) {
        fast_stop_ = true;  // DCP 13.1
      } else if (speed) {
        speed_ = speed;
        holding_ = false;        // DCP 12.1.3
        distance_mode_ = false;  // the next 0101 frame carries the real remaining distance
        target_v_ = 0.0;
      }
    } else if (!fast_stop_) {
      const bool distance_travel = protocol_ == dcp::Protocol::Dcp4 &&
                                   type == dcp::MessageType::DistanceOrDecel && !travel_bit &&
                                   speed_ != dcp::Speed::VI && !after_travel_;
      if (type == dcp::MessageType::Travel) after_travel_ = true;
      if (type == dcp::MessageType::Stop) holding_ = false;  // DCP 12.2.2: end of the hold
      if (distance_travel) {
        distance_mode_ = true;
        remaining_mm_ = data_word;
      }
      if ((travel_bit || stop_switch) && phase_ == Phase::Idle) begin_preflux();
      if (phase_ == Phase::Preflux || phase_ == Phase::Moving) {
        if (distance_mode_) {
          target_v_ = std::min(nominal_speed_mm_s(speed_.value_or(dcp::Speed::V0)),
                               std::sqrt(2.0 * config_.accel_mm_s2 * std::max(0.0, remaining_mm_)));
        } else if (travel_bit) {
          target_v_ = nominal_speed_mm_s(speed_.value_or(dcp::Speed::V0));
          if (speed_ == dcp::Speed::VN && stop_switch)
            target_v_ = nominal_speed_mm_s(dcp::Speed::V0);
        } else if (stop_switch) {
          target_v_ = nominal_speed_mm_s(dcp::Speed::V0);  // crawl while B2 (DCP 10.1.1 step 4)
        } else {
          target_v_ = 0.0;  // B1 and B2 off: stop (positioning)
        }
        if (holding_) target_v_ = 0.0;
        if (!travel_bit && !stop_switch && !holding_ && phase_ == Phase::Moving) {
          phase_ = Phase::Stopping;
        }
        if (!travel_bit && !stop_switch && phase_ == Phase::Preflux) {
          phase_ = Phase::Stopping;  // stop message during pre-flux / hold (DCP 12.2.2)
        }
      }
    }
    advance();
  }

  /// Deceleration distance for the data bytes: nullopt while stationary or starting
  /// (DCP 4.2.1.2: 0x7FFF then).
  std::optional<std::uint32_t> decel_distance_mm() const {
    if (phase_ != Phase::Moving || v_ <= 0.0) return std::nullopt;
    return static_cast<std::uint32_t>(v_ * v_ / (2.0 * config_.accel_mm_s2));
  }

  dcp::Status& status() { return status_; }
  double position_mm() const { return position_mm_; }
  void set_position_mm(double p) { position_mm_ = p; }
  double speed_mm_s() const { return v_; }
  Phase phase() const { return phase_; }
  std::optional<dcp::Speed> speed() const { return speed_; }

 private:
  void begin_preflux() {
    phase_ = Phase::Preflux;
    counter_ = 0;
    status_.travel_active = true;
    status_.accepted = true;
  }

  void advance() {
    switch (phase_) {
      case Phase::Idle:
        return;
      case Phase::Preflux:
        if (++counter_ >= config_.preflux_cycles) {
          status_.brake_open = true;
          phase_ = Phase::Moving;
        }
        return;
      case Phase::Moving:
      case Phase::Stopping: {
        if (holding_ && phase_ == Phase::Moving) return;  // fast start: car held, brake open
        const double a = fast_stop_ ? config_.fast_stop_mm_s2 : config_.accel_mm_s2;
        const double goal = (fast_stop_ || phase_ == Phase::Stopping) ? 0.0 : target_v_;
        if (v_ < goal) v_ = std::min(goal, v_ + a * kCycleS);
        if (v_ > goal) v_ = std::max(goal, v_ - a * kCycleS);
        double step = v_ * kCycleS;
        if (distance_mode_ && !fast_stop_) step = std::min(step, std::max(0.0, remaining_mm_));
        position_mm_ += down_ ? -step : step;
        if (distance_mode_) remaining_mm_ -= step;
        const bool arrived = distance_mode_ && remaining_mm_ < 0.5 && v_ < a * kCycleS * 2;
        if (v_ <= 0.0 || arrived) {
          if (phase_ == Phase::Moving && !arrived && !fast_stop_) return;  // waiting to go
          v_ = 0.0;
          status_.brake_open = false;  // DCP 9.1.7: S6 off at standstill
          phase_ = Phase::BrakeClosing;
          counter_ = 0;
        }
        return;
      }
      case Phase::BrakeClosing:
        if (++counter_ >= config_.brake_hold_cycles) {
          status_.travel_active = false;
          phase_ = Phase::Idle;
          fast_stop_ = false;
          holding_ = false;
          after_travel_ = false;
          distance_mode_ = false;
        }
        return;
    }
  }

  dcp::Protocol protocol_;
  FakeDriveConfig config_;
  dcp::Status status_{};
  Phase phase_ = Phase::Idle;
  std::optional<dcp::Speed> speed_;
  bool down_ = false;
  bool distance_mode_ = false;
  bool after_travel_ = false;
  bool holding_ = false;
  bool fast_stop_ = false;
  double remaining_mm_ = 0.0;
  double target_v_ = 0.0;
  double v_ = 0.0;
  double position_mm_ = 0.0;
  int counter_ = 0;
};

/// One recorded master frame with what the controller saw that cycle.
struct Record {
  std::uint8_t command = 0;
  std::uint16_t data_word = 0;
  std::int64_t position_mm = 0;  ///< position the controller saw
  dcp::Status status{};          ///< status the controller saw
  std::optional<ChannelRequest> channel_request;
};

/// Controller + drive + fake clock + a channel that answers I7 and I8.
class Rig {
 public:
  Rig(dcp::Protocol protocol, TravelConfig config = {}, FakeDriveConfig drive_config = {})
      : controller(config), drive(protocol, drive_config), config_(config) {
    input.link_up = true;
    input.reply_fresh = true;  // the fake drive answers every frame
    input.handshake_done = true;
    input.protocol = protocol;
    input.inputs.valid = true;
    input.inputs.safety_chain_closed = true;
    input.inputs.doors_closed = true;
    input.inputs.doors_locked = true;
    with_position = protocol == dcp::Protocol::Dcp4;
  }

  /// One cycle: controller decides from the drive's last reply, the drive gets the frame.
  CycleOutput cycle() {
    now += kCycle;
    input.now = now;
    input.status = drive.status();
    input.decel_distance_mm = drive.decel_distance_mm();
    input.position_mm = with_position
                            ? std::optional<std::int64_t>(std::llround(drive.position_mm()))
                            : std::nullopt;
    input.channel_reply = pending_reply_;
    pending_reply_.reset();
    const CycleOutput out = controller.step(input);
    records.push_back({out.command, out.data_word, input.position_mm.value_or(0), input.status,
                       out.channel_request});
    if (out.channel_request && answer_channel) {
      ChannelReply reply;
      reply.kind = out.channel_request->kind;
      if (reply.kind == ChannelRequest::Kind::StartParameters) {
        reply.short_travel = false;  // DCP 11.1.2.1 example 2: 'l', Sg 520 cm, Sv 250 cm
        reply.min_distance_cm = 520;
        reply.decel_distance_cm = 250;
      }
      pending_reply_ = reply;
    }
    drive.on_frame(out.command, out.data_word);
    while (auto event = controller.pop_event()) events.push_back(*event);
    return out;
  }

  /// Runs until the predicate holds or `max_cycles` pass; returns whether it held.
  template <typename Pred>
  bool run_until(Pred pred, int max_cycles = 4000) {
    for (int i = 0; i < max_cycles; ++i) {
      cycle();
      if (pred()) return true;
    }
    return false;
  }
  /// Runs until the controller is idle and the drive stationary.
  bool run_to_idle(int max_cycles = 4000) {
    return run_until(
        [&] {
          return controller.active_kind() == TravelKind::None && !drive.status().travel_active;
        },
        max_cycles);
  }

  /// Command bytes with consecutive repeats collapsed.
  std::vector<std::uint8_t> command_runs(std::size_t from = 0) const {
    std::vector<std::uint8_t> runs;
    for (std::size_t i = from; i < records.size(); ++i) {
      if (runs.empty() || runs.back() != records[i].command) runs.push_back(records[i].command);
    }
    return runs;
  }
  /// Number of records with this command byte.
  std::size_t count(std::uint8_t command) const {
    std::size_t n = 0;
    for (const auto& r : records) n += r.command == command ? 1 : 0;
    return n;
  }
  /// Index of the first record with this command byte, or records.size().
  std::size_t first(std::uint8_t command, std::size_t from = 0) const {
    for (std::size_t i = from; i < records.size(); ++i) {
      if (records[i].command == command) return i;
    }
    return records.size();
  }
  /// Event types in order.
  std::vector<Event::Type> event_types() const {
    std::vector<Event::Type> types;
    for (const auto& e : events) types.push_back(e.type);
    return types;
  }

  TravelController controller;
  FakeDrive drive;
  CycleInput input{};
  MonoTime now{};
  bool with_position = true;
  bool answer_channel = true;
  std::vector<Record> records;
  std::vector<Event> events;

 private:
  TravelConfig config_;
  std::optional<ChannelReply> pending_reply_;
};

/// Text of a channel request body.
inline std::string body_text(const ChannelRequest& request) {
  const ChannelText text = request.body();
  return std::string(text.chars.data(), text.size);
}

}  // namespace liftd::travel::test
