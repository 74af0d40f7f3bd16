// The journal catalog: one fixed MESSAGE_ID per kind of event a technician acts on. The
// explanations live in systemd/liftd.catalog (installed to /usr/lib/systemd/catalog/), so
// `journalctl -x -u liftd` prints what happened, the likely causes and what to check under the
// entry. A test checks that this table and the catalog file name exactly the same ids.
#pragma once

#include <optional>
#include <span>
#include <string_view>

#include "log/log.hpp"

namespace liftd::log {

/// One catalogued event kind.
struct CatalogEntry {
  std::string_view name;   ///< short name for documents, e.g. "link_lost"
  std::string_view id;     ///< MESSAGE_ID: 32 lower-case hex digits (sd-id128(3) format)
  std::string_view event;  ///< the LIFTD_EVENT it is attached to
  std::string_view key;    ///< an extra field that must match as well ("" = any record)
  std::string_view value;  ///< the value `key` must have
};

/// Every catalogued event kind; the first entry whose event and field match a record wins.
std::span<const CatalogEntry> catalog();

/// The MESSAGE_ID of a record with this event name and these extra fields, if catalogued.
std::optional<std::string_view> message_id_for(std::string_view event, const Fields* fields);

}  // namespace liftd::log
