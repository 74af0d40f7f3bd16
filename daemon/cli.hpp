// The liftd command line: parsed into plain data, no side effects (tested in tests/daemon).
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>

#include "log/log.hpp"

namespace liftd::daemon {

/// Where the daemon reads its configuration unless told otherwise.
inline constexpr std::string_view kDefaultConfigPath = "/etc/liftd/liftd.json";

/// What the command line asks for.
struct CommandLine {
  /// The action to take.
  enum class Mode : std::uint8_t {
    run,              ///< run the daemon
    check_config,     ///< --check-config FILE: validate, print a summary or every problem
    print_config,     ///< --print-config: print the effective configuration as JSON
    print_reference,  ///< --print-config-reference: Markdown table of every key
    version,          ///< --version
    help,             ///< --help
  };
  Mode mode = Mode::run;                   ///< the action
  std::optional<std::string> config_path;  ///< --config / --check-config FILE
  bool simulate = false;                   ///< --simulate
  std::optional<log::Level> log_level;     ///< --log-level LEVEL
};

/// The outcome of parsing: a command line, or an error message for the user.
struct ParsedCommandLine {
  std::optional<CommandLine> command_line;  ///< set when the arguments made sense
  std::string error;                        ///< what was wrong otherwise
};

/// Parses the arguments after the program name. Accepts "--opt value" and "--opt=value".
ParsedCommandLine parse_command_line(std::span<const std::string_view> args);

/// The --help text.
std::string usage();

}  // namespace liftd::daemon
