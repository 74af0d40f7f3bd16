// The faults a lift can stand in, whatever its drive: each ends any travel in the safe state
// (no travel command, drive enable off) and is reported once when it comes and once when it
// goes. The names are the API's fault codes (docs/api.md "Fault codes"); each drive kind words
// the technician's explanation of its drive's faults in its own terms (its kFaultTexts, a
// DriveFaultTexts).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "common/mono_time.hpp"

namespace liftd::lift {

enum class FaultCode : std::uint8_t {
  LinkFault,       ///< the link to the drive is lost (DCP 7.3, the SCH001 card silent, a bus)
  DriveFault,      ///< the drive reports a general fault (DCP S3, SCH001 ERR)
  SafetyChain,     ///< safety chain open
  InputsLost,      ///< input provider silent longer than inputs.timeout_ms
  PositionLost,    ///< the position source is invalid or stale
  AdvanceWarning,  ///< the drive warns of a coming fault (DCP S2): no new travel until it clears
  kCount,
};

/// snake_case code for the API and the journal ("link_fault", ...); "internal" for kCount.
std::string_view fault_code_name(FaultCode code) noexcept;

/// The technician's text of a fault of the machine's inputs, alike on every drive kind
/// (SafetyChain, InputsLost, PositionLost); "internal" for a fault of the drive.
constexpr std::string_view machine_fault_text(FaultCode code) noexcept {
  switch (code) {
    case FaultCode::SafetyChain:
      return "safety chain open; drive enable is off";
    case FaultCode::InputsLost:
      return "no input update from the I/O provider within inputs.timeout_ms";
    case FaultCode::PositionLost:
      return "the car position is unknown or stale: no travel possible";
    default:
      return "internal";
  }
}

/// A drive kind's texts of the faults of its drive, in its own terms (its link, its fault and
/// warning signals); every other fault reads as machine_fault_text() says.
struct DriveFaultTexts {
  std::string_view link_fault;
  std::string_view drive_fault;
  std::string_view advance_warning;  ///< empty: the drive has no warning signal
  /// Empty: machine_fault_text's. A kind with travels that need no position (DCP3) says so.
  std::string_view position_lost;

  /// The technician's one line of explanation of `code` on this kind's lift.
  constexpr std::string_view of(FaultCode code) const noexcept {
    switch (code) {
      case FaultCode::LinkFault:
        return link_fault;
      case FaultCode::DriveFault:
        return drive_fault;
      case FaultCode::AdvanceWarning:
        return advance_warning.empty() ? machine_fault_text(code) : advance_warning;
      case FaultCode::PositionLost:
        return position_lost.empty() ? machine_fault_text(code) : position_lost;
      default:
        return machine_fault_text(code);
    }
  }
};

/// The faults a controller stands in, when each began, and what it still owes the io thread:
/// every raise and every clear is told once and in order. When telling fails (the event queue is
/// full) it stays owed and is told at a later set() of that fault: never lost, and repeats missed
/// meanwhile are told as one (a clear, then a raise). Real-time safe.
class FaultTable {
 public:
  static constexpr std::size_t kSize = static_cast<std::size_t>(FaultCode::kCount);

  /// Sets `code` active or not at `now`, then tells what is owed for it through
  /// `tell(code, raised)`, which returns false when it could not tell (tried again next time).
  /// Call it for every fault at every step, so that an owed report is not kept waiting.
  template <typename Tell>
  void set(FaultCode code, bool active, MonoTime now, Tell&& tell) noexcept {
    const auto i = static_cast<std::size_t>(code);
    if (active_[i] != active) {
      active_[i] = active;
      if (active) {
        since_[i] = now;
        ++raises_[i];
      }
    }
    for (;;) {
      const bool raise_owed = raises_[i] != raises_told_[i];
      bool raise;
      if (!told_[i] && raise_owed) {
        raise = true;
      } else if (told_[i] && (!active_[i] || raise_owed)) {
        raise = false;  // ended, or ended and came again: the clear first
      } else {
        return;  // the io thread knows the truth
      }
      if (!tell(code, raise)) return;  // not lost: told at a later set()
      told_[i] = raise;
      if (raise) raises_told_[i] = raises_[i];  // missed repeats told as one
    }
  }
  bool active(FaultCode code) const noexcept { return active_[static_cast<std::size_t>(code)]; }
  /// Each fault's state, indexed by FaultCode (for a snapshot).
  const std::array<bool, kSize>& active_all() const noexcept { return active_; }
  /// When each fault last began.
  const std::array<MonoTime, kSize>& since_all() const noexcept { return since_; }

 private:
  std::array<bool, kSize> active_{};
  std::array<MonoTime, kSize> since_{};
  std::array<std::uint64_t, kSize> raises_{};
  std::array<std::uint64_t, kSize> raises_told_{};
  std::array<bool, kSize> told_{};
};

}  // namespace liftd::lift
