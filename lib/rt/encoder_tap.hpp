// A CAN position encoder on the bus a CAN runner reads: its frames go to the encoder
// (can/encoder.hpp), everything else to the drive's engine, if the bus has one (the SCH001 card
// and the encoder may share a bus; a DCP lift runs a runner for the encoder alone).
#pragma once

#include "can/encoder.hpp"
#include "rt/can_runner.hpp"

namespace liftd::rt {

class EncoderTap final : public CanEngine {
 public:
  /// `inner` may be nullptr (a bus with the encoder only).
  EncoderTap(can::CanEncoder& encoder, CanEngine* inner) noexcept
      : encoder_(encoder), inner_(inner) {}
  void on_frame(const can::Frame& frame, MonoTime now, CanOutbox& out) noexcept override {
    if (encoder_.on_frame(frame, now)) return;  // the encoder is only listened to
    if (inner_ != nullptr) inner_->on_frame(frame, now, out);
  }
  void on_bus_error(const can::ErrorReport& report, MonoTime now) noexcept override {
    if (inner_ != nullptr) inner_->on_bus_error(report, now);
  }
  void on_endpoint(bool up, MonoTime now) noexcept override {
    if (inner_ != nullptr) inner_->on_endpoint(up, now);
  }
  void on_tick(MonoTime now, CanOutbox& out) noexcept override {
    if (inner_ != nullptr) inner_->on_tick(now, out);
  }
  /// Every frame sent was the inner engine's.
  void on_sent(const can::Frame& frame, bool delivered, MonoTime now) noexcept override {
    if (inner_ != nullptr) inner_->on_sent(frame, delivered, now);
  }

 private:
  can::CanEncoder& encoder_;
  CanEngine* inner_;
};

}  // namespace liftd::rt
