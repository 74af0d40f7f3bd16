// In-process rig: the real DcpController (master link + travel + lift model) against the drive
// simulator engine, one 15 ms cycle per call, on a fake clock. No threads, no ports.
#pragma once

#include <chrono>
#include <cmath>
#include <functional>
#include <vector>

#include "dcp/control/dcp_controller.hpp"
#include "dcp/sim/drive_sim.hpp"

namespace liftd::control::testing {

using namespace std::chrono_literals;

/// The simulated encoder as a PositionSource.
class SimPosition final : public PositionSource {
 public:
  explicit SimPosition(const dcp::sim::DriveSim& sim) : sim_(sim) {}
  std::optional<std::int64_t> position_mm(MonoTime) const noexcept override {
    if (!valid) return std::nullopt;
    return std::llround(sim_.position_mm());
  }
  bool valid = true;

 private:
  const dcp::sim::DriveSim& sim_;
};

/// A six-floor building, 3 m apart (the config example's floors).
inline std::vector<std::int64_t> six_floors() {
  return {0, 3000, 6000, 9000, 12000, 15000};
}

/// The simulator's own fixed deceleration distance SVx for a DCP3 speed when its config leaves
/// it at 0: its deceleration ramp from Vx down to crawl V0, plus 50 mm of crawl (drive_sim.hpp,
/// DriveConfig::dcp3_decel_mm). The controller must be configured with the same figure, the way
/// an installer sets the deceleration points from the drive's SVx parameter (DCP 8.1).
inline std::uint32_t sim_sv_mm(const dcp::sim::DriveConfig& drive, dcp::Speed speed) {
  const double metres =
      dcp::sim::ramp_distance_m(drive.speeds.of(speed), drive.speeds.v0_mps, drive.decel) + 0.050;
  return static_cast<std::uint32_t>(std::ceil(metres * 1000.0));
}

/// DCP3 with position reference: B2 is withdrawn this far before the level so the drive's stop
/// from crawl (V0 = 0.05 m/s on a 2.1 m/s^3 jerk-limited ramp: 2 * sqrt(0.05 / 2.1) = 0.31 s,
/// 0.05 * 0.31 / 2 = 7.7 mm) ends on it.
inline constexpr std::uint32_t kDcp3StopLeadMm = 8;

/// DCP 10.1.1: the drive reaches crawl at the end of its SVx; the deceleration point is placed
/// this much earlier so the car crawls into the level instead of arriving still braking.
inline constexpr std::uint32_t kDcp3CrawlMm = 100;

inline ControllerConfig default_config(dcp::Protocol protocol) {
  ControllerConfig c;
  c.floors_mm = six_floors();
  c.link.extended_position = true;
  if (protocol == dcp::Protocol::Dcp3) {
    const dcp::sim::DriveConfig drive;  // the simulator's defaults
    c.travel.dcp3_reference = travel::Dcp3Reference::Position;
    c.travel.dcp3_speed_count = 2;
    c.travel.dcp3_stop_lead_mm = kDcp3StopLeadMm;
    for (dcp::Speed s : {dcp::Speed::V4, dcp::Speed::V3}) {
      c.travel.dcp3_decel_distance_mm[travel::speed_index(s)] = sim_sv_mm(drive, s) + kDcp3CrawlMm;
    }
  }
  return c;
}

inline dcp::sim::DriveConfig sim_config(dcp::Protocol protocol) {
  dcp::sim::DriveConfig c;  // SVx derived by the simulator itself (see sim_sv_mm)
  c.protocol = protocol;
  return c;
}

/// What the rig fed the controller for one cycle, and the frame the controller sent. The gating
/// checks work from these records only, never from the controller's own state.
struct CycleRecord {
  MonoTime at{};                      ///< frame time
  dcp::FrameBytes frame{};            ///< master frame sent this cycle
  std::optional<std::uint8_t> seen;   ///< last status byte delivered BEFORE this frame was built
  std::optional<std::uint8_t> reply;  ///< status byte delivered after this frame (nullopt: dropped)
  lift::Inputs inputs{};              ///< inputs last posted (at or before this frame)
  MonoTime inputs_at{};               ///< when they were posted (-1 s: never)
  bool position_valid = true;         ///< the position source answered this cycle
  double position_mm = 0.0;           ///< simulated car position at the frame
};

/// The message nibble B3..B0 of a master frame (DCP 3.5).
inline std::uint8_t nibble_of(const dcp::FrameBytes& f) {
  return f[0] & 0x0F;
}
/// B0 of a master frame.
inline bool enable_of(const dcp::FrameBytes& f) {
  return (f[0] & dcp::command_bit::kDriveEnable) != 0;
}
/// Data bytes 1 and 2 of a frame as one word (data1 is the high byte, DCP 3.2).
inline std::uint16_t word_of(const dcp::FrameBytes& f) {
  return static_cast<std::uint16_t>((f[1] << 8) | f[2]);
}

/// The controller, the simulator and the fake I/O provider, stepped one cycle at a time.
struct Rig {
  explicit Rig(dcp::Protocol protocol = dcp::Protocol::Dcp4)
      : Rig(default_config(protocol), sim_config(protocol)) {}
  Rig(const ControllerConfig& config, const dcp::sim::DriveConfig& sim_cfg)
      : sim(sim_cfg, now), position(sim), controller(config, position) {
    inputs.valid = inputs.safety_chain_closed = inputs.doors_closed = inputs.doors_locked = true;
  }

