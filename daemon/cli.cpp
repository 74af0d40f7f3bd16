// Command-line parsing for liftd.
#include "daemon/cli.hpp"

#include <vector>

namespace liftd::daemon {

ParsedCommandLine parse_command_line(std::span<const std::string_view> args) {
  CommandLine cl;
  bool mode_set = false;
  const auto set_mode = [&](CommandLine::Mode mode, std::string_view option) -> std::string {
    if (mode_set && cl.mode != mode) {
      return std::string(option) + " cannot be combined with the other action given";
    }
    cl.mode = mode;
    mode_set = true;
    return {};
  };
  for (std::size_t i = 0; i < args.size(); ++i) {
    std::string_view arg = args[i];
    std::optional<std::string_view> inline_value;
    if (arg.starts_with("--")) {
      if (const auto eq = arg.find('='); eq != std::string_view::npos) {
        inline_value = arg.substr(eq + 1);
        arg = arg.substr(0, eq);
      }
    }
    const auto takes_value = [&]() -> std::optional<std::string_view> {
      if (inline_value) return inline_value;
      if (i + 1 < args.size()) return args[++i];
      return std::nullopt;
    };
    const auto no_value = [&]() { return !inline_value.has_value(); };
    std::string error;
    if (arg == "--config" || arg == "--check-config") {
      const auto value = takes_value();
      if (!value || value->empty()) return {std::nullopt, std::string(arg) + " needs a FILE"};
      if (cl.config_path && *cl.config_path != *value) {
        return {std::nullopt, "give the configuration file only once"};
      }
      cl.config_path = std::string(*value);
      if (arg == "--check-config") error = set_mode(CommandLine::Mode::check_config, arg);
    } else if (arg == "--log-level") {
      const auto value = takes_value();
      if (!value)
        return {std::nullopt, "--log-level needs a LEVEL (trace, debug, info, warn, error)"};
      cl.log_level = log::parse_level(*value);
      if (!cl.log_level) {
        return {std::nullopt, "--log-level: \"" + std::string(*value) +
                                  "\" is not a level: use trace, debug, info, warn or error"};
      }
    } else if (arg == "--simulate" && no_value()) {
      cl.simulate = true;
    } else if (arg == "--print-config" && no_value()) {
      error = set_mode(CommandLine::Mode::print_config, arg);
    } else if (arg == "--print-config-reference" && no_value()) {
      error = set_mode(CommandLine::Mode::print_reference, arg);
    } else if ((arg == "--version" || arg == "-V") && no_value()) {
      error = set_mode(CommandLine::Mode::version, arg);
    } else if ((arg == "--help" || arg == "-h") && no_value()) {
      error = set_mode(CommandLine::Mode::help, arg);
    } else {
      return {std::nullopt, "unknown argument \"" + std::string(args[i]) + "\""};
    }
    if (!error.empty()) return {std::nullopt, error};
  }
  return {cl, {}};
}

std::string usage() {
  return "Usage: liftd [OPTIONS]\n"
         "Lift controller master daemon: DCP/USS drive link, travel sequencing, JSON API.\n"
         "\n"
         "  --config FILE             configuration file (default " +
         std::string(kDefaultConfigPath) +
         ")\n"
         "  --check-config FILE       validate FILE, print a summary (exit 0) or every\n"
         "                            problem (exit 2), and exit\n"
         "  --simulate                run against the built-in simulated lift; without\n"
         "                            --config the defaults are used\n"
         "  --log-level LEVEL         trace, debug, info, warn or error (overrides log.level)\n"
         "  --print-config            print the effective configuration as JSON and exit\n"
         "  --print-config-reference  print the Markdown reference of every key and exit\n"
         "  --version                 print the version and exit\n"
         "  --help                    print this help and exit\n"
         "\n"
         "Exit status: 0 clean stop (SIGTERM/SIGINT), 1 runtime failure, 2 bad command line or\n"
         "configuration.\n";
}

}  // namespace liftd::daemon
