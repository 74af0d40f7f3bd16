// The daemon's DCP lift (drive.kind "dcp"): the DCP controller on its 15 ms cycle (DCP 7.2), the
// API backend over it with the commands only a DCP drive offers (display, keypad, power, load,
// fast start and fast stop, drive reset by I2), and with --simulate the simulated drive on a
// pseudo-terminal, its encoder and the I/O board. The io-thread side every kind shares is
// host/controller_lift.hpp; lib/kinds/lifts.cpp picks the lift by drive.kind.
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <utility>

#include "api/backend.hpp"
#include "can/encoder.hpp"
#include "config/config.hpp"
#include "dcp/control/dcp_controller.hpp"
#include "dcp/host/commands.hpp"
#include "dcp/host/dcp_status.hpp"
#include "dcp/host/simulated_lift.hpp"
#include "host/controller_lift.hpp"
#include "host/host.hpp"
#include "rt/can_runner.hpp"
#include "rt/cycle_runner.hpp"
#include "rt/encoder_tap.hpp"
#include "rt/overrun_journal.hpp"

namespace liftd::daemon {

/// The DCP controller's settings from the configuration (what a default Config gives is what a
/// default ControllerConfig holds: common/defaults.hpp).
control::ControllerConfig dcp_controller_config(const config::Config& config);

/// The DCP drive's lift as controller_lift.hpp names its parts.
struct DcpDrive : DriveParts<control::DcpController, rt::CycleRunner, SimulatedLift> {
  /// The cycle answers a travel command within a cycle and an I-message within
  /// dcp.request_timeout_ms: 3 s catches a cycle that stopped. After a forced end it sends
  /// frames without B0 for more than one DCP 7.3 supervision window (10 x 15 ms).
  static constexpr DriveFacts kFacts{drive::Kind::Dcp, "cycle", std::chrono::seconds(3),
                                     std::chrono::milliseconds(500), &control::kFaultTexts};
  /// The command bits B0..B7 and status bits S0..S7 (DCP 4.1).
  static TravelBitNames travel_bit_names();
  /// A learning leg crawls (DCP 10.3) within the crawl limit.
  static std::uint32_t learn_leg_base_ms(const config::Config&) {
    return travel::TravelConfig{}.crawl_timeout_ms;
  }
  /// The car moves while a travel runs or the drive still reports travel active (S1, DCP 4.1):
  /// a car whose drive enable was cut may still be on its ramp.
  static bool car_moving(const control::ControllerSnapshot& s) noexcept {
    return s.travel_kind != travel::TravelKind::None ||
           (s.status_byte && (*s.status_byte & dcp::status_bit::kTravelActive) != 0);
  }
};

/// api::Backend and the DCP commands over the DCP controller and its cycle.
class DcpBackend final : public ControllerBackend<DcpDrive>, public DcpCommandBackend {
 public:
  DcpBackend(const config::Config& config, const config::Schema& schema,
             control::DcpController& controller, rt::CycleRunner& runner,
             PositionFeed* position_feed, SimulatedLift* sim);

  // ---- api::Backend: what only a DCP drive answers ----
  api::StatusSnapshot status() override;
  api::StatsSnapshot stats() override;
  std::vector<api::TraceEntry> trace(std::size_t max_entries) override;
  void drive_reset(api::Responder done) override;
  void travel(const api::TravelArgs& args, api::Responder done) override;

  // ---- DcpCommandBackend ----
  DisplaySnapshot display() override;
  void key(int button, api::Responder done) override;
  void power(PowerSetting setting, api::Responder done) override;
  void load(int percent, api::Responder done) override;
  void fast_stop(api::Responder done) override;
  void fast_start(const std::string& action, const api::TravelArgs& args,
                  api::Responder done) override;

  /// Sends the wall clock to the cycle for I3 (DCP 5.12.5).
  void send_clock(std::chrono::system_clock::time_point now);

 private:
  DcpStatusFacts dcp_facts_{};                        ///< what dcp_details_ was built from
  api::SharedJson dcp_details_{dcp_status_json({})};  ///< status.dcp, shared by the snapshots
};

/// The DCP lift as one piece, registered with the daemon.
class DcpLift final : public ControllerLift<DcpDrive> {
 public:
  /// Builds the parts (throws std::invalid_argument / std::runtime_error with a clear message
  /// on a configuration the parts refuse) and registers them with `daemon`.
  DcpLift(Host& daemon, const config::Config& config, bool simulate);
  ~DcpLift() override;

  /// The real-time cycle (statistics for benchmarks and diagnostics).
  const rt::CycleRunner& cycle() const { return *runner_; }

 private:
  /// The serial device's driver and settings, a USB adapter's latency timer (serial_device.hpp).
  void before_start() override;
  void journal_started() override;
  void handle_event(const control::ControllerEvent& event) override;
  /// The clock for I3 every second, the drive's display when it changed.
  void after_events(MonoTime now) override;
  /// Skipped cycles (WARN only when they threaten the link supervision), the port's events.
  void handle_runner_event(const rt::CycleEvent& event) override;
  DcpBackend& dcp_backend() { return static_cast<DcpBackend&>(*backend_); }

  std::unique_ptr<can::CanEncoder> encoder_;       ///< position.source "can"
  std::unique_ptr<rt::EncoderTap> encoder_tap_;    ///< its frames to it
  std::unique_ptr<rt::CanRunner> encoder_runner_;  ///< reads its bus
  rt::OverrunJournal overruns_;
  MonoTime last_clock_{};
  std::uint32_t last_display_version_ = 0;
};

}  // namespace liftd::daemon
