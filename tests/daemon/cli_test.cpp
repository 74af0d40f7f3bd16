// The command-line parser, table-driven.
#include "daemon/cli.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace liftd::daemon {
namespace {

ParsedCommandLine parse(std::vector<std::string_view> args) {
  return parse_command_line(args);
}

TEST(CommandLine, DefaultsToRunningWithTheDefaultConfig) {
  const auto r = parse({});
  ASSERT_TRUE(r.command_line.has_value());
  EXPECT_EQ(r.command_line->mode, CommandLine::Mode::run);
  EXPECT_FALSE(r.command_line->config_path.has_value());
  EXPECT_FALSE(r.command_line->simulate);
  EXPECT_FALSE(r.command_line->log_level.has_value());
  EXPECT_EQ(kDefaultConfigPath, "/etc/liftd/liftd.json");
}

TEST(CommandLine, AcceptsEveryOptionInBothSpellings) {
  // Legend: arguments -> mode, config path, simulate, log level.
  struct Case {
    std::vector<std::string_view> args;
    CommandLine::Mode mode;
    std::optional<std::string> config;
    bool simulate;
    std::optional<log::Level> level;
  };
  using M = CommandLine::Mode;
  const std::vector<Case> cases = {
      {{"--config", "/a.json"}, M::run, "/a.json", false, std::nullopt},
      {{"--config=/a.json"}, M::run, "/a.json", false, std::nullopt},
      {{"--simulate"}, M::run, std::nullopt, true, std::nullopt},
      {{"--simulate", "--config", "x.json", "--log-level", "trace"},
       M::run,
       "x.json",
       true,
       log::Level::trace},
      {{"--log-level=warn"}, M::run, std::nullopt, false, log::Level::warn},
      {{"--check-config", "/b.json"}, M::check_config, "/b.json", false, std::nullopt},
      {{"--check-config=/b.json"}, M::check_config, "/b.json", false, std::nullopt},
      {{"--print-config", "--simulate"}, M::print_config, std::nullopt, true, std::nullopt},
      {{"--print-config-reference"}, M::print_reference, std::nullopt, false, std::nullopt},
      {{"--version"}, M::version, std::nullopt, false, std::nullopt},
      {{"-V"}, M::version, std::nullopt, false, std::nullopt},
      {{"--help"}, M::help, std::nullopt, false, std::nullopt},
      {{"-h"}, M::help, std::nullopt, false, std::nullopt},
  };
  for (const auto& c : cases) {
    const auto r = parse(c.args);
    ASSERT_TRUE(r.command_line.has_value()) << c.args[0] << ": " << r.error;
    EXPECT_EQ(r.command_line->mode, c.mode) << c.args[0];
    EXPECT_EQ(r.command_line->config_path, c.config) << c.args[0];
    EXPECT_EQ(r.command_line->simulate, c.simulate) << c.args[0];
    EXPECT_EQ(r.command_line->log_level, c.level) << c.args[0];
  }
}

TEST(CommandLine, RefusesWhatItCannotUnderstand) {
  // Legend: arguments -> part of the error message.
  const std::vector<std::pair<std::vector<std::string_view>, std::string>> cases = {
      {{"--frobnicate"}, "unknown argument \"--frobnicate\""},
      {{"extra"}, "unknown argument \"extra\""},
      {{"--config"}, "--config needs a FILE"},
      {{"--config="}, "--config needs a FILE"},
      {{"--check-config"}, "--check-config needs a FILE"},
      {{"--log-level"}, "--log-level needs a LEVEL"},
      {{"--log-level", "verbose"}, "\"verbose\" is not a level"},
      {{"--simulate=yes"}, "unknown argument \"--simulate=yes\""},
      {{"--version", "--help"}, "cannot be combined"},
      {{"--config", "a.json", "--check-config", "b.json"}, "only once"},
  };
  for (const auto& [args, message] : cases) {
    const auto r = parse(args);
    EXPECT_FALSE(r.command_line.has_value()) << args[0];
    EXPECT_NE(r.error.find(message), std::string::npos) << args[0] << ": " << r.error;
  }
}

TEST(CommandLine, UsageNamesEveryOption) {
  const std::string text = usage();
  for (const char* option :
       {"--config FILE", "--check-config FILE", "--simulate", "--log-level LEVEL", "--print-config",
        "--print-config-reference", "--version", "--help"}) {
    EXPECT_NE(text.find(option), std::string::npos) << option;
  }
}

}  // namespace
}  // namespace liftd::daemon
