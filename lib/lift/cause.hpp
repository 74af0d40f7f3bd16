// Why a travel ended early or could not start, for every drive kind (DCP, SCH001, USS): one
// enum, one table of API names (docs/api.md, "Abort causes"). A cause only one kind can raise
// says which kind and where its spec defines it; what each kind does about a cause (a DCP
// emergency stop, a USS OFF1/OFF2/OFF3 wish) stays in that kind's code.
#pragma once

#include <cstdint>
#include <string_view>

namespace liftd::lift {

/// Why a travel ended early or was refused.
enum class Cause : std::uint8_t {
  None,  ///< the travel started or ended normally
  /// The drive link failed. DCP: link fault, no good replies; USS: uss.telegram_failures
  /// telegrams in a row failed or the port was lost.
  LinkDown,
  NoHandshake,    ///< DCP only: no valid I0 exchange with the drive (DCP 5.12.2)
  DriveNotReady,  ///< the drive cannot take a travel: DCP S0 = 0 at start (DCP 9.1.3), SCH001
                  ///< card RDY = 0 (card document 3e), USS not ready to switch on, local control
  ///< (C 5.2.1 ZSW bit 9 = 0) or operation enabled lost during a run
  AdvanceWarning,      ///< the drive warns at start: DCP S2 = 1 (DCP 9.1.5), USS ZSW bit 7
  DriveFault,          ///< the drive reports a fault: DCP S3 = 1 (DCP 9.1.6), SCH001 card ERR (card
                       ///< document 3d), USS ZSW bit 3 or a latched profile supervision
  SafetyChainOpen,     ///< the safety chain opened
  DoorsNotLocked,      ///< the doors are not locked where the travel needs them locked
  PositionLost,        ///< the car position is unknown where the travel steers by it
  InputsLost,          ///< the machine inputs are missing or stale (inputs.timeout_ms)
  DoorReversal,        ///< DCP only: fast start, the doors opened again (DCP 12.2)
  FastStartTimeout,    ///< DCP only: fast start, doors not locked in time (DCP 12.1.2)
  StopRequested,       ///< the user stopped the travel (stop, fast stop, fast start abort)
  DriveDidNotStart,    ///< the drive did not start the motor in time after it was enabled
  DriveDidNotStop,     ///< the drive did not report the stop in time after it
  ModeChanged,         ///< inspection or recall switched on during a normal travel (DCP 9.1.1)
  StoppedOffLevel,     ///< DCP4 only: the drive ended the travel beyond the arrival tolerance
  LevelNotReached,     ///< a crawl or relevelling ran longer than its time limit
  TargetRefused,       ///< DCP only: the drive cleared S5, speed or target not accepted (DCP 4.1)
  ShuttingDown,        ///< liftd stopped before the car came to rest: the drive's enable withdrawn
  CardSilent,          ///< SCH001 only: no frame from the card for 10 s (card document 3f)
  BusFault,            ///< SCH001 only: CAN bus-off, error passive, or the CAN socket failed
  TravelTimeout,       ///< SCH001 and USS: the motor run-time limiter ended the travel
  SpeedNotConfigured,  ///< USS only: the speed has no setpoint in uss.speeds (refusal only)
};

/// The API and journal name of a cause ("safety_chain_open", "link_down", ...; "none").
std::string_view to_string(Cause cause) noexcept;

}  // namespace liftd::lift
