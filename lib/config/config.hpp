// liftd configuration: the typed settings, loaded from JSON and validated against a Schema
// (config/schema.hpp: the shared sections here, each drive kind's section in its own folder,
// put together by lib/kinds). Exceptions are used only while loading; the result is plain data.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/defaults.hpp"
#include "drive/drive.hpp"

namespace liftd::config {

/// Log verbosity, lowest first.
enum class LogLevel : std::uint8_t { trace, debug, info, warn, error };
/// Which kind of drive the daemon talks to (one vocabulary with the API: lib/drive).
using DriveKind = drive::Kind;
/// How the serial port's kernel RS485 mode is used.
enum class Rs485Mode : std::uint8_t {
  automatic,  ///< "auto": use it where the port supports it, warn where not
  required,   ///< "required": refuse to start without it
  off,        ///< "off": never switch it on (an external transceiver handles direction)
};
/// Whether the drive's serial line gives our own frames back (drive.echo).
enum class EchoMode : std::uint8_t {
  automatic,  ///< "auto": find out at each port open, say so in the journal and `status`
  on,         ///< "on": the line echoes; read back exactly the bytes sent before the reply
  off,        ///< "off": the line does not echo
};
/// Where the car's absolute position comes from.
enum class PositionSource : std::uint8_t { sim, api, can };
/// With which door state relevelling is allowed.
enum class RelevelDoors : std::uint8_t { open, closed, both, never };
/// Where a DCP3 travel learns its deceleration point and its level.
enum class Dcp3Reference : std::uint8_t { position, shaft_signals };

/// `log.*`
struct LogConfig {
  LogLevel level = LogLevel::info;  ///< log.level
};

/// `drive.*`
struct DriveConfig {
  DriveKind kind = DriveKind::Dcp;         ///< drive.kind
  std::string device = "/dev/ttyS1";       ///< drive.device
  Rs485Mode rs485 = Rs485Mode::automatic;  ///< drive.rs485
  EchoMode echo = EchoMode::automatic;     ///< drive.echo
};

/// `rt.*`
struct RtConfig {
  int priority = 80;             ///< rt.priority (SCHED_FIFO)
  bool require_realtime = true;  ///< rt.require_realtime: refuse to run without SCHED_FIFO
  int cpu = -1;                  ///< rt.cpu, -1 = no pinning
  bool lock_memory = true;       ///< rt.lock_memory (mlockall)
  int flight_recorder_s = 30;    ///< rt.flight_recorder_s
  int trace_files_kept = 10;     ///< rt.trace_files_kept
  int send_window_us = 1375;     ///< rt.send_window_us (DCP 7.2: 15 - 13.625 ms at most)
};

/// `api.*`
struct ApiConfig {
  std::string socket = "/run/liftd/api.sock";   ///< api.socket
  std::string socket_group = "liftd";           ///< api.socket_group
  std::string read_group = "liftd";             ///< api.read_group
  std::string control_group = "liftd-control";  ///< api.control_group
  std::string inputs_group = "liftd-io";        ///< api.inputs_group
  int max_clients = 32;                         ///< api.max_clients
  int max_requests_per_s = 5000;                ///< api.max_requests_per_s, 0 = no limit
  int max_clients_per_uid = 8;                  ///< api.max_clients_per_uid (root exempt)
  int reserved_clients = 4;                     ///< api.reserved_clients, for control access
  int stalled_reader_timeout_s = 30;            ///< api.stalled_reader_timeout_s
  int idle_timeout_s = 0;                       ///< api.idle_timeout_s, 0 = none
  int state_rate_hz = 10;                       ///< api.state_rate_hz (position/speed events)
  std::string car_name;                         ///< api.car_name, `hello`'s car.name
};

/// `record.*`: the lift's record on the board's storage (lib/record).
struct RecordConfig {
  bool enabled = true;  ///< record.enabled
  /// record.path; empty: `$STATE_DIRECTORY/record.db` (the unit's StateDirectory), with
  /// --simulate the runtime directory's record.db, else /var/lib/liftd/record.db
  std::string path;
  int max_travels = 1000000;  ///< record.max_travels: the oldest go first beyond it
  int curves_kept = 100;      ///< record.curves_kept: the newest travels that keep their curve
};

/// `eta.*`: the profile the arrival times (`eta`) use until the car measured travels of its own.
struct EtaConfig {
  int speed_mm_s = 1000;         ///< eta.speed_mm_s: rated speed
  int acceleration_mm_s2 = 600;  ///< eta.acceleration_mm_s2: acceleration and deceleration
  int start_ms = 2000;           ///< eta.start_ms: a travel's time beyond its motion
  int stop_ms = 1000;            ///< eta.stop_ms: arrival at a queued stop to the next start
};

/// `inputs.*`
struct InputsConfig {
  int timeout_ms = defaults::kInputsTimeoutMs;  ///< inputs.timeout_ms
};

/// One entry of `floors`.
struct Floor {
  std::string name;       ///< shown to people, 1..16 characters, unique
  std::int32_t level_mm;  ///< mm above the lowest level, strictly increasing
  /// Field-wise equality.
  friend bool operator==(const Floor&, const Floor&) = default;
};

/// The default building: six floors 3 m apart, named "0".."5".
std::vector<Floor> default_floors();

/// `position.*`
struct PositionConfig {
  PositionSource source = PositionSource::api;  ///< position.source
  // position.source "can": the absolute encoder's frame on can.interface.
  int can_id = 0x190;           ///< position.can_id: 11-bit identifier
  int can_offset = 0;           ///< position.can_offset: first data byte of the value
  int can_length = 4;           ///< position.can_length: 2..4 bytes
  bool can_big_endian = false;  ///< position.can_byte_order "big" (else "little")
  bool can_signed = false;      ///< position.can_signed
  int can_um_per_count = 1000;  ///< position.can_um_per_count: scale
  int can_offset_mm = 0;        ///< position.can_offset_mm: position at count 0
  int can_timeout_ms = 100;     ///< position.can_timeout_ms: older values count as lost
};

/// `travel.*`
struct TravelConfig {
  int level_tolerance_mm = defaults::kLevelToleranceMm;         ///< travel.level_tolerance_mm
  int call_stop_ms = defaults::kCallStopMs;                     ///< travel.call_stop_ms
  int relevel_threshold_mm = defaults::kRelevelThresholdMm;     ///< travel.relevel_threshold_mm
  RelevelDoors relevel_with_doors = RelevelDoors::both;         ///< travel.relevel_with_doors
  bool relevel_electric_stop = defaults::kRelevelElectricStop;  ///< travel.relevel_electric_stop
  bool use_start_parameters = defaults::kUseStartParameters;    ///< travel.use_start_parameters
  int fast_start_timeout_ms = defaults::kFastStartTimeoutMs;    ///< travel.fast_start_timeout_ms
  int inspection_hold_ms = defaults::kInspectionHoldMs;         ///< travel.inspection_hold_ms
  int dcp3_stop_lead_mm = defaults::kDcp3StopLeadMm;            ///< travel.dcp3_stop_lead_mm
  int dcp3_speed_count = defaults::kDcp3SpeedCount;             ///< travel.dcp3_speed_count
  Dcp3Reference dcp3_reference = Dcp3Reference::position;       ///< travel.dcp3_reference
  /// travel.dcp3_decel_distance_mm: speed name ("V4", "V3", ...) -> deceleration distance.
  std::map<std::string, int> dcp3_decel_distance_mm = {{"V3", defaults::kDcp3DecelV3Mm},
                                                       {"V4", defaults::kDcp3DecelV4Mm}};
};

/// `can.*`
struct CanConfig {
  /// can.interface: a SocketCAN interface ("can0") or "unix:PATH" where a card simulator listens.
  std::string interface = "can0";
};

/// `sim.*`
struct SimConfig {
  int dcp = 4;  ///< sim.dcp: the simulated drive speaks DCP3 or DCP4
  /// sim.shaft_levels_mm: the simulated shaft's true level of each floor, lowest first; empty:
  /// the floor table's levels. Its level zones may differ from the floors in number (a shaft
  /// with a missing zone).
  std::vector<std::int64_t> shaft_levels_mm;
  /// sim.level_zone_mm: length of each simulated level zone, centred on its true level.
  int level_zone_mm = 100;
  /// sim.slow_mm_per_s: the simulated drive's slowest travel speed: the DCP drive's crawl V0
  /// (DCP 10.3), the hydraulic unit's slow (levelling) speed (card document 1.4); 50 mm/s, a
  /// usual one; a test may make the learning travel's crawl shorter. A USS drive's crawl is
  /// uss.speeds V0.
  int slow_mm_per_s = 50;
};

/// Each drive kind's own section of the file (`dcp.*`, `sch001.*`, ...): its struct lives in
/// the kind's folder (lib/<kind>/config/section.hpp) and names its kind (`kKind`), so this
/// folder knows none of them. Holds one of each kind set so far; a kind's section never set
/// reads as its defaults (the struct's member initialisers). Copies are deep, as of a struct.
class KindSections {
 public:
  KindSections() = default;
  KindSections(const KindSections& other) {
    for (std::size_t i = 0; i < slots_.size(); ++i) {
      const Slot& from = other.slots_[i];
      if (from.value) slots_[i] = Slot{from.copy(from.value.get()), from.copy};
    }
  }
  KindSections(KindSections&&) noexcept = default;
  KindSections& operator=(const KindSections& other) {
    if (this != &other) *this = KindSections(other);
    return *this;
  }
  KindSections& operator=(KindSections&&) noexcept = default;
  ~KindSections() = default;

