// The API commands only the DCP lift offers: the drive's remote keypad and display, the power
// supply mode, the car load, fast start and fast stop; what its backend serves of them. The
// registry adds them (dcp::RegistryEntry::add_commands, lib/dcp/registry_entry.hpp); the
// dispatcher knows them on every lift and answers them `not_offered` on a drive kind without
// the capability (CommandSpec::needs).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "api/backend.hpp"
#include "api/dispatcher.hpp"
#include "api/result.hpp"
#include "drive/drive.hpp"

namespace liftd::daemon {

/// Contents of the drive's remote display (DCP 5.7: up to 4 lines of 20 characters).
struct DisplaySnapshot {
  std::vector<std::string> lines;    ///< UTF-8, one string per line
  std::optional<int> cursor_line;    ///< 0-based; nullopt when no cursor is shown
  std::optional<int> cursor_column;  ///< 0-based
};

/// Power supply state for I6 (DCP 5.12.6).
struct PowerSetting {
  bool emergency = false;  ///< false: mains 'N', true: emergency 'U'
  int saving = 0;          ///< energy saving mode '0', '1' or '2'
};

/// JSON of the display: {"lines": [...], "cursor": {"line":..,"column":..} | null}.
nlohmann::json to_json(const DisplaySnapshot& display);
/// JSON of a power setting: {"supply":"mains"|"emergency","saving":0..2}.
nlohmann::json to_json(const PowerSetting& power);

/// What the DCP lift's backend serves besides api::Backend: the DCP commands. Called on the
/// io_context's thread; every Responder must be called exactly once on that thread.
class DcpCommandBackend {
 public:
  virtual ~DcpCommandBackend() = default;
  /// Current contents of the drive's remote display.
  virtual DisplaySnapshot display() = 0;
  /// Sends a keypad button (DCP 5.8; button 1..5 is bit 0x04 << (button - 1)).
  virtual void key(int button, api::Responder done) = 0;
  /// Sets the power supply mode (I6, DCP 5.12.6); the result is the mode the drive reports.
  virtual void power(PowerSetting setting, api::Responder done) = 0;
  /// Sends the car load for the next travel (I8, DCP 5.12.8), percent of rated load.
  virtual void load(int percent, api::Responder done) = 0;
  /// DCP 13 fast stop.
  virtual void fast_stop(api::Responder done) = 0;
  /// DCP 12 fast start: "arm" (with args.floor), "go" or "abort".
  virtual void fast_start(const std::string& action, const api::TravelArgs& args,
                          api::Responder done) = 0;
};

}  // namespace liftd::daemon
