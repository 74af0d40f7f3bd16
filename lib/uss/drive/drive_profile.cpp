#include "uss/drive/drive_profile.hpp"

#include <chrono>

namespace liftd::uss {
namespace {

using std::chrono::milliseconds;

}  // namespace

std::string_view to_string(ProfileState state) noexcept {
  switch (state) {
    case ProfileState::NotReadyToSwitchOn:
      return "not_ready_to_switch_on";
    case ProfileState::SwitchOnInhibit:
      return "switch_on_inhibit";
    case ProfileState::ReadyToSwitchOn:
      return "ready_to_switch_on";
    case ProfileState::Ready:
      return "ready";
    case ProfileState::OperationEnabled:
      return "operation_enabled";
    case ProfileState::Off1Active:
      return "off1_active";
    case ProfileState::Off2Active:
      return "off2_active";
    case ProfileState::Off3Active:
      return "off3_active";
    case ProfileState::Fault:
      return "fault";
  }
  return "fault";
}

std::string_view to_string(ProfileWish wish) noexcept {
  switch (wish) {
    case ProfileWish::Stop:
      return "stop";
    case ProfileWish::Run:
      return "run";
    case ProfileWish::Coast:
      return "coast";
    case ProfileWish::QuickStop:
      return "quick_stop";
  }
  return "stop";
}

std::string_view to_string(Supervision supervision) noexcept {
  switch (supervision) {
    case Supervision::None:
      return "none";
    case Supervision::NotSwitchedOn:
      return "drive_did_not_start";
    case Supervision::NotStopped:
      return "drive_did_not_stop";
  }
  return "none";
}

ProfileState decode_status(std::uint16_t zsw, bool off1_sent) noexcept {
  // C 5.2.1 table 5.5. A fault (bit 3) holds the drive "außer Betrieb" whatever else it says;
  // the inhibit (bit 6) is where OFF2, OFF3 and an acknowledged fault end.
  if ((zsw & zsw::kFault) != 0) return ProfileState::Fault;
  if ((zsw & zsw::kSwitchOnInhibit) != 0) return ProfileState::SwitchOnInhibit;
  // Bits 4 and 5 are active low: 0 = "AUS 2 / AUS 3 Befehl steht an".
  if ((zsw & zsw::kNoOff2) == 0) return ProfileState::Off2Active;
  if ((zsw & zsw::kNoOff3) == 0) return ProfileState::Off3Active;
  if ((zsw & zsw::kOperationEnabled) != 0) {
    // Table 5.2, OFF1: the drive ramps down with its pulses on and switches off at n/f = 0.
    return off1_sent ? ProfileState::Off1Active : ProfileState::OperationEnabled;
  }
  if ((zsw & zsw::kReady) != 0) return ProfileState::Ready;
  if ((zsw & zsw::kReadyToSwitchOn) != 0) return ProfileState::ReadyToSwitchOn;
  return ProfileState::NotReadyToSwitchOn;
}

std::uint16_t control_word(ProfileWish wish, ProfileState state) noexcept {
  switch (wish) {
    case ProfileWish::Stop:
      return control::kStop;
    case ProfileWish::Coast:
      return control::kCoast;
    case ProfileWish::QuickStop:
      return control::kQuickStop;
    case ProfileWish::Run:
      break;
  }
  switch (state) {
    case ProfileState::ReadyToSwitchOn:
    case ProfileState::Ready:
    case ProfileState::OperationEnabled:
    case ProfileState::Off1Active:
      return control::kRun;
    case ProfileState::NotReadyToSwitchOn:
    case ProfileState::SwitchOnInhibit:
    case ProfileState::Off2Active:
    case ProfileState::Off3Active:
    case ProfileState::Fault:
      break;
  }
  // C 5.2.1 ZSW bit 6: "Wiedereinschalten nur durch AUS 1 und anschließendem EIN": OFF1 first,
  // ON only once the drive reports "ready to switch on".
  return control::kStop;
}

void DriveProfile::acknowledge() noexcept {
  ack_ = Ack::Armed;
  supervision_ = Supervision::None;
}

std::uint16_t DriveProfile::step(ProfileWish wish, const ProfileInput& in) noexcept {
  state_ = decode_status(in.zsw, (stw_ & stw::kOn) == 0);
  const bool enabled = operation_enabled(in.zsw);
  // The supervision clock runs from the wish or from the last time its goal held, and only
  // while the replies are current (without them the link supervision speaks).
  const bool goal_met =
      wish == ProfileWish::Run ? state_ == ProfileState::OperationEnabled : !enabled;
  if (!wish_started_ || wish != wish_ || goal_met || !in.link_ok) {
    wish_since_ = in.now;
    wish_started_ = true;
  }
  wish_ = wish;
  if (supervision_ == Supervision::None && in.link_ok && state_ != ProfileState::Fault) {
    if (wish == ProfileWish::Run &&
        in.now - wish_since_ >= milliseconds(config_.switch_on_timeout_ms)) {
      supervision_ = Supervision::NotSwitchedOn;
    } else if (wish != ProfileWish::Run &&
               in.now - wish_since_ >= milliseconds(config_.stop_timeout_ms)) {
      supervision_ = Supervision::NotStopped;
    }
  }

  std::uint16_t word = control_word(wish, state_);
  // C 5.2.1 table 5.3, bit 7: the fault is acknowledged on the rising edge. The drive must
  // have taken a telegram with bit 7 = 0 before the one with 1: the 0 stays until the drive
  // answered a telegram sent after it was set (a reply counted after this step).
  switch (ack_) {
    case Ack::Idle:
      break;
    case Ack::Armed:
      ack_ = Ack::Low;
      ack_replies_ = in.replies;
      break;
    case Ack::Low:
      if (in.replies > ack_replies_) {
        ack_ = Ack::High;
        ack_replies_ = in.replies;
        ack_since_ = in.now;
        word |= stw::kFaultAcknowledge;
      }
      break;
    case Ack::High: {
      // Held until the drive answered the 1 and no longer reports the fault ("geht nach
      // Quittierung ... in Einschaltsperre", ZSW bit 3), or the hold time passed.
      const bool answered = in.replies > ack_replies_;
      const bool cleared = answered && (in.zsw & zsw::kFault) == 0;
      if (cleared || in.now - ack_since_ >= milliseconds(config_.acknowledge_hold_ms)) {
        ack_ = Ack::Idle;
      } else {
        word |= stw::kFaultAcknowledge;
      }
      break;
    }
  }
  stw_ = word;
  return word;
}

}  // namespace liftd::uss
