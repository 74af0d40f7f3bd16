// The MESSAGE_ID table. Ids were made once with `systemd-id128 new` and never change: a
// technician's saved `journalctl MESSAGE_ID=...` query and the catalog file depend on them.
#include "log/catalog.hpp"

#include <array>

namespace liftd::log {
namespace {

// Order matters: a specific entry (an event with a field value) comes before the same event's
// catch-all entry.
constexpr std::array kCatalog = {
    CatalogEntry{"started", "0f2a19dbd8a64ea99e54148dc512defd", "ready", "", ""},
    CatalogEntry{"stopped", "52edbf52818f43d4bd48bfa2a7c4e429", "stopped", "", ""},
    CatalogEntry{"start_failed", "2c13340a9417459f846a681157696589", "start_failed", "", ""},
    CatalogEntry{"start_failed", "2c13340a9417459f846a681157696589", "setup_failed", "", ""},
    CatalogEntry{"config_refused", "4ab90acd59804c488255bbfdafff0567", "config_invalid", "", ""},
    CatalogEntry{"reload_refused", "fe421f6e61e74b048f764a419cf18ed7", "reload_refused", "", ""},
    CatalogEntry{"reload_needs_restart", "758f5b15d4794881bdd6f4f14cb21111",
                 "reload_restart_needed", "", ""},
    CatalogEntry{"watchdog_withheld", "53798ea0112d4e99bf4e2245cbb7117d", "watchdog_withheld", "",
                 ""},
    CatalogEntry{"link_lost", "91c498ffaa7944c9a9ac4f8ca304a670", "fault_raised", "code",
                 "link_fault"},
    CatalogEntry{"link_restored", "847992ef8a0147b888c1e99373159da8", "fault_cleared", "code",
                 "link_fault"},
    CatalogEntry{"serial_port_lost", "7a709f3db0e847e587c4a3f5373882ea", "port_lost", "", ""},
    CatalogEntry{"serial_port_lost", "7a709f3db0e847e587c4a3f5373882ea", "port_open_failed", "",
                 ""},
    CatalogEntry{"drive_fault", "3a5f987995d8489ab4d2924e22af2290", "fault_raised", "code",
                 "drive_fault"},
    CatalogEntry{"drive_error_log", "310ba254364441ef9e4f291611ca8724", "drive_error", "", ""},
    CatalogEntry{"drive_advance_warning", "b8923085dc4d4978b87d0e769e5807f6", "fault_raised",
                 "code", "advance_warning"},
    CatalogEntry{"safety_chain_open", "a24d5247030f433d990dd88d17eddc66", "fault_raised", "code",
                 "safety_chain_open"},
    CatalogEntry{"safety_chain_opened_mid_travel", "ce1139c89ae344019ff1b085dbe3478a",
                 "travel_aborted", "cause", "safety_chain_open"},
    CatalogEntry{"travel_aborted", "aead774b70ba409fbc70c9f8ee6890af", "travel_aborted", "", ""},
    CatalogEntry{"position_lost", "c76df52c044d40f6a05d28aabccedd45", "fault_raised", "code",
                 "position_lost"},
    CatalogEntry{"inputs_lost", "f9209d2c1374471fa1cdca417d350e8c", "fault_raised", "code",
                 "inputs_lost"},
    // The SCH001 hydraulic card and the USS drive: their drivers log these event names.
    CatalogEntry{"card_fault", "747a03af540d46ba85f3190021b6809f", "card_fault", "", ""},
    CatalogEntry{"can_own_id_in_use", "2f12340309554c1dbc6ad2ed1abc8d9c", "own_id_in_use", "", ""},
    CatalogEntry{"uss_slave_fault", "dce538ec71c248bebd75a1de4dcdb397", "uss_slave_fault", "", ""},
};

}  // namespace

std::span<const CatalogEntry> catalog() {
  return kCatalog;
}

std::optional<std::string_view> message_id_for(std::string_view event, const Fields* fields) {
  if (event.empty()) return std::nullopt;
  for (const CatalogEntry& entry : kCatalog) {
    if (entry.event != event) continue;
    if (entry.key.empty()) return entry.id;
    if (fields == nullptr) continue;
    for (const Field& field : *fields) {
      if (field.key == entry.key && field.value == entry.value) return entry.id;
    }
  }
  return std::nullopt;
}

}  // namespace liftd::log
