// The drive kinds put together: the one configuration schema of the daemon, its shared sections
// (lib/config) and each kind's own section and checks (lib/<kind>/config). The only folder of
// lib/ that knows every kind; lib/config includes none.
#pragma once

#include <filesystem>
#include <string_view>

#include "config/config.hpp"
#include "config/schema.hpp"

namespace liftd::kinds {

/// Every key of the configuration file, in the reference's order, with every kind's rules.
/// Built once; safe to call from any thread.
const config::Schema& config_schema();

/// config::parse() against config_schema().
config::LoadResult parse_config(std::string_view text, std::string_view origin);

/// config::load_file() against config_schema(): the validation of `--check-config` and of the
/// daemon's start and reload.
config::LoadResult load_config(const std::filesystem::path& path);

}  // namespace liftd::kinds
