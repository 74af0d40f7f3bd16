// In-process rig: the real DcpController (master link + travel + lift model) against the drive
// simulator engine, one 15 ms cycle per call, on a fake clock. No threads, no ports.
#pragma once

#include <chrono>
#include <cmath>
#include <functional>
#include <vector>

#include "control/dcp_controller.hpp"
#include "sim/drive_sim.hpp"

namespace liftd::control::testing {

using namespace std::chrono_literals;

/// The simulated encoder as a PositionSource.
class SimPosition final : public PositionSource {
 public:
  explicit SimPosition(const sim::DriveSim& sim) : sim_(sim) {}
  std::optional<std::int64_t> position_mm(MonoTime) const noexcept override {
    if (!valid) return std::nullopt;
    return std::llround(sim_.position_mm());
  }
  bool valid = true;

 private:
  const sim::DriveSim& sim_;
};

/// A six-floor building, 3 m apart (the config example's floors).
inline std::vector<std::int64_t> six_floors() {
  return {0, 3000, 6000, 9000, 12000, 15000};
}

inline ControllerConfig default_config(dcp::Protocol protocol) {
  ControllerConfig c;
  c.floors_mm = six_floors();
  c.link.extended_position = true;
  if (protocol == dcp::Protocol::Dcp3) {
    c.travel.dcp3_reference = travel::Dcp3Reference::Position;
    c.travel.dcp3_speed_count = 2;
    c.travel.dcp3_decel_distance_mm[travel::speed_index(dcp::Speed::V4)] = 2500;
    c.travel.dcp3_decel_distance_mm[travel::speed_index(dcp::Speed::V3)] = 1200;
  }
  return c;
}

inline sim::DriveConfig sim_config(dcp::Protocol protocol) {
  sim::DriveConfig c;
  c.protocol = protocol;
  c.dcp3_decel_mm[travel::speed_index(dcp::Speed::V4)] = 2500;
  c.dcp3_decel_mm[travel::speed_index(dcp::Speed::V3)] = 1200;
  return c;
}

struct Rig {
  explicit Rig(dcp::Protocol protocol = dcp::Protocol::Dcp4)
      : Rig(default_config(protocol), sim_config(protocol)) {}
  Rig(const ControllerConfig& config, const sim::DriveConfig& sim_cfg)
      : sim(sim_cfg, now), position(sim), controller(config, position) {
    inputs.valid = inputs.safety_chain_closed = inputs.doors_closed = inputs.doors_locked = true;
  }

  /// One 15 ms cycle (DCP 7.2): frame out, simulator reply, engine fed.
  void cycle() {
    now += 15ms;
    if (cycle_count++ % 4 == 0) post(InputsCommand{inputs});  // the I/O provider, every 60 ms
    sim.advance(now);
    const auto frame = controller.frame_to_send(now);
    frames.push_back({});
    std::copy(frame.begin(), frame.end(), frames.back().begin());
    const sim::Reply reply = sim.on_master_frame(
        std::span<const std::uint8_t, dcp::kFrameSize>(frame.data(), dcp::kFrameSize), now);
    if (reply.size == dcp::kFrameSize && !drop_replies) {
      controller.on_reply(reply.view(), now + 4ms);
    } else {
      controller.on_no_reply(now + 13ms);
    }
    controller.after_cycle(now + 13ms);
    ControllerEvent ev;
    while (controller.poll_event(ev)) events.push_back(ev);
    CommandReply r;
    while (controller.poll_reply(r)) replies.push_back(r);
  }

  void run(std::chrono::milliseconds duration) {
    for (auto end = now + duration; now < end;) cycle();
  }
  /// Runs until `done` or the time limit; true if done.
  bool run_until(const std::function<bool()>& done, std::chrono::milliseconds limit = 60s) {
    for (auto end = now + limit; now < end;) {
      cycle();
      if (done()) return true;
    }
    return false;
  }
  void post(CommandBody body, std::uint32_t tag = 0) { controller.post(Command{tag, body}); }

  /// Posts a tagged command and runs until its reply.
  CommandReply command(CommandBody body) {
    const std::uint32_t tag = ++next_tag;
    post(body, tag);
    for (int i = 0; i < 400; ++i) {
      cycle();
      for (const auto& r : replies) {
        if (r.tag == tag) return r;
      }
    }
    return CommandReply{tag, ReplyCode::Timeout, "rig: no reply", {}, false};
  }

  bool link_up() { return controller.snapshot().link == dcp::LinkState::Up; }
  bool idle() {
    const auto s = controller.snapshot();
    return s.travel_kind == travel::TravelKind::None && s.status_byte &&
           (*s.status_byte & dcp::status_bit::kTravelActive) == 0;
  }
  bool finished_travels(std::size_t n) {
    std::size_t count = 0;
    for (const auto& e : events) {
      if (e.kind == ControllerEvent::Kind::Travel &&
          e.travel.type == travel::Event::Type::Finished) {
        ++count;
      }
    }
    return count >= n;
  }

  MonoTime now{std::chrono::seconds(1)};
  sim::DriveSim sim;
  SimPosition position;
  DcpController controller;
  lift::Inputs inputs;
  bool drop_replies = false;
  std::uint64_t cycle_count = 0;
  std::uint32_t next_tag = 0;
  std::vector<dcp::FrameBytes> frames;
  std::vector<ControllerEvent> events;
  std::vector<CommandReply> replies;
};

}  // namespace liftd::control::testing