  /// One 15 ms cycle (DCP 7.2): frame out, simulator reply, engine fed.
  void cycle() {
    now += 15ms;
    // The I/O provider, every 60 ms (or at once when a test changed the inputs).
    if (post_inputs && (cycle_count % 4 == 0 || inputs != posted_inputs)) {
      post(InputsCommand{inputs});
      posted_inputs = inputs;
      posted_at = now;
    }
    ++cycle_count;
    sim.advance(now);
    CycleRecord rec;
    rec.at = now;
    rec.seen = last_status;
    rec.inputs = posted_inputs;
    rec.inputs_at = posted_at;
    rec.position_valid = position.valid;
    rec.position_mm = sim.position_mm();
    const auto frame = controller.frame_to_send(now);
    frames.push_back({});
    std::copy(frame.begin(), frame.end(), frames.back().begin());
    rec.frame = frames.back();
    const dcp::sim::Reply reply = sim.on_master_frame(
        std::span<const std::uint8_t, dcp::kFrameSize>(frame.data(), dcp::kFrameSize), now);
    if (reply.size == dcp::kFrameSize && !drop_replies) {
      if (controller.on_reply(reply.view(), now + 4ms)) {
        last_status =
            static_cast<std::uint8_t>(reply.bytes[0] & ~dcp::status_bit::kMessageChecksumError);
        rec.reply = last_status;
      }
    } else {
      controller.on_no_reply(now + 13ms);
    }
    log.push_back(rec);
    controller.after_cycle(now + 13ms);
    ControllerEvent ev;
    while (controller.poll_event(ev)) events.push_back(ev);
    CommandReply r;
    while (read_replies && controller.poll_reply(r)) replies.push_back(r);
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
    return CommandReply{tag, ReplyCode::Timeout, "rig: no reply", {}, false, {}};
  }

  /// Link up, inputs posted, first statuses seen: ready for a travel command.
  bool warm_up() {
    if (!run_until([&] { return link_up(); }, 5s)) return false;
    run(200ms);
    return true;
  }
  /// Moves the car (simulator at rest only) and lets the controller see it for a few cycles.
  void place_at(std::int64_t position_mm) {
    sim.set_position_mm(static_cast<double>(position_mm));
    run(60ms);
  }
  /// Events of one kind (and travel event type, for travel events).
  std::vector<ControllerEvent> events_of(ControllerEvent::Kind kind) const {
    std::vector<ControllerEvent> out;
    for (const auto& e : events) {
      if (e.kind == kind) out.push_back(e);
    }
    return out;
  }
  /// Travel events of one type.
  std::vector<travel::Event> travel_events(travel::Event::Type type) const {
    std::vector<travel::Event> out;
    for (const auto& e : events) {
      if (e.kind == ControllerEvent::Kind::Travel && e.travel.type == type) out.push_back(e.travel);
    }
    return out;
  }
  /// How often `code` was raised.
  std::size_t raised(FaultCode code) const {
    std::size_t n = 0;
    for (const auto& e : events)
      n += e.kind == ControllerEvent::Kind::FaultRaised && e.fault == code;
    return n;
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
  dcp::sim::DriveSim sim;
  SimPosition position;
  DcpController controller;
  lift::Inputs inputs;
  bool drop_replies = false;
  bool read_replies = true;  ///< false: the io thread does not read replies (a test does)
  bool post_inputs = true;   ///< false: the input provider falls silent
  lift::Inputs posted_inputs{};
  MonoTime posted_at{-1s};
  std::optional<std::uint8_t> last_status;
  std::vector<CycleRecord> log;
  std::uint64_t cycle_count = 0;
  std::uint32_t next_tag = 0;
  std::vector<dcp::FrameBytes> frames;
  std::vector<ControllerEvent> events;
  std::vector<CommandReply> replies;
};

}  // namespace liftd::control::testing
