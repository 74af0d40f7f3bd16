#include "dcp/travel/gate.hpp"

#include "lift/gate.hpp"

namespace liftd::travel {

namespace cb = dcp::command_bit;

namespace {
constexpr std::uint8_t kMotionBits = cb::kDriveEnable | cb::kTravel | cb::kStopSwitch;
}  // namespace

lift::Cause CommandGate::drive_forbidding(const CycleInput& in, bool starting) noexcept {
  if (!in.link_up) return lift::Cause::LinkDown;                                  // DCP 7.3
  if (!in.handshake_done) return lift::Cause::NoHandshake;                        // DCP 5.12.2
  if (in.status.general_fault) return lift::Cause::DriveFault;                    // DCP 9.1.6
  if (starting && !in.status.ready) return lift::Cause::DriveNotReady;            // DCP 9.1.3
  if (starting && in.status.advance_warning) return lift::Cause::AdvanceWarning;  // DCP 9.1.5
  return lift::Cause::None;
}

lift::Cause CommandGate::forbidding(const CycleInput& in, const GateProfile& profile,
                                    bool starting) noexcept {
  // The link and a drive fault come first; the drive's start conditions (S0, S2) after the
  // machine's, so a refusal names an open safety chain or door before a drive not ready.
  const lift::Cause drive = drive_forbidding(in, starting);
  if (drive == lift::Cause::LinkDown || drive == lift::Cause::NoHandshake ||
      drive == lift::Cause::DriveFault) {
    return drive;
  }
  // The machine's rules, common to every drive kind (DCP 9.1.1: the safety chain).
  const lift::Cause machine = lift::refusal_cause(lift::machine_refusal(
      in.inputs, in.position_mm.has_value(),
      {profile.doors_locked_required, profile.door_bridge_allowed, profile.position_required}));
  if (machine != lift::Cause::None) return machine;
  return drive;
}

GateResult CommandGate::apply(const Demand& demand, const CycleInput& in) noexcept {
  GateResult result;
  // B7 belongs to the link layer (DCP 3.1); the sequencers never set it.
  const auto command = static_cast<std::uint8_t>(demand.command & ~cb::kReplyChecksumError);
  if ((command & kMotionBits) != 0) {
    result.violation = forbidding(in, demand.profile, !enable_on_);
  }
  if (result.violation == lift::Cause::None) {
    result.output.command = command;
    result.output.data_word = demand.data_word;
  }
  enable_on_ = (result.output.command & cb::kDriveEnable) != 0;
  // DCP 9.1.7: the brake follows S6 at once; without a link, the last status is stale: close it.
  result.output.brake_open = in.link_up && in.status.brake_open;
  // DCP 9.1.4 / 10.1.1 step 5: contactors on while we enable the drive or it reports S1.
  result.output.contactors_on = enable_on_ || (in.link_up && in.status.travel_active);
  return result;
}

}  // namespace liftd::travel