  /// The section of `Section::kKind`: as set, or its defaults.
  template <class Section>
  const Section& get() const {
    const Slot& slot = slots_[index<Section>()];
    if (!slot.value) {
      static const Section kDefaults{};
      return kDefaults;
    }
    return *static_cast<const Section*>(slot.value.get());
  }
  /// The section of `Section::kKind` to change (its defaults until then).
  template <class Section>
  Section& get() {
    Slot& slot = slots_[index<Section>()];
    if (!slot.value) {
      slot.value = std::make_shared<Section>();
      slot.copy = [](const void* from) -> std::shared_ptr<void> {
        return std::make_shared<Section>(*static_cast<const Section*>(from));
      };
    }
    return *static_cast<Section*>(slot.value.get());
  }

 private:
  struct Slot {
    std::shared_ptr<void> value;                           ///< the Section, never shared by copies
    std::shared_ptr<void> (*copy)(const void*) = nullptr;  ///< a copy of the Section
  };
  template <class Section>
  static constexpr std::size_t index() {
    static_assert(static_cast<std::size_t>(Section::kKind) < drive::kKindNames.size(),
                  "a section names its drive kind: static constexpr drive::Kind kKind");
    return static_cast<std::size_t>(Section::kKind);
  }
  std::array<Slot, drive::kKindNames.size()> slots_{};
};

/// The whole configuration; every member mirrors a key of the JSON file. The member
/// initialisers are the defaults (the schema's keys read them from a default Config).
struct Config {
  LogConfig log;                                 ///< log.*
  DriveConfig drive;                             ///< drive.*
  RtConfig rt;                                   ///< rt.*
  ApiConfig api;                                 ///< api.*
  InputsConfig inputs;                           ///< inputs.*
  RecordConfig record;                           ///< record.*
  EtaConfig eta;                                 ///< eta.*
  std::vector<Floor> floors = default_floors();  ///< floors
  PositionConfig position;                       ///< position.*
  TravelConfig travel;                           ///< travel.*
  CanConfig can;                                 ///< can.*
  KindSections kinds;                            ///< each drive kind's own section
  SimConfig sim;                                 ///< sim.*
};

class Schema;

/// One thing wrong with a configuration, ready to print as "<where>: <message>".
struct Problem {
  std::string where;    ///< key path ("dcp.link_fault_frames"), or "file:line:col", or the path
  std::string message;  ///< what is wrong and what is allowed
};

/// Formats a problem as one line.
std::string to_string(const Problem& problem);

/// The outcome of loading: the config (defaults where keys are missing) and every problem
/// found. The config is only meaningful when `problems` is empty.
struct LoadResult {
  Config config;                  ///< the effective configuration
  std::vector<Problem> problems;  ///< every problem, in file order where known
  /// True when there is nothing wrong.
  bool ok() const { return problems.empty(); }
};

/// Parses and validates JSON text against `schema`; `origin` names it in messages (usually the
/// file path).
LoadResult parse(std::string_view text, std::string_view origin, const Schema& schema);

/// The largest configuration file load_file() reads, in bytes (1 MiB; a full 64-floor file is
/// a few KiB).
inline constexpr std::size_t kMaxFileBytes = 1024 * 1024;

/// Reads, parses and validates a file, then checks it against this host (check_host()): the one
/// validation both `--check-config` and the daemon's start use. Only a regular file of at most
/// kMaxFileBytes is read (symbolic links are followed); a FIFO, device or directory is one
/// problem and is never read, so this never blocks. An unreadable file is one problem naming the
/// path and the errno text.
LoadResult load_file(const std::filesystem::path& path, const Schema& schema);

/// Facts about the machine a configuration must fit.
struct HostFacts {
  /// CPUs this process may run on (online and in its affinity mask), ascending.
  std::vector<int> usable_cpus;
  /// The facts of the machine and process this runs in.
  static HostFacts current();
};

/// The problems a valid configuration has on this host: `rt.cpu` must be a usable CPU.
std::vector<Problem> check_host(const Config& config, const HostFacts& host);

/// Validates a JSON document that is already parsed (shared by parse() and tests): every key of
/// `schema` for type and range, the shared cross-checks, then the cross-check of the kind that
/// `drive.kind` names.
LoadResult from_json(const nlohmann::json& document, const Schema& schema);

/// The effective configuration as JSON, every key of `schema` present (the API's `config`
/// command).
nlohmann::json to_json(const Config& config, const Schema& schema);

/// A short human summary for `liftd --check-config`: the drive as its kind's rules describe it,
/// then the shared sections.
std::string summary(const Config& config, const Schema& schema);

/// The Markdown reference of every key (type, default, allowed values, description), generated
/// from `schema`; docs/config.md embeds it.
std::string reference_markdown(const Schema& schema);

/// Every key path of `schema`, in its order.
std::vector<std::string> key_paths(const Schema& schema);

/// The name of an enum value as written in the JSON file.
std::string_view to_string(LogLevel value);
/// The name of an enum value as written in the JSON file.
std::string_view to_string(Rs485Mode value);
/// The name of an enum value as written in the JSON file.
std::string_view to_string(EchoMode value);
/// The name of an enum value as written in the JSON file.
std::string_view to_string(PositionSource value);
/// The name of an enum value as written in the JSON file.
std::string_view to_string(RelevelDoors value);
/// The name of an enum value as written in the JSON file.
std::string_view to_string(Dcp3Reference value);

/// Parses a log level name ("trace".."error").
std::optional<LogLevel> parse_log_level(std::string_view name);

/// The DCP3 speeds an installation with `speed_count` travelling speeds uses, fastest first
/// (DCP 3.5.3.7 table): 1 -> V4; 2 -> V4 V3; ... 7 -> V4 V3 V2 V1 V7 V6 V5.
std::vector<std::string> dcp3_speeds(int speed_count);

/// Levenshtein distance, used for "did you mean" suggestions.
std::size_t edit_distance(std::string_view a, std::string_view b);

}  // namespace liftd::config
