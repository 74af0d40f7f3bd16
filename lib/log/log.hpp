// liftd logging: spdlog underneath, per-component loggers, named events with structured fields.
// Under systemd records go to journald through libsystemd (journal.hpp); otherwise readable
// lines go to stderr. Never call any of this from inside the real-time cycle: it formats, allocates
// and takes a lock.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <source_location>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <spdlog/fmt/fmt.h>

#include "log/catalog.hpp"

namespace spdlog {
class logger;
}

namespace liftd::log {

/// Severity, least severe first (the same names as the config's log.level).
enum class Level : std::uint8_t { trace, debug, info, warn, error };

/// The name of a level ("trace".."error").
std::string_view to_string(Level level);
/// Parses a level name; nullopt for anything else.
std::optional<Level> parse_level(std::string_view name);

/// One extra structured field, e.g. {"cause", "10 lost frames"}. In the journal the key becomes
/// LIFTD_<KEY> (upper case, characters other than A-Z 0-9 _ replaced by _).
struct Field {
  std::string key;    ///< lower-case name, e.g. "cause"
  std::string value;  ///< any text (newlines allowed)
};
/// Extra fields of one event.
using Fields = std::vector<Field>;

/// Where records go.
enum class Backend : std::uint8_t {
  automatic,  ///< journal when running under systemd (JOURNAL_STREAM or INVOCATION_ID), else text
  journal,    ///< journald through sd_journal_sendv(3); "<N>"-prefixed stderr lines if it fails
  text,       ///< readable lines on stderr
};

/// How to set up logging.
struct Options {
  Level level = Level::info;             ///< least severe record written
  Backend backend = Backend::automatic;  ///< where records go
  std::string identifier = "liftd";      ///< SYSLOG_IDENTIFIER
};

/// True when the process runs under systemd (JOURNAL_STREAM or INVOCATION_ID is set).
bool under_systemd();

/// The backend `automatic` resolves to in this environment.
Backend resolve(Backend backend);

/// Sets up (or replaces) the sinks. Call it before other threads log (replacing the sinks
/// is not synchronised with writers); calling it again on the main thread at startup is fine.
void init(const Options& options);
/// Changes the level at run time.
void set_level(Level level);
/// The current level.
Level level();
/// Whether a record of this level would be written.
bool enabled(Level level);
/// Writes everything buffered (spdlog sinks are synchronous; this flushes stderr).
void flush();

/// Writes one record with an event name and extra fields, e.g.
/// `event(Level::warn, "dcp", "link_fault", {{"cause", "10 lost frames"}}, "link lost")`.
/// A record a technician acts on passes its catalog key, which alone gives it its journal
/// MESSAGE_ID (catalog.hpp), e.g. `..., "fault: link lost", Catalogued::LinkLost)`.
void event(Level level, std::string_view component, std::string_view event_name,
           const Fields& fields, std::string_view text,
           std::optional<Catalogued> catalogued = std::nullopt,
           std::source_location where = std::source_location::current());

/// Writes one plain record for a component.
void write(Level level, std::string_view component, std::string_view text,
           std::source_location where = std::source_location::current());

/// A logger bound to one component name ("dcp", "api", "daemon", ...).
class Logger {
 public:
  /// A logger whose records carry LIFTD_COMPONENT=`component`.
  explicit Logger(std::string component) : component_(std::move(component)) {}

  /// The component name.
  const std::string& component() const { return component_; }

  /// Formats and writes a record at `level` (fmt syntax).
  template <class... Args>
  void log(Level level, fmt::format_string<Args...> format, Args&&... args) const {
    if (!enabled(level)) return;
    write(level, component_, fmt::format(format, std::forward<Args>(args)...),
          std::source_location{});
  }
  /// trace-level record.
  template <class... Args>
  void trace(fmt::format_string<Args...> format, Args&&... args) const {
    log(Level::trace, format, std::forward<Args>(args)...);
  }
  /// debug-level record.
  template <class... Args>
  void debug(fmt::format_string<Args...> format, Args&&... args) const {
    log(Level::debug, format, std::forward<Args>(args)...);
  }
  /// info-level record.
  template <class... Args>
  void info(fmt::format_string<Args...> format, Args&&... args) const {
    log(Level::info, format, std::forward<Args>(args)...);
  }
  /// warn-level record.
  template <class... Args>
  void warn(fmt::format_string<Args...> format, Args&&... args) const {
    log(Level::warn, format, std::forward<Args>(args)...);
  }
  /// error-level record.
  template <class... Args>
  void error(fmt::format_string<Args...> format, Args&&... args) const {
    log(Level::error, format, std::forward<Args>(args)...);
  }
  /// A record with an event name, fields and maybe a catalog key (see log::event).
  void event(Level level, std::string_view event_name, const Fields& fields, std::string_view text,
             std::optional<Catalogued> catalogued = std::nullopt,
             std::source_location where = std::source_location::current()) const {
    log::event(level, component_, event_name, fields, text, catalogued, where);
  }

 private:
  std::string component_;
};

}  // namespace liftd::log
