// The MESSAGE_ID table. Ids were made once with `systemd-id128 new` and never change: a
// technician's saved `journalctl MESSAGE_ID=...` query and the catalog file depend on them.
#include "log/catalog.hpp"

#include <array>
#include <cstddef>

namespace liftd::log {
namespace {

// In the order of the enum: entry i is the one of key i (checked at compile time below).
constexpr std::array kCatalog = {
    CatalogEntry{Catalogued::Started, "started", "0f2a19dbd8a64ea99e54148dc512defd"},
    CatalogEntry{Catalogued::Stopped, "stopped", "52edbf52818f43d4bd48bfa2a7c4e429"},
    CatalogEntry{Catalogued::StartFailed, "start_failed", "2c13340a9417459f846a681157696589"},
    CatalogEntry{Catalogued::ConfigRefused, "config_refused", "4ab90acd59804c488255bbfdafff0567"},
    CatalogEntry{Catalogued::ReloadRefused, "reload_refused", "fe421f6e61e74b048f764a419cf18ed7"},
    CatalogEntry{Catalogued::ReloadNeedsRestart, "reload_needs_restart",
                 "758f5b15d4794881bdd6f4f14cb21111"},
    CatalogEntry{Catalogued::WatchdogWithheld, "watchdog_withheld",
                 "53798ea0112d4e99bf4e2245cbb7117d"},
    CatalogEntry{Catalogued::LinkLost, "link_lost", "91c498ffaa7944c9a9ac4f8ca304a670"},
    CatalogEntry{Catalogued::LinkRestored, "link_restored", "847992ef8a0147b888c1e99373159da8"},
    CatalogEntry{Catalogued::SerialPortLost, "serial_port_lost",
                 "7a709f3db0e847e587c4a3f5373882ea"},
    CatalogEntry{Catalogued::DriveFault, "drive_fault", "3a5f987995d8489ab4d2924e22af2290"},
    CatalogEntry{Catalogued::DriveErrorLog, "drive_error_log", "310ba254364441ef9e4f291611ca8724"},
    CatalogEntry{Catalogued::DriveAdvanceWarning, "drive_advance_warning",
                 "b8923085dc4d4978b87d0e769e5807f6"},
    CatalogEntry{Catalogued::SafetyChainOpen, "safety_chain_open",
                 "a24d5247030f433d990dd88d17eddc66"},
    CatalogEntry{Catalogued::SafetyChainOpenedMidTravel, "safety_chain_opened_mid_travel",
                 "ce1139c89ae344019ff1b085dbe3478a"},
    CatalogEntry{Catalogued::TravelAborted, "travel_aborted", "aead774b70ba409fbc70c9f8ee6890af"},
    CatalogEntry{Catalogued::PositionLost, "position_lost", "c76df52c044d40f6a05d28aabccedd45"},
    CatalogEntry{Catalogued::InputsLost, "inputs_lost", "f9209d2c1374471fa1cdca417d350e8c"},
    CatalogEntry{Catalogued::CardFault, "card_fault", "747a03af540d46ba85f3190021b6809f"},
    CatalogEntry{Catalogued::CanOwnIdInUse, "can_own_id_in_use",
                 "2f12340309554c1dbc6ad2ed1abc8d9c"},
    CatalogEntry{Catalogued::UssSlaveFault, "uss_slave_fault", "dce538ec71c248bebd75a1de4dcdb397"},
    CatalogEntry{Catalogued::RecordOff, "record_off", "ba707342f0964343abf3310a4b757142"},
};

constexpr bool indexed_by_key() {
  if (kCatalog.size() != static_cast<std::size_t>(Catalogued::kCount)) return false;
  for (std::size_t i = 0; i < kCatalog.size(); ++i) {
    if (static_cast<std::size_t>(kCatalog[i].key) != i) return false;
  }
  return true;
}
static_assert(indexed_by_key(), "one entry per Catalogued key, in the order of the enum");

}  // namespace

std::span<const CatalogEntry> catalog() {
  return kCatalog;
}

std::string_view message_id(Catalogued key) {
  const auto index = static_cast<std::size_t>(key);
  return index < kCatalog.size() ? kCatalog[index].id : std::string_view{};
}

}  // namespace liftd::log
