// The journal catalog: one fixed MESSAGE_ID per kind of event a technician acts on. The
// explanations live in systemd/liftd.catalog (installed to /usr/lib/systemd/catalog/), so
// `journalctl -x -u liftd` prints what happened, the likely causes and what to check under the
// entry. A record gets its MESSAGE_ID from the key its call site passes (log::event), never
// from its text. A test checks that this table and the catalog file name exactly the same ids.
#pragma once

#include <cstdint>
#include <span>
#include <string_view>

namespace liftd::log {

/// One catalogued event kind: the key a call site passes with a record that gets a MESSAGE_ID.
enum class Catalogued : std::uint8_t {
  Started,                     ///< liftd is ready
  Stopped,                     ///< liftd stopped
  StartFailed,                 ///< a part could not start, or the setup failed
  ConfigRefused,               ///< the configuration was refused at start
  ReloadRefused,               ///< a reload was refused
  ReloadNeedsRestart,          ///< a changed key waits for a restart
  WatchdogWithheld,            ///< no progress: WATCHDOG=1 withheld
  LinkLost,                    ///< the link_fault fault was raised
  LinkRestored,                ///< the link_fault fault was cleared
  SerialPortLost,              ///< a serial port was lost or could not be opened
  DriveFault,                  ///< the drive_fault fault was raised
  DriveErrorLog,               ///< the drive logged an error text
  DriveAdvanceWarning,         ///< the advance_warning fault was raised
  SafetyChainOpen,             ///< the safety_chain_open fault was raised
  SafetyChainOpenedMidTravel,  ///< a travel aborted because the safety chain opened
  TravelAborted,               ///< a travel aborted for any other cause
  PositionLost,                ///< the position_lost fault was raised
  InputsLost,                  ///< the inputs_lost fault was raised
  CardFault,                   ///< the SCH001 card reports a fault or went silent
  CanOwnIdInUse,               ///< another CAN node sends on liftd's identifier
  UssSlaveFault,               ///< a USS slave does not send or reports a fault
  RecordOff,                   ///< the lift's record cannot be kept (storage, file)
  kCount,
};

/// One catalogued event kind.
struct CatalogEntry {
  Catalogued key;         ///< what call sites pass
  std::string_view name;  ///< short name for documents, e.g. "link_lost"
  std::string_view id;    ///< MESSAGE_ID: 32 lower-case hex digits (sd-id128(3) format)
};

/// Every catalogued event kind, one entry per key, indexed by the key.
std::span<const CatalogEntry> catalog();

/// The MESSAGE_ID of a key; empty for kCount, which names no event.
std::string_view message_id(Catalogued key);

}  // namespace liftd::log
